// The HTML report's writer (core/report) below the browser: bad arguments, the numbers' keys and
// values, text that would end a script element, display clustering, the input's marks. The page
// in a browser is tests/python/test_html_report.py (ctest html_report).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "report/display_mesh.h"
#include "report/input_marks.h"
#include "test_meshes.h"
#include "vdbwrap/html_report.h"

namespace {

using namespace vdbwrap;

size_t count_of(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

const char* kReport = R"({"input": {"triangles": 12, "closed": true, "diagonal": 1.7320508075688772},
  "stages": [{"name": "prepare", "seconds": 0.5}], "total_seconds": 1.25,
  "parameters": {"base_size": "1%", "feature_angle_deg": 30.0},
  "leak": {"detected": false}})";

TEST(HtmlReport, RejectsMissingInputAndReportsThatAreNotJsonObjects) {
  const Mesh box = vdbwrap::testing::box_mesh({0, 0, 0}, {1, 1, 1});
  HtmlReportData data;
  data.report_json = kReport;
  try {
    html_report(data, "var THREE = {};");
    FAIL() << "no input mesh accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
  }
  Mesh broken = box;
  broken.triangles[3][1] = 8;
  data.input = &broken;
  try {
    html_report(data, "var THREE = {};");
    FAIL() << "a triangle corner past the points accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
  }
  data.input = &box;
  for (const char* bad : {"", "{\"input\": ", "[1, 2]", "42"}) {
    data.report_json = bad;
    try {
      html_report(data, "var THREE = {};");
      FAIL() << "report '" << bad << "' accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument) << bad;
    }
  }
}

TEST(HtmlReport, EveryNumberCarriesItsKeyAndItsJsonValue) {
  const Mesh box = vdbwrap::testing::box_mesh({0, 0, 0}, {1, 1, 1});
  HtmlReportData data;
  data.input = &box;
  data.report_json = kReport;
  const std::string page = html_report(data, "var THREE = {};");
  EXPECT_NE(page.find(R"(data-key="input.triangles" data-value="12">12<)"), std::string::npos);
  EXPECT_NE(page.find(R"(data-key="input.closed" data-value="true">yes<)"), std::string::npos);
  EXPECT_NE(page.find(R"(data-key="input.diagonal" data-value="1.7320508075688772">1.732<)"), std::string::npos);
  EXPECT_NE(page.find(R"(data-key="stages.0.seconds" data-value="0.5">0.5 s<)"), std::string::npos);
  EXPECT_NE(page.find(R"(data-key="parameters.base_size" data-value="&quot;1%&quot;">1%<)"), std::string::npos);
  // No wrap: no wrap section, and nothing shown the report does not have.
  EXPECT_EQ(page.find("data-key=\"output."), std::string::npos);
  EXPECT_EQ(page.find("<section id=\"wrap\">"), std::string::npos);
}

TEST(HtmlReport, TextThatWouldEndAScriptIsEscaped) {
  Mesh box = vdbwrap::testing::box_mesh({0, 0, 0}, {1, 1, 1});
  box.part_names = {"</script><b>bold</b>"};
  std::string report = kReport;
  report.insert(1, R"("source": {"file_name": "a</script>.stl", "parts": [{"name": "</script>", "triangles": 12}]},)");
  HtmlReportData data;
  data.input = &box;
  data.report_json = report;
  data.title = "<i>x</i>";
  const std::string page = html_report(data, "var THREE = {}; // </script> in a comment");
  // The four scripts' own ends only: the report, the scene, three.js and the viewer.
  EXPECT_EQ(count_of(page, "</script>"), 4u);
  EXPECT_NE(page.find(R"(<\/script><b>bold<\/b>)"), std::string::npos) << "the part name, inside the scene's JSON";
  EXPECT_EQ(page.find("<i>x"), std::string::npos);
  EXPECT_NE(page.find("&lt;i&gt;x&lt;/i&gt;"), std::string::npos);
}

TEST(HtmlReport, BigMeshesAreClusteredForDisplayAndThePageSaysHowMany) {
  const Mesh sphere = vdbwrap::testing::icosphere_mesh(1.0, 6);  // 81920 triangles
  ASSERT_GT(sphere.triangles.size(), 50000u);
  const report::DisplayMesh small = report::display_mesh(sphere, {0, 0, 0}, sphere.triangles.size());
  EXPECT_FALSE(small.clustered);
  EXPECT_EQ(small.source_triangle.size(), sphere.triangles.size());

  const size_t limit = 10000;
  const Vec3 origin{0.25, -0.5, 2};
  const report::DisplayMesh d = report::display_mesh(sphere, origin, limit);
  EXPECT_TRUE(d.clustered);
  EXPECT_LE(d.source_triangle.size(), limit);
  EXPECT_GT(d.source_triangle.size(), limit / 8) << "clustered far more than needed";
  EXPECT_EQ(d.triangles.size(), 3 * d.source_triangle.size());
  ASSERT_EQ(d.vertex_of.size(), sphere.points.size());
  // Cluster centres of points on the unit sphere stay close to it (origin taken off).
  for (size_t v = 0; v < d.positions.size() / 3; ++v) {
    const double x = d.positions[3 * v] + origin[0], y = d.positions[3 * v + 1] + origin[1],
                 z = d.positions[3 * v + 2] + origin[2];
    EXPECT_NEAR(std::sqrt(x * x + y * y + z * z), 1.0, 2 * d.cluster_size);
  }
  for (uint32_t t : d.source_triangle) ASSERT_LT(t, sphere.triangles.size());
  for (size_t i = 0; i < d.triangles.size(); i += 3) {
    EXPECT_NE(d.triangles[i], d.triangles[i + 1]);
    EXPECT_NE(d.triangles[i + 1], d.triangles[i + 2]);
  }
  // A cluster shows its value of largest magnitude: one far vertex is not averaged away.
  std::vector<double> values(sphere.points.size(), 0.1);
  values[17] = -5;
  const std::vector<float> shown = report::display_values(d, values);
  EXPECT_FLOAT_EQ(shown[d.vertex_of[17]], -5.0f);
  EXPECT_EQ(std::count(shown.begin(), shown.end(), -5.0f), 1);

  HtmlReportData data;
  data.input = &sphere;
  data.report_json = kReport;
  data.display_triangles = limit;
  const std::string page = html_report(data, "var THREE = {};");
  EXPECT_NE(page.find("\"clustered\":true"), std::string::npos);
  EXPECT_NE(page.find("\"triangles_shown\":" + std::to_string(d.source_triangle.size())), std::string::npos);
  EXPECT_NE(page.find("\"triangles_total\":" + std::to_string(sphere.triangles.size())), std::string::npos);
}

TEST(HtmlReport, InputMarksFindHolesFlipsAndSharpEdges) {
  Mesh box = vdbwrap::testing::box_mesh({0, 0, 0}, {2, 1, 1});
  report::InputMarks clean = report::mark_input(box, exact_weld(box.points), 30, true);
  EXPECT_EQ(std::count(clean.flags.begin(), clean.flags.end(), 0), 12);
  EXPECT_EQ(clean.sharp_edges.size(), 12u) << "a box's edges, not its faces' diagonals";
  EXPECT_TRUE(clean.intersections_searched);

  // One triangle turned over: it and its three neighbours face against each other, and the
  // box's edges stay its sharp edges (the angle is the surface's, not the flip's).
  std::swap(box.triangles[0][1], box.triangles[0][2]);
  report::InputMarks flipped = report::mark_input(box, exact_weld(box.points), 30, false);
  EXPECT_EQ(std::count_if(flipped.flags.begin(), flipped.flags.end(),
                          [](uint8_t f) { return f & report::kInputMisoriented; }),
            4);
  EXPECT_EQ(flipped.sharp_edges.size(), 12u);
  EXPECT_FALSE(flipped.intersections_searched);

  // A hole: its rim's triangles, and nothing else.
  box = vdbwrap::testing::box_mesh({0, 0, 0}, {2, 1, 1});
  box.triangles.erase(box.triangles.begin());
  box.triangle_part.erase(box.triangle_part.begin());
  report::InputMarks holed = report::mark_input(box, exact_weld(box.points), 30, true);
  const auto rim =
      std::count_if(holed.flags.begin(), holed.flags.end(), [](uint8_t f) { return f & report::kInputBorder; });
  EXPECT_EQ(rim, 3) << "the three triangles across the missing one's edges";

  // Two boxes pushed into each other cross.
  Mesh two = vdbwrap::testing::box_mesh({0, 0, 0}, {1, 1, 1});
  vdbwrap::testing::add_box(two, {0.5, 0.5, 0.5}, {1.5, 1.5, 1.5});
  report::InputMarks crossing = report::mark_input(two, exact_weld(two.points), 30, true);
  EXPECT_GT(std::count_if(crossing.flags.begin(), crossing.flags.end(),
                          [](uint8_t f) { return f & report::kInputIntersecting; }),
            0);
}

}  // namespace
