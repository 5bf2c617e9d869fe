// Nastran bulk data (write only): GRID* in large field format (16-character coordinates, so
// doubles keep 14-15 significant digits in the usual ranges), CTRIA3 in small field format,
// one PSHELL per part with PID = part index + 1 and the part's name in a "$ PID n: name"
// comment just above it (Nastran itself has no place for names).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

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

}  // namespace

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
