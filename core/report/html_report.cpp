// The HTML report page: the numbers of the JSON report as static HTML (readable without
// WebGL, each value in an element with data-key = its path in the JSON and data-value = its
// JSON text), and the meshes, the input's marks and the leak as data for the embedded viewer.
#include "vdbwrap/html_report.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <sstream>

#include "common/vec.h"
#include "report/base64.h"
#include "report/display_mesh.h"
#include "report/input_marks.h"
#include "report/page_assets.h"

namespace vdbwrap {
namespace {

using nlohmann::json;

std::string escape_html(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// JSON text that can sit inside <script>: "</" never closes the element ("<\/" is the same string).
std::string script_safe(const json& j) {
  std::string text = j.dump(-1, ' ', false, json::error_handler_t::replace);
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    out += text[i];
    if (text[i] == '<' && i + 1 < text.size() && (text[i + 1] == '/' || text[i + 1] == '!')) out += '\\';
  }
  return out;
}

// "</script" inside the library's text would end its element early.
std::string script_text(const std::string& code) {
  std::string out;
  out.reserve(code.size());
  size_t from = 0;
  for (size_t at; (at = code.find("</script", from)) != std::string::npos; from = at + 2)
    out += code.substr(from, at - from) + "<\\/";
  return out + code.substr(from);
}

std::string with_thousands(unsigned long long v) {
  std::string digits = std::to_string(v), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

std::string real(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

enum class Shown { Plain, Percent, Seconds };

std::string shown(const json& v, Shown how) {
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number_unsigned()) return with_thousands(v.get<unsigned long long>());
  if (v.is_number_integer())
    return v.get<long long>() < 0 ? "-" + with_thousands(-v.get<long long>()) : with_thousands(v.get<long long>());
  if (v.is_number()) return real(v.get<double>()) + (how == Shown::Percent ? " %" : how == Shown::Seconds ? " s" : "");
  if (v.is_string()) return v.get<std::string>().empty() ? "none" : v.get<std::string>();
  if (v.is_null()) return "none";
  if (v.is_array()) {
    if (v.empty()) return "none";
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + shown(v[i], Shown::Plain);
    return v.size() > 1 && v[0].is_number() && !v[0].is_number_integer() ? "(" + s + ")" : s;
  }
  return v.dump();
}

const json* at_path(const json& root, const std::string& path) {
  const json* j = &root;
  std::stringstream parts(path);
  for (std::string key; std::getline(parts, key, '.');) {
    if (j->is_array()) {
      const size_t i = std::stoul(key);
      if (i >= j->size()) return nullptr;
      j = &(*j)[i];
    } else if (j->is_object() && j->contains(key)) {
      j = &(*j)[key];
    } else {
      return nullptr;
    }
  }
  return j;
}

// Tables of the report's values; a path the report lacks is left out.
class Tables {
 public:
  explicit Tables(const json& report) : report_(report) {}

  // Opened by its first row: a section the report has nothing for is left out.
  void section(const std::string& title, const std::string& id) {
    close();
    pending_ = "<section id=\"" + id + "\"><h2>" + escape_html(title) + "</h2><table>";
  }
  void row(const std::string& label, const std::string& path, Shown how = Shown::Plain) {
    if (const json* v = at_path(report_, path)) value_row(label, path, *v, how);
  }
  // Plain rows: (label, path) pairs.
  void rows(std::initializer_list<std::pair<const char*, const char*>> list) {
    for (const auto& [label, path] : list) row(label, path);
  }
  void value_row(const std::string& label, const std::string& path, const json& v, Shown how = Shown::Plain) {
    if (!open_) html_ << pending_, open_ = true;
    html_ << "<tr><th>" << escape_html(label) << "</th><td data-key=\"" << escape_html(path) << "\" data-value=\""
          << escape_html(v.dump(-1, ' ', false, json::error_handler_t::replace)) << "\">" << escape_html(shown(v, how))
          << "</td></tr>";
  }
  std::string done() {
    close();
    return html_.str();
  }

 private:
  void close() {
    if (open_) html_ << "</table></section>";
    open_ = false;
  }
  const json& report_;
  std::string pending_;
  std::ostringstream html_;
  bool open_ = false;
};

std::string numbers_html(const json& r, bool has_wrap) {
  Tables t(r);
  const json* leak = at_path(r, "leak.detected");
  const bool leaked = leak && leak->is_boolean() && leak->get<bool>();
  if (leaked) {
    t.section("Leak", "leak");
    t.rows({{"What", "leak.description"}, {"Narrowest passage at", "leak.location"}, {"Passage width", "leak.width"}});
  }
  t.section("Input", "input");
  t.rows({{"Triangles", "input.triangles"},
          {"Vertices", "input.vertices"},
          {"Parts", "input.parts"},
          {"Connected components", "input.components"},
          {"Border edges", "input.border_edges"},
          {"Non-manifold edges", "input.nonmanifold_edges"},
          {"Non-manifold vertices", "input.nonmanifold_vertices"},
          {"Misoriented edges", "input.misoriented_edges"},
          {"Degenerate triangles", "input.degenerate_triangles"},
          {"Intersecting triangles", "input.intersecting_triangles"},
          {"Closed", "input.closed"},
          {"Bounding-box diagonal", "input.diagonal"}});
  if (const json* parts = at_path(r, "source.parts"); parts && parts->is_array() && parts->size() > 1)
    for (size_t i = 0; i < parts->size(); ++i) {
      const json* name = at_path(r, "source.parts." + std::to_string(i) + ".name");
      t.row("Part " + (name && name->is_string() && !name->get<std::string>().empty() ? name->get<std::string>()
                                                                                      : std::to_string(i)),
            "source.parts." + std::to_string(i) + ".triangles");
    }
  if (has_wrap) {
    t.section("Wrap", "wrap");
    t.rows({{"Valid closed surface", "output.valid_closed_surface"},
            {"Triangles", "output.triangles"},
            {"Vertices", "output.vertices"},
            {"Connected components", "output.components"},
            {"Closed", "output.closed"},
            {"Manifold", "output.manifold"},
            {"Outward oriented", "output.outward"},
            {"Self-intersecting", "output.self_intersecting"},
            {"Area", "output.area"},
            {"Volume", "output.volume"}});
    t.section("Distance (% of the diagonal)", "distance");
    for (const auto& [label, key] : {std::pair<std::string, std::string>{"Wrap to input", "distance_output_to_input"},
                                     {"Input to wrap", "distance_input_to_output"},
                                     {"Sharp edges to wrap", "distance_sharp_edges_to_output"}}) {
      const json* samples = at_path(r, key + ".samples");
      if (!samples || !samples->is_number() || samples->get<double>() <= 0) continue;
      t.row(label + ", mean", key + ".mean_percent_of_diagonal", Shown::Percent);
      t.row(label + ", 95th percentile", key + ".p95_percent_of_diagonal", Shown::Percent);
      t.row(label + ", max", key + ".max_percent_of_diagonal", Shown::Percent);
    }
    t.section("Quality of the wrap", "quality");
    t.rows({{"Smallest angle (degrees)", "quality.after.min_angle_deg"},
            {"Sliver triangles", "quality.after.sliver_triangles"},
            {"Small triangles", "quality.after.small_area_triangles"},
            {"Short edges", "quality.after.short_edges"},
            {"Long edges", "quality.after.long_edges"},
            {"Normal off the input", "quality.after.normal_deviation_triangles"},
            {"Sharp-edge samples lost", "quality.after.lost_feature_samples"},
            {"Regions rebuilt", "quality.remesh.regions"}});
  }
  t.section("Features", "features");
  t.rows({{"Sharp edges", "features.sharp_edges"},
          {"Sharp edges left out as noise", "features.noise_sharp_edges"},
          {"Intersection segments left out as noise", "features.noise_intersection_segments"},
          {"Boundary edges of small rims left out", "features.small_rim_edges"},
          {"Edges of narrow strips left out", "features.narrow_strip_edges"},
          {"Intersection segments of narrow strips left out", "features.narrow_strip_intersection_segments"},
          {"Sharp edges beside a copy's left out", "features.duplicate_sharp_edges"},
          {"Intersection segments beside a copy's left out", "features.duplicate_intersection_segments"},
          {"Boundary edges of cracks left out", "features.crack_edges"},
          {"Intersection segments along cracks left out", "features.crack_intersection_segments"},
          {"Width of the hairline cracks (nine in ten within)", "features.crack_gap"},
          {"Faces where solids touch left out", "features.inside_faces"},
          {"Curves", "features.curves"},
          {"Corners", "features.corners"},
          {"Curves captured", "features.curves_captured"},
          {"Corners captured", "features.corners_captured"}});
  t.section("Grid and volumes", "grid");
  t.rows({{"Base cell", "grid.base_size"},
          {"Finest cell", "grid.finest_size"},
          {"Cells on the input per level", "grid.cells_on_input_per_level"},
          {"Free volumes", "volumes.free_volumes"},
          {"Enclosed volumes", "volumes.enclosed_volumes"},
          {"Input encloses a volume", "volumes.input_encloses_a_volume"},
          {"Chosen volume", "volumes.chosen_volume"}});
  if (const json* params = at_path(r, "parameters"); params && params->is_object()) {
    t.section("Parameters", "parameters");
    for (const auto& [key, value] : params->items()) t.value_row(key, "parameters." + key, value);
  }
  if (const json* stages = at_path(r, "stages"); stages && stages->is_array()) {
    t.section("Stage times", "stages");
    for (size_t i = 0; i < stages->size(); ++i) {
      const json* name = at_path(r, "stages." + std::to_string(i) + ".name");
      t.row(name && name->is_string() ? name->get<std::string>() : std::to_string(i),
            "stages." + std::to_string(i) + ".seconds", Shown::Seconds);
    }
    t.row("Total", "total_seconds", Shown::Seconds);
  }
  return t.done();
}

json mesh_data(const Mesh& mesh, const report::DisplayMesh& d) {
  json m{{"positions", report::base64(d.positions)},
         {"triangles", report::base64(d.triangles)},
         {"triangles_total", d.mesh_triangles},
         {"triangles_shown", d.source_triangle.size()},
         {"clustered", d.clustered},
         {"cluster_size", d.cluster_size}};
  json names = json::array();
  for (const auto& n : mesh.part_names) names.push_back(n);
  m["part_names"] = names;
  if (!mesh.triangle_part.empty() && mesh.part_names.size() > 1)
    m["parts"] = report::base64(report::display_per_triangle(d, mesh.triangle_part));
  return m;
}

// How many triangles carry each bit, over the whole mesh (the legend's counts).
json bit_counts(const std::vector<uint8_t>& flags) {
  std::vector<size_t> counts(8, 0);
  for (uint8_t f : flags)
    for (int b = 0; b < 8; ++b) counts[b] += (f >> b) & 1;
  return counts;
}

void check_indices(const Mesh& m, const char* which) {
  for (const Tri& t : m.triangles)
    for (uint32_t v : t)
      if (v >= m.points.size())
        throw Error(ErrorKind::InvalidArgument, std::string("html report: the ") + which + " has a triangle corner " +
                                                    std::to_string(v) + " past its " + std::to_string(m.points.size()) +
                                                    " points");
  if (!m.triangle_part.empty() && m.triangle_part.size() != m.triangles.size())
    throw Error(ErrorKind::InvalidArgument,
                std::string("html report: the ") + which + "'s part list does not match its triangles");
}

const char* sign_name(DistanceSign s) {
  switch (s) {
    case DistanceSign::Outside:
      return "outside";
    case DistanceSign::FrontSide:
      return "front";
    default:
      return "unsigned";
  }
}

}  // namespace

std::string html_report(const HtmlReportData& data, const std::string& three_js) {
  if (!data.input) throw Error(ErrorKind::InvalidArgument, "html report: no input mesh");
  json r;
  try {
    r = json::parse(data.report_json);
  } catch (const json::exception& e) {
    throw Error(ErrorKind::InvalidArgument, std::string("html report: the report is not JSON: ") + e.what());
  }
  if (!r.is_object()) throw Error(ErrorKind::InvalidArgument, "html report: the report is not a JSON object");
  const Mesh& input = *data.input;
  const Mesh* wrap = data.wrap && !data.wrap->triangles.empty() ? data.wrap : nullptr;
  check_indices(input, "input");
  if (wrap) check_indices(*wrap, "wrap");

  Box3 box;
  for (const Tri& t : input.triangles)
    for (uint32_t v : t) box.add(input.points[v]);
  if (wrap)
    for (const Vec3& p : wrap->points) box.add(p);
  const Vec3 origin = box.empty() ? Vec3{0, 0, 0} : box.center();

  double feature_angle = 30;
  if (const json* a = at_path(r, "parameters.feature_angle_deg"); a && a->is_number()) feature_angle = a->get<double>();
  // The report's count says when there is nothing to find: the search is most of the marking.
  const json* crossing = at_path(r, "input.intersecting_triangles");
  const bool none_crossing = crossing && crossing->is_number() && crossing->get<double>() == 0;
  // One exact weld of the input serves its marks and its display.
  const ExactWeld input_weld = exact_weld(input.points);
  const report::InputMarks marks = report::mark_input(
      input, input_weld, feature_angle, !none_crossing && input.triangles.size() <= data.intersection_search_limit);

  json scene{{"origin", origin}, {"diagonal", box.diagonal()}, {"display_limit", data.display_triangles}};
  const report::DisplayMesh input_display = report::display_mesh(input, origin, data.display_triangles, &input_weld);
  scene["input"] = mesh_data(input, input_display);
  scene["input"]["flags"] = report::base64(report::display_per_triangle(input_display, marks.flags));
  scene["input"]["flag_counts"] = bit_counts(marks.flags);
  scene["input"]["intersections_searched"] = none_crossing || marks.intersections_searched;
  // Feature curves: every sharp edge up to a display budget, evenly thinned beyond it.
  const size_t max_segments = std::max<size_t>(data.display_triangles / 2, 1);
  const size_t stride = (marks.sharp_edges.size() + max_segments - 1) / max_segments;
  std::vector<float> segments;
  for (size_t i = 0; i < marks.sharp_edges.size(); i += std::max<size_t>(stride, 1))
    for (const Vec3& p : marks.sharp_edges[i])
      for (int k = 0; k < 3; ++k) segments.push_back(float(p[k] - origin[k]));
  scene["features"] = {{"segments", report::base64(segments)},
                       {"total", marks.sharp_edges.size()},
                       {"shown", segments.size() / 6},
                       {"angle_deg", feature_angle}};
  if (wrap) {
    const report::DisplayMesh wrap_display = report::display_mesh(*wrap, origin, data.display_triangles);
    scene["wrap"] = mesh_data(*wrap, wrap_display);
    const DeviationField* dev = data.deviation;
    if (dev && dev->distance.size() == wrap->points.size()) {
      scene["wrap"]["deviation"] = report::base64(report::display_values(wrap_display, dev->distance));
      scene["deviation"] = {{"sign", sign_name(dev->sign)}, {"max_abs", dev->max_abs}, {"max_at", dev->max_at},
                            {"mean_abs", dev->mean_abs},    {"p95_abs", dev->p95_abs}, {"diagonal", dev->diagonal}};
    }
    if (dev && dev->triangle_flags.size() == wrap->triangles.size()) {
      scene["wrap"]["flags"] = report::base64(report::display_per_triangle(wrap_display, dev->triangle_flags));
      scene["wrap"]["flag_counts"] = bit_counts(dev->triangle_flags);
    }
  }

  const std::string title = data.title.empty() ? std::string("vdbwrap report") : "vdbwrap report: " + data.title;
  const json* leak = at_path(r, "leak.detected");
  const bool leaked = leak && leak->is_boolean() && leak->get<bool>();
  const json* valid = at_path(r, "output.valid_closed_surface");
  std::string verdict, verdict_class;
  if (leaked)
    verdict = "No wrap: the volume leaks", verdict_class = "bad";
  else if (wrap && valid && valid->is_boolean() && valid->get<bool>())
    verdict = "Valid closed surface", verdict_class = "good";
  else
    verdict = wrap ? "The wrap failed validation" : "No wrap", verdict_class = "bad";

  std::ostringstream page;
  page
      << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
      << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
      << "<meta name=\"generator\" content=\"vdbwrap\"><title>" << escape_html(title) << "</title>\n<style>"
      << report::kViewerCss << "</style></head>\n<body data-viewer=\"loading\">\n"
      << "<div id=\"app\"><main id=\"view\"><div id=\"toolbar\"></div><div id=\"stage\"><canvas id=\"canvas\"></canvas>"
      << "<div id=\"message\"></div><div id=\"legend\"></div></div><div id=\"note\"></div></main>\n"
      << "<aside id=\"numbers\"><header><h1>" << escape_html(data.title.empty() ? "vdbwrap report" : data.title)
      << "</h1><p class=\"verdict " << verdict_class << "\">" << escape_html(verdict) << "</p>";
  if (const json* v = at_path(r, "vdbwrap_version"); v && v->is_string())
    page << "<p class=\"small\">vdbwrap " << escape_html(v->get<std::string>()) << "</p>";
  page << "</header>" << numbers_html(r, wrap != nullptr) << "</aside></div>\n"
       << "<script type=\"application/json\" id=\"vdbwrap-report\">" << script_safe(r) << "</script>\n"
       << "<script type=\"application/json\" id=\"vdbwrap-scene\">" << script_safe(scene) << "</script>\n"
       << "<script>" << script_text(three_js) << "</script>\n"
       << "<script>" << script_text(report::kViewerJs) << "</script>\n</body></html>\n";
  return page.str();
}

}  // namespace vdbwrap
