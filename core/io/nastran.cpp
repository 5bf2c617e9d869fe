// Nastran bulk data. Writes GRID* in large field format (16-character coordinates, so
// doubles keep 14-15 significant digits in the usual ranges), CTRIA3 in small field format,
// one PSHELL per part with PID = part index + 1 and the part's name in a "$ PID n: name"
// comment just above it (Nastran itself has no place for names).
// Reads GRID (basic coordinate system), CTRIA3/CTRIA6 and CQUAD4/CQUAD8 (corner grids) in
// small, large and free field format; the PIDs are the parts, named by "$ PID n: name",
// ANSA's "$ANSA_NAME_COMMENT;n;PSHELL;name" or HyperMesh's "$HMNAME PROP n"name"" comments.
// Other cards are skipped.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unordered_map>

#include "io/readers.h"

namespace vdbwrap::io::detail {
namespace {

constexpr size_t kLargeField = 16;
constexpr size_t kSmallField = 8;

// What a Nastran reader takes `text` for: "1.5-3" is 1.5E-3 (an exponent without its E).
double nastran_value(const std::string& text) {
  std::string s = text;
  for (size_t i = 1; i < s.size(); ++i)
    if ((s[i] == '+' || s[i] == '-') && s[i - 1] != 'E') {
      s.insert(i, 1, 'E');
      break;
    }
  return std::strtod(s.c_str(), nullptr);
}

// Nastran reals need a decimal point ("3" is an integer, a fatal error in a real field).
std::string with_point(std::string s) {
  if (s.find('.') != std::string::npos) return s;
  size_t e = s.find_first_of("eE");
  s.insert(e == std::string::npos ? s.size() : e, 1, '.');
  return s;
}

// "0.25" -> ".25", "-0.25" -> "-.25": one more digit fits.
std::string drop_leading_zero(std::string s) {
  size_t digit = (s[0] == '-') ? 1 : 0;
  if (s.size() > digit + 2 && s[digit] == '0' && s[digit + 1] == '.') s.erase(digit, 1);
  return s;
}

// Mantissa and exponent as printf's %.*e gives them, the mantissa's trailing zeros dropped.
std::string scientific(double v, int digits, const char* separator) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*e", digits, v);
  std::string s = buf;
  size_t e = s.find('e');
  std::string mantissa = with_point(s.substr(0, e));
  while (mantissa.back() == '0') mantissa.pop_back();
  int exponent = std::atoi(s.c_str() + e + 1);
  std::string exp = std::to_string(exponent);
  if (exponent >= 0 && separator[0] == '\0') exp = "+" + exp;  // "1.5+3": the sign is the marker
  return mantissa + separator + exp;
}

// The most digits of `v` that fit in `width` characters for one way of writing it.
template <class Writer>
std::string widest_fit(Writer format, size_t width) {
  for (int digits = 17; digits >= 0; --digits) {
    std::string s = format(digits);
    if (s.size() <= width) return s;
  }
  return {};
}

// A real in at most `width` characters that reads back as close to `v` as that width allows:
// the shortest exact text when it fits, else the best of fixed, "E" and E-less exponent forms.
std::string nastran_real(double v, size_t width) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string exact = with_point(std::string(buf, size_t(r.ptr - buf)));
  for (char& c : exact)
    if (c == 'e') c = 'E';
  exact = drop_leading_zero(exact);
  if (exact.size() <= width) return exact;

  const std::string candidates[] = {
      widest_fit(
          [&](int digits) {
            char fixed[400];
            std::snprintf(fixed, sizeof fixed, "%.*f", digits, v);
            std::string s = drop_leading_zero(with_point(fixed));
            while (s.back() == '0') s.pop_back();
            return s;
          },
          width),
      widest_fit([&](int digits) { return scientific(v, digits, "E"); }, width),
      widest_fit([&](int digits) { return scientific(v, digits, ""); }, width),
  };
  std::string best;
  double best_error = 0;
  for (const std::string& c : candidates) {
    if (c.empty()) continue;
    double error = std::fabs(nastran_value(c) - v);
    if (best.empty() || error < best_error) best = c, best_error = error;
  }
  return best;
}

std::string right(const std::string& s, size_t width) {
  return s.size() >= width ? s : std::string(width - s.size(), ' ') + s;
}

std::string left(const std::string& s, size_t width) {
  return s.size() >= width ? s : s + std::string(width - s.size(), ' ');
}

// ---- reader -------------------------------------------------------------------------------

std::string upper(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c >= 'a' && c <= 'z') c = char(c - 'a' + 'A');
  return out;
}

std::string trimmed(std::string_view s) { return std::string(trim(s)); }

class NastranReader {
 public:
  NastranReader(std::string_view text, const std::string& name) : lines_(text), name_(name) {}

  Mesh read() {
    std::string_view line;
    while (lines_.next(line)) {
      if (!line.empty() && line[0] == '$') {
        name_comment(line);
        continue;
      }
      line = line.substr(0, line.find('$'));  // a comment may end any line
      if (trim(line).empty()) continue;
      if (line[0] == '+' || line[0] == '*' || line[0] == ',' || trim(line.substr(0, 8)).empty()) {
        if (card_.name.empty()) continue;  // continuation of a card we skip
        append_fields(line, true);
        continue;
      }
      finish_card();
      const std::string keyword = upper(trim(line));
      if (keyword.rfind("BEGIN", 0) == 0 && keyword.find("BULK") != std::string::npos) continue;
      if (keyword == "ENDDATA") break;
      card_line_ = lines_.line_number();
      large_ = false;
      card_.name.clear();
      card_.fields.clear();
      append_fields(line, false);
    }
    finish_card();
    return build();
  }

 private:
  struct Card {
    std::string name;
    std::vector<std::string> fields;
  };
  struct Element {
    int64_t id, pid;
    std::vector<int64_t> grids;
    size_t line;
  };

  [[noreturn]] void error(size_t line, const std::string& what) { fail_line(name_, line, what); }

  // Fixed fields: 8 columns (small) or 16 (large, a '*' after the name); free fields: commas.
  void append_fields(std::string_view line, bool continuation) {
    if (line.find(',') != std::string_view::npos) {
      std::vector<std::string> tokens;
      size_t start = 0;
      for (size_t comma; (comma = line.find(',', start)) != std::string_view::npos; start = comma + 1)
        tokens.push_back(trimmed(line.substr(start, comma - start)));
      tokens.push_back(trimmed(line.substr(start)));
      if (!continuation) card_.name = upper(tokens[0]);
      // Field 1 names the card or marks the continuation; field 10 is a continuation mark.
      for (size_t i = 1; i < tokens.size() && i < 9; ++i) card_.fields.push_back(tokens[i]);
    } else {
      if (!continuation) {
        card_.name = upper(trim(line.substr(0, 8)));
        large_ = !card_.name.empty() && card_.name.back() == '*';
      } else if (line[0] == '*') {
        large_ = true;
      }
      const size_t width = large_ ? 16 : 8, count = large_ ? 4 : 8;
      for (size_t k = 0; k < count; ++k)
        card_.fields.push_back(8 + k * width < line.size() ? trimmed(line.substr(8 + k * width, width)) : "");
    }
    if (!card_.name.empty() && card_.name.back() == '*') card_.name.pop_back();
  }

  double real(const std::string& field, const char* what) {
    std::string s = upper(field);
    for (char& c : s)
      if (c == 'D') c = 'E';  // Fortran double exponent
    if (s.find('E') == std::string::npos)
      for (size_t i = 1; i < s.size(); ++i)
        if ((s[i] == '+' || s[i] == '-')) {
          s.insert(i, 1, 'E');  // "1.5-3" is 1.5E-3
          break;
        }
    double v = 0;
    if (s.empty()) return 0;  // blank real fields are 0
    if (!parse_double(s, v)) error(card_line_, std::string("malformed ") + what + " " + quoted(field));
    return v;
  }

  int64_t integer(const std::string& field, const char* what, int64_t blank) {
    if (field.empty()) return blank;
    int64_t v = 0;
    if (!parse_int(field, v)) error(card_line_, std::string("malformed ") + what + " " + quoted(field));
    return v;
  }

  const std::string& field(size_t i) const {
    static const std::string kBlank;
    return i < card_.fields.size() ? card_.fields[i] : kBlank;
  }

  void finish_card() {
    const std::string& n = card_.name;
    if (n == "GRID") {
      const int64_t id = integer(field(0), "GRID ID", 0);
      if (id <= 0) error(card_line_, "GRID needs a positive ID");
      const int64_t cp = integer(field(1), "GRID CP", 0);
      if (cp != 0)
        error(card_line_, "GRID " + std::to_string(id) + " is in coordinate system " + std::to_string(cp) +
                              " (only the basic system, CP 0 or blank, is read)");
      Vec3 p{real(field(2), "coordinate"), real(field(3), "coordinate"), real(field(4), "coordinate")};
      if (!is_finite(p)) error(card_line_, "GRID " + std::to_string(id) + " has a non-finite coordinate");
      if (!grid_index_.emplace(id, uint32_t(points_.size())).second)
        error(card_line_, "GRID " + std::to_string(id) + " is defined twice");
      check_point_count(name_, points_.size() + 1);
      points_.push_back(p);
    } else if (n == "CTRIA3" || n == "CTRIA6" || n == "CQUAD4" || n == "CQUAD8") {
      const size_t corners = n[1] == 'T' ? 3 : 4;
      Element e;
      e.id = integer(field(0), "element ID", 0);
      e.pid = integer(field(1), "PID", e.id);  // a blank PID is the element ID
      for (size_t k = 0; k < corners; ++k) {
        if (field(2 + k).empty())
          error(card_line_, n + " " + std::to_string(e.id) + " lacks grid " + std::to_string(k + 1));
        e.grids.push_back(integer(field(2 + k), "grid ID", 0));
      }
      e.line = card_line_;
      elements_.push_back(std::move(e));
    }
    card_.name.clear();
  }

  void name_comment(std::string_view line) {
    std::string_view rest = line.substr(1);
    int64_t pid = 0;
    std::string_view part;
    if (trim(rest).substr(0, 4) == "PID ") {  // ours: "$ PID 3: name"
      rest = trim(rest).substr(4);
      size_t colon = rest.find(": ");
      if (colon == std::string_view::npos || !parse_int(trim(rest.substr(0, colon)), pid)) return;
      part = rest.substr(colon + 2);
    } else if (rest.substr(0, 18) == "ANSA_NAME_COMMENT;") {  // "$ANSA_NAME_COMMENT;3;PSHELL;name;..."
      rest = rest.substr(18);
      size_t a = rest.find(';'), b = a == std::string_view::npos ? a : rest.find(';', a + 1);
      if (b == std::string_view::npos || rest.substr(a + 1, b - a - 1) != "PSHELL" ||
          !parse_int(rest.substr(0, a), pid))
        return;
      part = rest.substr(b + 1);
      part = part.substr(0, part.find(';'));
    } else if (rest.substr(0, 12) == "HMNAME PROP ") {  // "$HMNAME PROP       3"name""
      rest = rest.substr(12);
      size_t quote = rest.find('"'), end = quote == std::string_view::npos ? quote : rest.find('"', quote + 1);
      if (end == std::string_view::npos || !parse_int(trim(rest.substr(0, quote)), pid)) return;
      part = rest.substr(quote + 1, end - quote - 1);
    } else {
      return;
    }
    pid_names_.emplace(pid, std::string(part));
  }

  Mesh build() {
    Mesh mesh;
    mesh.points = std::move(points_);
    std::unordered_map<int64_t, int32_t> part_index;
    std::vector<uint32_t> polygon;
    PolygonTriangulator triangulator;
    for (const Element& e : elements_) {
      polygon.clear();
      for (int64_t g : e.grids) {
        auto it = grid_index_.find(g);
        if (it == grid_index_.end())
          error(e.line, "element " + std::to_string(e.id) + " refers to GRID " + std::to_string(g) +
                            ", which the file does not define");
        polygon.push_back(it->second);
      }
      auto [it, inserted] = part_index.emplace(e.pid, int32_t(mesh.part_names.size()));
      if (inserted) {
        auto named = pid_names_.find(e.pid);
        mesh.part_names.push_back(named != pid_names_.end() ? named->second : "pid" + std::to_string(e.pid));
      }
      triangulator.run(mesh.points, polygon.data(), polygon.size(), mesh.triangles);
      mesh.triangle_part.resize(mesh.triangles.size(), it->second);
    }
    return mesh;
  }

  LineReader lines_;
  const std::string& name_;
  Card card_;
  bool large_ = false;
  size_t card_line_ = 0;
  std::vector<Vec3> points_;
  std::unordered_map<int64_t, uint32_t> grid_index_;
  std::vector<Element> elements_;
  std::unordered_map<int64_t, std::string> pid_names_;
};

}  // namespace

Mesh read_nastran(std::string_view bytes, const std::string& name) { return NastranReader(bytes, name).read(); }

void write_nastran(const Mesh& mesh, Sink& out) {
  out.put("$ Nastran bulk data written by vdbwrap: GRID* (large field), CTRIA3, PSHELL\n");
  out.put("BEGIN BULK\n");
  const size_t parts = std::max<size_t>(mesh.part_names.size(), 1);
  for (size_t p = 0; p < parts; ++p) {
    const std::string pid = std::to_string(p + 1);
    if (p < mesh.part_names.size()) out.put("$ PID " + pid + ": " + one_line(mesh.part_names[p]) + "\n");
    out.put(left("PSHELL", kSmallField) + right(pid, kSmallField) + "\n");
  }
  // GRID* ID CP X1 X2, continued on a "*" line: X3 CD.
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    const Vec3& p = mesh.points[i];
    out.put(left("GRID*", kSmallField));
    out.put(right(std::to_string(i + 1), kLargeField));
    out.put(right("0", kLargeField));
    out.put(right(nastran_real(p[0], kLargeField), kLargeField));
    out.put(right(nastran_real(p[1], kLargeField), kLargeField));
    out.put("\n");
    out.put(left("*", kSmallField));
    out.put(right(nastran_real(p[2], kLargeField), kLargeField));
    out.put(right("0", kLargeField));
    out.put("\n");
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    std::string card = left("CTRIA3", kSmallField) + right(std::to_string(t + 1), kSmallField) +
                       right(std::to_string(mesh.part_of(t) + 1), kSmallField);
    for (uint32_t v : mesh.triangles[t]) card += right(std::to_string(uint64_t(v) + 1), kSmallField);
    out.put(card + "\n");
  }
  out.put("ENDDATA\n");
}

}  // namespace vdbwrap::io::detail
