// The CLI as a user runs it: exit codes and one-line messages for bad input and arguments.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <set>
#include <filesystem>
#include <fstream>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <regex>

#include "../client/suggest.h"
#include "vdbwrap/io.h"
#include "test_meshes.h"

#ifndef VDBWRAP_CLI
#define VDBWRAP_CLI "vdbwrap"
#endif

using namespace vdbwrap;
namespace fs = std::filesystem;

namespace {

struct CliRun {
  int code;
  std::string err;
  std::string out;
  double seconds = 0;  // wall time of the run
};

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("vdbwrap_cli_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }

  // env: assignments put before the command (VAR=value ...).
  CliRun run(const std::string& args, const std::string& env = "") {
    std::string err = (dir / "stderr.txt").string(), out = (dir / "stdout.txt").string();
    std::string cmd = env + " " + std::string(VDBWRAP_CLI) + " " + args + " > " + out + " 2> " + err;
    const auto t0 = std::chrono::steady_clock::now();
    int status = std::system(cmd.c_str());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    auto slurp = [](const std::string& path) {
      std::ifstream in(path);
      return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(err), slurp(out), seconds};
  }
  // Runs the CLI on a pseudo-terminal, as from an interactive shell (stderr is a TTY): what it
  // wrote to the terminal, and its exit code.
  CliRun run_on_terminal(const std::string& args) {
    const std::string cmd = std::string(VDBWRAP_CLI) + " " + args;
    int master = -1;
    const pid_t pid = ::forkpty(&master, nullptr, nullptr, nullptr);
    if (pid == 0) {
      ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    std::string text;
    if (pid < 0) return {-1, "forkpty failed", "", 0};
    char buf[4096];
    for (;;) {
      const ssize_t n = ::read(master, buf, sizeof buf);
      if (n > 0)
        text.append(buf, size_t(n));
      else if (n < 0 && errno == EINTR)
        continue;
      else
        break;  // EIO once the child has closed the terminal
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ::close(master);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text, "", 0};
  }
  std::string file(const std::string& name, const std::string& bytes) {
    std::string p = (dir / name).string();
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
  fs::path dir;
};

std::string binary_stl(uint32_t declared, size_t triangles, float fill = 0.0f) {
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&declared), 4);
  for (size_t t = 0; t < triangles; ++t) {
    float v[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, fill};
    s.append(reinterpret_cast<const char*>(v), 48);
    s.append(2, '\0');
  }
  return s;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

TEST_F(Cli, WrapsAFileAndWritesAReport) {
  CliRun r = run("wrap " + vdbwrap::testing::data_path("fuze.obj") + " -o " + (dir / "out.ply").string() +
                 " --base-size 2% --report " + (dir / "report.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  Mesh out = io::read_mesh((dir / "out.ply").string());
  auto v = vdbwrap::testing::valid_closed_surface(out);
  EXPECT_TRUE(v.ok) << v.why;
  std::ifstream rep(dir / "report.json");
  std::string json((std::istreambuf_iterator<char>(rep)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"valid_closed_surface\": true"), std::string::npos);
  EXPECT_NE(json.find("distance_output_to_input"), std::string::npos);
  EXPECT_NE(json.find("peak_memory_mb"), std::string::npos);
}

// The last line of a wrap run with --no-distances printed "distance to input mean 0.0000%, p95
// 0.0000% of the diagonal, max 0 at (0, 0, 0)", as if the fit were perfect (found by the
// 2026-11-26 sweep). It says the distances were not sampled; with samples it gives them.
TEST_F(Cli, WrapWithoutDistancesSaysSoInsteadOfPrintingZeros) {
  const std::string in = vdbwrap::testing::data_path("fuze.obj"), out = (dir / "out.ply").string();
  CliRun none = run("wrap " + in + " -o " + out + " --base-size 4% --no-distances");
  ASSERT_EQ(none.code, 0) << none.err;
  EXPECT_NE(none.err.find("distances not sampled (--no-distances)"), std::string::npos) << none.err;
  EXPECT_EQ(none.err.find("distance to input mean"), std::string::npos) << none.err;
  CliRun sampled = run("wrap " + in + " -o " + out + " --base-size 4%");
  ASSERT_EQ(sampled.code, 0) << sampled.err;
  EXPECT_NE(sampled.err.find("distance to input mean"), std::string::npos) << sampled.err;
}

TEST_F(Cli, CheckReportsWatertightnessAndDistance) {
  CliRun ok = run("check " + vdbwrap::testing::data_path("unit_sphere.STL") + " --against " +
                  vdbwrap::testing::data_path("unit_sphere.STL"));
  EXPECT_EQ(ok.code, 0) << ok.err;
}

TEST_F(Cli, CheckRequireValidFailsOnAnOpenMesh) {
  EXPECT_EQ(run("check --require-valid " + vdbwrap::testing::data_path("suzanne.ply")).code, 4);
  EXPECT_EQ(run("check --require-valid " + vdbwrap::testing::data_path("torus.STL")).code, 0);
}

TEST_F(Cli, EmptyFileIsInvalidInput) {
  CliRun r = run("wrap " + file("empty.stl", "") + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("empty.stl"), std::string::npos) << r.err;
}

TEST_F(Cli, TruncatedBinaryStlIsInvalidInput) {
  std::string bytes = binary_stl(10, 10);
  bytes.resize(bytes.size() - 30);
  CliRun r = run("wrap " + file("truncated.stl", bytes) + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("truncated.stl"), std::string::npos) << r.err;
}

TEST_F(Cli, TriangleCountNotMatchingTheSizeIsInvalidInput) {
  CliRun r = run("wrap " + file("count.stl", binary_stl(1000, 3)) + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("1000"), std::string::npos) << r.err;
}

TEST_F(Cli, NanCoordinatesAreInvalidInput) {
  CliRun r = run("wrap " + file("nan.stl", binary_stl(2, 2, std::nanf(""))) + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(r.code, 3);
  std::string ascii =
      "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex inf 0 0\nvertex 0 1 "
      "0\nendloop\nendfacet\nendsolid x\n";
  CliRun a = run("wrap " + file("inf.stl", ascii) + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(a.code, 3);
  EXPECT_NE(a.err.find("line 5"), std::string::npos) << a.err;
}

TEST_F(Cli, ZeroTrianglesIsInvalidInput) {
  CliRun r = run("wrap " + file("zero.stl", binary_stl(0, 0)) + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("no triangles"), std::string::npos) << r.err;
}

TEST_F(Cli, ObjIndexOutOfRangeNamesTheLine) {
  CliRun r = run("wrap " + file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n") + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("line 4"), std::string::npos) << r.err;
}

TEST_F(Cli, MissingFileIsInvalidInput) {
  CliRun r = run("wrap " + (dir / "nope.stl").string() + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("nope.stl"), std::string::npos);
}

TEST_F(Cli, BadArgumentsAreExitCodeTwo) {
  std::string in = vdbwrap::testing::data_path("fuze.obj");
  EXPECT_EQ(run("wrap " + in + " -o " + (dir / "o.xyz").string()).code, 2);
  EXPECT_EQ(run("wrap " + in + " -o " + (dir / "o.stl").string() + " --base-size -3").code, 2);
  EXPECT_EQ(run("wrap " + in + " -o " + (dir / "o.stl").string() + " --levels 12").code, 2);
  EXPECT_EQ(run("wrap " + in + " -o " + (dir / "o.stl").string() + " --volume sideways").code, 2);
  EXPECT_EQ(run("wrap").code, 2);
  EXPECT_EQ(run("frobnicate").code, 2);
}

TEST_F(Cli, UnwritableOutputIsExitCodeFive) {
  // /proc is a folder no file can be created in: the path passes the early checks (as root) or
  // fails the writability check (as a user); either way the output is not written.
  CliRun r = run("wrap " + vdbwrap::testing::data_path("fuze.obj") + " -o /proc/vdbwrap_cli_test.stl --base-size 5%");
  EXPECT_EQ(r.code, 5) << r.err;
  EXPECT_NE(r.err.find("/proc/vdbwrap_cli_test.stl"), std::string::npos) << r.err;
}

TEST_F(Cli, MissingOutputFolderFailsBeforeTheWrap) {
  const std::string in = vdbwrap::testing::data_path("fuze.obj");
  const std::string ok_args = " --base-size 1.5% --threads 1";
  const fs::path out = dir / "o.stl";
  CliRun ok = run("wrap " + in + " -o " + out.string() + ok_args + " -q");
  ASSERT_EQ(ok.code, 0) << ok.err;
  fs::remove(out);
  const std::string missing = (dir / "no_such_folder").string();
  // Each output option names a file in a folder that does not exist: exit 2 at once, naming it.
  for (const std::string& bad :
       {" -o " + missing + "/o.stl", " -o " + out.string() + " --report " + missing + "/r.json",
        " -o " + out.string() + " --leak-path " + missing + "/leak.obj"}) {
    CliRun r = run("wrap " + in + bad + ok_args);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_NE(r.err.find(missing), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
    EXPECT_LT(r.seconds, ok.seconds / 2) << "the check comes before the wrap (" << ok.seconds << " s)";
    EXPECT_FALSE(fs::exists(out)) << bad;
    EXPECT_FALSE(fs::exists(out.string() + ".tmp")) << bad;
  }
  // Before the input is even read: a missing input with a missing output folder is a bad argument.
  EXPECT_EQ(run("wrap " + (dir / "nope.stl").string() + " -o " + missing + "/o.stl").code, 2);
  // repair and check likewise.
  CliRun rep = run("repair " + in + " -o " + missing + "/fixed.stl");
  EXPECT_EQ(rep.code, 2);
  EXPECT_NE(rep.err.find(missing), std::string::npos) << rep.err;
  CliRun rep_report = run("repair " + in + " -o " + (dir / "fixed.stl").string() + " --report " + missing + "/r.json");
  EXPECT_EQ(rep_report.code, 2);
  EXPECT_FALSE(fs::exists(dir / "fixed.stl"));
  CliRun chk = run("check " + in + " --report " + missing + "/c.json");
  EXPECT_EQ(chk.code, 2);
  EXPECT_NE(chk.err.find(missing), std::string::npos) << chk.err;
  // An output that names a folder is refused up front too.
  fs::create_directories(dir / "taken.stl");
  CliRun folder = run("wrap " + in + " -o " + (dir / "taken.stl").string());
  EXPECT_EQ(folder.code, 2);
  EXPECT_NE(folder.err.find("is a folder"), std::string::npos) << folder.err;
}

TEST_F(Cli, UnknownOptionsAndCommandsSuggestTheClosest) {
  const std::string in = vdbwrap::testing::data_path("fuze.obj"), out = (dir / "o.stl").string();
  CliRun typo = run("wrap " + in + " -o " + out + " --base-szie 2%");
  EXPECT_EQ(typo.code, 2);
  EXPECT_NE(typo.err.find("unknown option --base-szie; did you mean --base-size?"), std::string::npos) << typo.err;
  CliRun with_value = run("wrap " + in + " -o " + out + " --gap-closre=0.1");
  EXPECT_EQ(with_value.code, 2);
  EXPECT_NE(with_value.err.find("did you mean --gap-closure?"), std::string::npos) << with_value.err;
  CliRun single_dash = run("wrap " + in + " -o " + out + " -quiet");
  EXPECT_EQ(single_dash.code, 2);
  EXPECT_NE(single_dash.err.find("did you mean --quiet?"), std::string::npos) << single_dash.err;
  CliRun repair_typo = run("repair " + in + " -o " + out + " --max-deviaton 1%");
  EXPECT_EQ(repair_typo.code, 2);
  EXPECT_NE(repair_typo.err.find("did you mean --max-deviation?"), std::string::npos) << repair_typo.err;
  CliRun command = run("wrp " + in + " -o " + out);
  EXPECT_EQ(command.code, 2);
  EXPECT_NE(command.err.find("unknown command wrp; did you mean wrap?"), std::string::npos) << command.err;
  CliRun top = run("--verison");
  EXPECT_EQ(top.code, 2);
  EXPECT_NE(top.err.find("unknown option --verison; did you mean --version?"), std::string::npos) << top.err;
  // Nothing close: no guess, the valid names instead.
  CliRun far = run("frobnicate");
  EXPECT_EQ(far.code, 2);
  EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << far.err;
  EXPECT_NE(far.err.find("wrap, check, repair"), std::string::npos) << far.err;
  CliRun far_option = run("wrap " + in + " -o " + out + " --zzzzzzzz");
  EXPECT_EQ(far_option.code, 2);
  EXPECT_NE(far_option.err.find("unknown option --zzzzzzzz"), std::string::npos) << far_option.err;
  EXPECT_EQ(far_option.err.find("did you mean"), std::string::npos) << far_option.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(Suggest, EditDistanceCountsASwapAsOneEdit) {
  using vdbwrap::cli::closest_match;
  using vdbwrap::cli::edit_distance;
  EXPECT_EQ(edit_distance("size", "size"), 0u);
  EXPECT_EQ(edit_distance("szie", "size"), 1u);  // neighbours swapped
  EXPECT_EQ(edit_distance("levls", "levels"), 1u);
  EXPECT_EQ(edit_distance("", "wrap"), 4u);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  const std::vector<std::string> options = {"--levels", "--volume", "--report"};
  EXPECT_EQ(closest_match("--levles", options), std::optional<std::string>("--levels"));
  EXPECT_EQ(closest_match("--colour", options), std::nullopt);
}

TEST_F(Cli, HelpGroupsTheOptionsAndShowsExamples) {
  CliRun help = run("wrap --help");
  ASSERT_EQ(help.code, 0) << help.err;
  // Each group's heading, in this order, with an option of the group under it.
  const std::vector<std::pair<std::string, std::string>> groups = {{"Size:", "--base-size"},
                                                                   {"Volume:", "--gap-closure"},
                                                                   {"Features:", "--feature-angle"},
                                                                   {"Controls:", "--control-volume"},
                                                                   {"Output:", "--report"}};
  size_t at = 0;
  for (const auto& [heading, option] : groups) {
    const size_t h = help.out.find("\n" + heading, at);
    ASSERT_NE(h, std::string::npos) << heading << " missing or out of order:\n" << help.out;
    const size_t next = help.out.find(":\n", h + heading.size() + 2);
    EXPECT_LT(help.out.find(option, h), next) << option << " not under " << heading << ":\n" << help.out;
    at = h + 1;
  }
  const size_t examples = help.out.find("Examples:");
  ASSERT_NE(examples, std::string::npos) << help.out;
  size_t lines = 0;
  for (size_t p = help.out.find("  vdbwrap wrap ", examples); p != std::string::npos;
       p = help.out.find("  vdbwrap wrap ", p + 1))
    ++lines;
  EXPECT_GE(lines, 2u) << help.out;
  EXPECT_NE(run("--help").out.find("Examples:"), std::string::npos);
  EXPECT_NE(run("repair --help").out.find("Examples:"), std::string::npos);
}

TEST_F(Cli, InsideOfAnOpenSurfaceFailsClearly) {
  // A single triangle encloses nothing: --volume inside cannot produce a surface.
  CliRun r = run("wrap " + file("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n") + " -o " + (dir / "o.stl").string() +
                 " --volume inside");
  EXPECT_EQ(r.code, 4);
  EXPECT_NE(r.err.find("encloses no volume"), std::string::npos) << r.err;
}

TEST_F(Cli, LeakStopsWithExitFourAndStillWritesTheReportAndTheLeakPath) {
  const std::string in = (dir / "holed.obj").string();
  io::write_mesh(vdbwrap::testing::holed_cube(0.1), in);
  const std::string report = (dir / "r.json").string(), leak = (dir / "leak.obj").string();
  CliRun r = run("wrap " + in + " -o " + (dir / "o.obj").string() + " --volume 0.5,0.5,0.5 --report " + report +
                 " --leak-path " + leak);
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_NE(r.err.find("narrowest passage"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "o.obj")) << "no surface is written for a leaking volume";
  std::ifstream rep(report);
  std::string json((std::istreambuf_iterator<char>(rep)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"detected\": true"), std::string::npos) << json.substr(0, 400);
  EXPECT_NE(json.find("\"location\": ["), std::string::npos);
  Mesh marker = io::read_mesh(leak);
  EXPECT_EQ(marker.triangles.size(), 8u) << "the octahedron at the passage";

  // The same with a gap closure above the hole: wrapped.
  CliRun closed = run("wrap " + in + " -o " + (dir / "c.obj").string() + " --volume 0.5,0.5,0.5 --gap-closure 0.15");
  EXPECT_EQ(closed.code, 0) << closed.err;
}

TEST_F(Cli, ParameterFilesInJsonAndYamlAndTheCommandLineOverrides) {
  Mesh m;
  vdbwrap::testing::add_box(m, {0, 0, 0}, {1, 1, 1}, 0);
  vdbwrap::testing::add_box(m, {1.007, 0, 0}, {2.007, 1, 1}, 1);
  m.part_names = {"hot", "cold"};
  const std::string in = (dir / "parts.obj").string();
  io::write_mesh(m, in);
  const std::string yaml = file("p.yaml",
                                "# keep the two parts apart\n"
                                "base_size_percent: 1\n"
                                "levels: 1\n"
                                "contact_prevention:\n"
                                "  - groups:\n"
                                "      - parts: [hot, cold]\n"
                                "control_volumes:\n"
                                "  - shape: box\n"
                                "    a: {x: 0, y: 0, z: 0}\n"
                                "    b: {x: 0.2, y: 0.2, z: 0.2}\n"
                                "    size: {percent: 0.5}\n");
  const std::string out = (dir / "o.obj").string(), report = (dir / "r.json").string();
  CliRun r = run("wrap " + in + " -o " + out + " --params " + yaml + " --levels 2 --report " + report);
  ASSERT_EQ(r.code, 0) << r.err;
  Mesh wrapped = io::read_mesh(out);
  EXPECT_TRUE(vdbwrap::testing::valid_closed_surface(wrapped).ok);
  EXPECT_EQ(diagnose(wrapped, false).components, 2u) << "the file's contact prevention applied";
  ASSERT_EQ(wrapped.part_names.size(), 2u) << "part labels written as OBJ groups";
  std::ifstream rep(report);
  std::string json((std::istreambuf_iterator<char>(rep)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"levels\": 2"), std::string::npos) << "the command line overrides the file";
  EXPECT_NE(json.find("box:0,0,0,0.2,0.2,0.2:0.5%"), std::string::npos);

  const std::string good = file("p.json", R"({"base_size_percent": 2, "volume": "VOLUME_INSIDE", "levels": 0})");
  CliRun inside = run("wrap " + in + " -o " + (dir / "i.obj").string() + " --params " + good);
  EXPECT_EQ(inside.code, 0) << inside.err;

  const std::string typo = file("typo.json", R"({"base_size_percnt": 2})");
  CliRun bad = run("wrap " + in + " -o " + out + " --params " + typo);
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("typo.json"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("base_size_percnt"), std::string::npos) << bad.err;
  const std::string unknown_part = file("u.yaml", "contact_prevention: [{groups: [{parts: [hot, warm]}]}]\n");
  CliRun part = run("wrap " + in + " -o " + out + " --params " + unknown_part);
  EXPECT_EQ(part.code, 2);
  EXPECT_NE(part.err.find("warm"), std::string::npos) << part.err;
}

TEST_F(Cli, ReportsNameTheToolVersionTheInputFileAndItsParts) {
  Mesh m;
  vdbwrap::testing::add_box(m, {0, 0, 0}, {1, 1, 1}, 0);
  vdbwrap::testing::add_box(m, {2, 0, 0}, {3, 1, 1}, 1);
  vdbwrap::testing::add_box(m, {4, 0, 0}, {5, 1, 1}, 1);
  m.part_names = {"inlet", "housing"};
  const std::string in = (dir / "assembly.obj").string();
  io::write_mesh(m, in);
  // The version --version prints, without the program name.
  CliRun version = run("--version");
  ASSERT_EQ(version.code, 0);
  std::string expected_version = version.out.substr(version.out.find(' ') + 1);
  while (!expected_version.empty() && std::isspace(static_cast<unsigned char>(expected_version.back())))
    expected_version.pop_back();
  ASSERT_FALSE(expected_version.empty()) << version.out;
  auto expect_source = [&](const nlohmann::json& j, const std::string& what) {
    EXPECT_EQ(j.value("vdbwrap_version", ""), expected_version) << what;
    ASSERT_TRUE(j.contains("source")) << what;
    EXPECT_EQ(j["source"].value("file_name", ""), "assembly.obj") << what;
    const nlohmann::json& parts = j["source"]["parts"];
    ASSERT_EQ(parts.size(), 2u) << what;
    EXPECT_EQ(parts[0].value("name", ""), "inlet");
    EXPECT_EQ(parts[0].value("triangles", size_t(0)), 12u);
    EXPECT_EQ(parts[1].value("name", ""), "housing");
    EXPECT_EQ(parts[1].value("triangles", size_t(0)), 24u);
  };
  const fs::path report = dir / "r.json";
  CliRun r = run("wrap " + in + " -o " + (dir / "o.obj").string() + " --base-size 3% --report " + report.string());
  ASSERT_EQ(r.code, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(read_text(report));
  expect_source(j, "wrap");
  // The keys older readers use are all still there.
  for (const char* key :
       {"input", "features", "parameters", "grid", "volumes", "leak", "output", "stages", "total_seconds"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["input"].value("parts", size_t(0)), 2u);
  // A leaking seed point's report, written although the wrap stops.
  const std::string holed = (dir / "holed.obj").string();
  io::write_mesh(vdbwrap::testing::holed_cube(0.1), holed);
  fs::remove(report);
  CliRun leak =
      run("wrap " + holed + " -o " + (dir / "l.obj").string() + " --volume 0.5,0.5,0.5 --report " + report.string());
  EXPECT_EQ(leak.code, 4) << leak.err;
  nlohmann::json failed = nlohmann::json::parse(read_text(report));
  EXPECT_EQ(failed.value("vdbwrap_version", ""), expected_version);
  EXPECT_EQ(failed["source"].value("file_name", ""), "holed.obj");
  EXPECT_TRUE(failed["leak"].value("detected", false));
  // repair and check reports carry the same keys.
  ASSERT_EQ(run("repair " + in + " -o " + (dir / "f.obj").string() + " --report " + report.string()).code, 0);
  j = nlohmann::json::parse(read_text(report));
  expect_source(j, "repair");
  EXPECT_TRUE(j.contains("regions") && j.contains("all_fixed")) << j.dump();
  ASSERT_EQ(run("check " + in + " --report " + report.string()).code, 0);
  j = nlohmann::json::parse(read_text(report));
  expect_source(j, "check");
  EXPECT_TRUE(j.contains("diagnostics"));
}

TEST_F(Cli, OneOverallProgressFigureOnATerminal) {
  const std::string args =
      "wrap " + vdbwrap::testing::data_path("fuze.obj") + " -o " + (dir / "o.stl").string() + " --base-size 3%";
  CliRun tty = run_on_terminal(args);
  ASSERT_EQ(tty.code, 0) << tty.err;
  // One line redrawn in place: "[ 42%] project: ..." figures that only grow, ending at 100 %.
  const std::regex figure("\\r\x1b\\[K\\[ *([0-9]+)%\\] ([a-z ]+)");
  std::vector<int> figures;
  std::set<std::string> stages;
  for (auto it = std::sregex_iterator(tty.err.begin(), tty.err.end(), figure); it != std::sregex_iterator(); ++it) {
    figures.push_back(std::stoi((*it)[1]));
    stages.insert((*it)[2]);
  }
  ASSERT_GE(figures.size(), 5u) << tty.err;
  EXPECT_TRUE(std::is_sorted(figures.begin(), figures.end())) << tty.err;
  EXPECT_LT(figures.front(), 10) << tty.err;
  EXPECT_EQ(figures.back(), 100) << tty.err;
  EXPECT_GT(std::set<int>(figures.begin(), figures.end()).size(), 4u) << "the figure moves through the run";
  EXPECT_TRUE(stages.count("project")) << tty.err;
  EXPECT_FALSE(std::regex_search(tty.err, std::regex("\\[ *[0-9]+\\.[0-9]+s\\]")))
      << "no per-stage log lines on a terminal";
  EXPECT_NE(tty.err.find("wrote "), std::string::npos) << "the summary follows on its own line";
  // -q: nothing at all.
  CliRun quiet = run_on_terminal(args + " -q");
  ASSERT_EQ(quiet.code, 0);
  EXPECT_EQ(quiet.err.find('%'), std::string::npos) << quiet.err;
  EXPECT_EQ(quiet.err.find("wrote"), std::string::npos) << quiet.err;
  // Not a terminal (a log file): one line per stage message with the elapsed time, as before.
  CliRun log = run(args);
  ASSERT_EQ(log.code, 0) << log.err;
  EXPECT_TRUE(std::regex_search(log.err, std::regex("\\[ *[0-9]+\\.[0-9]+s\\] project"))) << log.err;
  EXPECT_EQ(log.err.find('\r'), std::string::npos);
}

// ---- repair ---------------------------------------------------------------------------

TEST_F(Cli, RepairFixesADentAndReportsIt) {
  Mesh m = vdbwrap::testing::cylinder_mesh({0, 0, 0}, 1.0, 0.02, 128);
  m.points[1][2] = -0.004;  // the top hub through the bottom
  std::string in = (dir / "dent.obj").string();
  io::write_mesh(m, in);
  CliRun r = run("repair " + in + " -o " + (dir / "fixed.stl").string() + " --report " + (dir / "r.json").string());
  ASSERT_EQ(r.code, 0) << r.err;
  Mesh out = io::read_mesh((dir / "fixed.stl").string());  // single precision, as written
  EXPECT_EQ(diagnose(out).intersecting_pairs, 0u);
  std::string json = read_text(dir / "r.json");
  EXPECT_NE(json.find("\"all_fixed\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"found\": 1"), std::string::npos);
  EXPECT_NE(json.find("\"left_unfixed\": 0"), std::string::npos);
  EXPECT_NE(json.find("max_deviation_fraction_of_diagonal"), std::string::npos);
}

TEST_F(Cli, RepairWithIntersectionsLeftExitsFourAndStillWrites) {
  // Two open sheets crossing edge to edge: the crossing runs into both borders, beyond repair.
  Mesh m = vdbwrap::testing::crossing_sheets();
  std::string in = (dir / "sheets.ply").string();
  io::write_mesh(m, in);
  CliRun r = run("repair " + in + " -o " + (dir / "out.ply").string() + " --report " + (dir / "r.json").string());
  EXPECT_EQ(r.code, 4) << r.err;
  Mesh out = io::read_mesh((dir / "out.ply").string());
  EXPECT_EQ(out.part_names.size(), 2u);
  std::string json = read_text(dir / "r.json");
  EXPECT_NE(json.find("\"all_fixed\": false"), std::string::npos) << json;
  EXPECT_NE(json.find("\"left_unfixed\": 1"), std::string::npos) << json;
  EXPECT_NE(json.find("\"center\""), std::string::npos) << json;  // where the unfixed region is
}

TEST_F(Cli, RepairErrors) {
  CliRun missing = run("repair " + (dir / "nope.stl").string() + " -o " + (dir / "o.stl").string());
  EXPECT_EQ(missing.code, 3);
  EXPECT_NE(missing.err.find("nope.stl"), std::string::npos) << missing.err;
  EXPECT_EQ(run("repair " + file("empty.stl", "") + " -o " + (dir / "o.stl").string()).code, 3);
  std::string in = vdbwrap::testing::data_path("fuze.obj");
  EXPECT_EQ(run("repair " + in + " -o " + (dir / "o.xyz").string()).code, 2);
  EXPECT_EQ(run("repair " + in + " -o " + (dir / "o.stl").string() + " --max-deviation -1").code, 2);
  EXPECT_EQ(run("repair " + in + " -o " + (dir / "o.stl").string() + " --area-ratio 2").code, 2);
  EXPECT_EQ(run("repair " + in).code, 2);                               // no output
  CliRun ok = run("repair " + in + " -o " + (dir / "o.obj").string());  // clean: nothing to do
  EXPECT_EQ(ok.code, 0) << ok.err;
}

// --stl ascii|binary: the same mesh in either encoding (STL output is validated in single
// precision whichever it is), and binary even where the default would be ASCII (several parts).
TEST_F(Cli, StlEncodingOptionWritesAsciiOrBinaryOfOneMesh) {
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  auto triangles_by_coordinates = [](const Mesh& m) {
    std::multiset<std::array<Vec3, 3>> out;
    for (const Tri& t : m.triangles) out.insert({m.points[t[0]], m.points[t[1]], m.points[t[2]]});
    return out;
  };
  const std::string fuze = std::string(VDBWRAP_TEST_DATA_DIR) + "/fuze.obj";
  const fs::path ascii = dir / "ascii.stl", binary = dir / "binary.stl";
  CliRun a = run("wrap " + fuze + " -o " + ascii.string() + " --base-size 3% --no-distances -q --stl ascii");
  ASSERT_EQ(a.code, 0) << a.err;
  CliRun b = run("wrap " + fuze + " -o " + binary.string() + " --base-size 3% --no-distances -q --stl binary");
  ASSERT_EQ(b.code, 0) << b.err;
  const std::string ascii_text = slurp(ascii), binary_bytes = slurp(binary);
  EXPECT_EQ(ascii_text.rfind("solid", 0), 0u);
  EXPECT_NE(ascii_text.find("facet normal"), std::string::npos);
  const Mesh from_ascii = io::read_mesh(ascii.string()), from_binary = io::read_mesh(binary.string());
  ASSERT_GT(from_binary.triangles.size(), 0u);
  EXPECT_EQ(binary_bytes.size(), 84 + 50 * from_binary.triangles.size()) << "not a binary STL";
  EXPECT_EQ(from_ascii.points, from_binary.points);
  EXPECT_EQ(from_ascii.triangles, from_binary.triangles);

  // Several parts: ASCII (the default) keeps them as solids; --stl binary drops the names but
  // holds the same triangles.
  const std::string parts = std::string(VDBWRAP_TEST_DATA_DIR) + "/two_objects_mixed_case_names.stl";
  const fs::path solids = dir / "solids.stl", plain = dir / "plain.stl";
  ASSERT_EQ(run("wrap " + parts + " -o " + solids.string() + " --base-size 3% --no-distances -q").code, 0);
  CliRun p = run("wrap " + parts + " -o " + plain.string() + " --base-size 3% --no-distances -q --stl binary");
  ASSERT_EQ(p.code, 0) << p.err;
  const Mesh with_names = io::read_mesh(solids.string()), without = io::read_mesh(plain.string());
  EXPECT_GT(with_names.part_names.size(), 1u);
  EXPECT_LE(without.part_names.size(), 1u);
  EXPECT_EQ(slurp(plain).size(), 84 + 50 * without.triangles.size());
  EXPECT_EQ(triangles_by_coordinates(with_names), triangles_by_coordinates(without));

  // repair takes it too; a value or an output it does not fit is exit code 2 before any work.
  CliRun r = run("repair " + fuze + " -o " + (dir / "r.stl").string() + " -q --stl ascii");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(dir / "r.stl").rfind("solid", 0), 0u);
  CliRun bad = run("wrap " + fuze + " -o " + (dir / "x.stl").string() + " -q --stl text");
  EXPECT_EQ(bad.code, 2);
  CliRun obj = run("wrap " + fuze + " -o " + (dir / "x.obj").string() + " -q --stl ascii");
  EXPECT_EQ(obj.code, 2);
  EXPECT_NE(obj.err.find("not an .stl file"), std::string::npos) << obj.err;
  EXPECT_FALSE(fs::exists(dir / "x.obj"));
}
