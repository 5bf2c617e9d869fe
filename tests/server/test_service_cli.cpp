// The CLI's remote mode against real servers: submit, wait, jobs, cancel, delete, output
// folders, environment defaults, round robin, exit codes.
#include "service_harness.h"

using namespace server_test;

namespace {

// --- the CLI's remote mode ------------------------------------------------------------

TEST_F(Service, CliSubmitDownloadsTheResult) {
  ServerProcess& s = server({"--workers", "2"});
  const fs::path out = dir_ / "fuze_remote.stl", report = dir_ / "fuze_remote.json";
  CliRun r = cli("submit --server " + s.address() + " " + vdbwrap::testing::data_path("fuze.obj") + " -o " +
                 out.string() + " --base-size 3% --report " + report.string());
  ASSERT_EQ(r.code, 0) << r.err;
  expect_valid_result(read_file(out), vdbwrap::io::Format::Stl, "fuze_remote.stl");
  EXPECT_NE(read_file(report).find("\"valid_closed_surface\": true"), std::string::npos);
  EXPECT_NE(r.err.find("project"), std::string::npos) << "progress lines expected:\n" << r.err;
  // Several inputs at once into a folder.
  fs::create_directories(dir_ / "outs");
  r = cli("submit --server " + s.address() + " " + vdbwrap::testing::data_path("unit_sphere.STL") + " " +
          vdbwrap::testing::data_path("two_objects_mixed_case_names.stl") + " --out-dir " + (dir_ / "outs").string() +
          " --base-size 3% --format ply -q");
  ASSERT_EQ(r.code, 0) << r.err;
  expect_valid_result(read_file(dir_ / "outs" / "unit_sphere_wrap.ply"), vdbwrap::io::Format::Ply, "sphere");
  expect_valid_result(read_file(dir_ / "outs" / "two_objects_mixed_case_names_wrap.ply"), vdbwrap::io::Format::Ply,
                      "two");
  EXPECT_TRUE(fs::exists(dir_ / "outs" / "unit_sphere_wrap.json"));
}

TEST_F(Service, RemoteLeakKeepsTheReportAndTheLeakPathAndParamsFilesWork) {
  ServerProcess& s = server({"--workers", "1"});
  const fs::path in = dir_ / "holed.obj", report = dir_ / "leak.json", leak = dir_ / "leak.obj";
  vdbwrap::io::write_mesh(vdbwrap::testing::holed_cube(0.1), in.string());
  CliRun r = cli("submit --server " + s.address() + " " + in.string() + " -o " + (dir_ / "o.obj").string() +
                 " --volume 0.5,0.5,0.5 --report " + report.string() + " --leak-path " + leak.string() + " -q");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_NE(r.err.find("leak"), std::string::npos) << r.err;
  EXPECT_NE(read_file(report).find("\"detected\": true"), std::string::npos);
  EXPECT_EQ(vdbwrap::io::read_mesh(leak.string()).triangles.size(), 8u);
  // The same job with a gap closure from a parameter file: wrapped on the server.
  write_file(dir_ / "p.yaml",
             "volume: seed_points\nseed_points: [{x: 0.5, y: 0.5, z: 0.5}]\ngap_closure: {model_units: 0.15}\n");
  r = cli("submit --server " + s.address() + " " + in.string() + " -o " + (dir_ / "c.ply").string() + " --params " +
          (dir_ / "p.yaml").string() + " -q");
  ASSERT_EQ(r.code, 0) << r.err;
  expect_valid_result(read_file(dir_ / "c.ply"), vdbwrap::io::Format::Ply, "inside of the holed cube");
}

TEST_F(Service, CliDetachWaitJobsCancel) {
  ServerProcess& s = server({"--workers", "1"});
  CliRun r = cli("submit --server " + s.address() + " --detach " +
                 vdbwrap::testing::data_path("two_objects_mixed_case_names.stl") + " " +
                 vdbwrap::testing::data_path("unit_sphere.STL") + " --base-size 3%");
  ASSERT_EQ(r.code, 0) << r.err;
  std::istringstream lines(r.out);
  std::vector<std::string> ids;
  for (std::string line; std::getline(lines, line);) ids.push_back(line);
  ASSERT_EQ(ids.size(), 2u) << r.out;
  CliRun listed = cli("jobs --server " + s.address());
  ASSERT_EQ(listed.code, 0) << listed.err;
  for (auto& id : ids) EXPECT_NE(listed.out.find(id), std::string::npos);
  fs::create_directories(dir_ / "w");
  CliRun waited =
      cli("wait --server " + s.address() + " " + ids[0] + " " + ids[1] + " --out-dir " + (dir_ / "w").string());
  ASSERT_EQ(waited.code, 0) << waited.err;
  expect_valid_result(read_file(dir_ / "w" / "two_objects_mixed_case_names_wrap.stl"), vdbwrap::io::Format::Stl, "two");
  expect_valid_result(read_file(dir_ / "w" / "unit_sphere_wrap.stl"), vdbwrap::io::Format::Stl, "sphere");
  // cancel
  CliRun slow_job = cli("submit --server " + s.address() + " --detach " + vdbwrap::testing::data_path("fuze.obj") +
                        " --base-size 0.5% --threads 1 --no-features");
  ASSERT_EQ(slow_job.code, 0) << slow_job.err;
  std::string slow_id = slow_job.out.substr(0, 32);
  CliRun cancelled = cli("cancel --server " + s.address() + " " + slow_id);
  EXPECT_EQ(cancelled.code, 0) << cancelled.err;
  Client c(s.address());
  EXPECT_EQ(c.wait_done(slow_id, 30s).state(), pb::JOB_STATE_CANCELLED);
  // wait on a cancelled job exits like a cancelled wrap (6).
  CliRun w2 = cli("wait --server " + s.address() + " " + slow_id + " --out-dir " + (dir_ / "w").string());
  EXPECT_EQ(w2.code, 6) << w2.err;
}

TEST_F(Service, CliOutputFoldersAndEnvironmentDefaults) {
  const fs::path token = dir_ / "token";
  write_file(token, "tok");
  ServerProcess& s = server({"--token-file", token.string()});
  // The server and the token from the environment, no --server or --token-file.
  const std::string env = "VDBWRAP_SERVER=" + s.address() + " VDBWRAP_TOKEN_FILE=" + token.string();
  const std::string sphere = vdbwrap::testing::data_path("unit_sphere.STL");
  // -o in a missing folder: refused before anything is uploaded.
  const fs::path missing = dir_ / "no_such_folder";
  CliRun early = cli("submit " + sphere + " -o " + (missing / "o.stl").string() + " --base-size 3%", env);
  EXPECT_EQ(early.code, 2) << early.err;
  EXPECT_NE(early.err.find(missing.string()), std::string::npos) << early.err;
  CliRun early_report =
      cli("submit " + sphere + " -o " + (dir_ / "o.stl").string() + " --report " + (missing / "r.json").string(), env);
  EXPECT_EQ(early_report.code, 2) << early_report.err;
  EXPECT_EQ(s.jobs_on_disk(), 0u) << "nothing uploaded";
  // --out-dir is created, parents included.
  const fs::path outs = dir_ / "results" / "today";
  CliRun r = cli("submit " + sphere + " --out-dir " + outs.string() + " --base-size 3% -q", env);
  ASSERT_EQ(r.code, 0) << r.err;
  expect_valid_result(read_file(outs / "unit_sphere_wrap.stl"), vdbwrap::io::Format::Stl, "sphere into a new folder");
  EXPECT_TRUE(fs::exists(outs / "unit_sphere_wrap.json"));
  // wait's --out-dir too.
  CliRun detached = cli("submit --detach " + sphere + " --base-size 3%", env);
  ASSERT_EQ(detached.code, 0) << detached.err;
  const std::string id = detached.out.substr(0, 32);
  CliRun waited = cli("wait " + id + " --out-dir " + (dir_ / "waited").string() + " -q", env);
  ASSERT_EQ(waited.code, 0) << waited.err;
  EXPECT_TRUE(fs::exists(dir_ / "waited" / "unit_sphere_wrap.stl"));
  // A file where the folder should be: a bad argument.
  write_file(dir_ / "a_file", "x");
  CliRun blocked = cli("wait " + id + " --out-dir " + (dir_ / "a_file").string() + " -q", env);
  EXPECT_EQ(blocked.code, 2) << blocked.err;
  // The environment is what made these calls work: without the token the server refuses.
  CliRun no_token = cli("jobs --server " + s.address());
  EXPECT_EQ(no_token.code, 2);
  EXPECT_NE(no_token.err.find("UNAUTHENTICATED"), std::string::npos) << no_token.err;
  // Options given on the command line win over the environment.
  CliRun explicit_server =
      cli("jobs --server " + s.address(), "VDBWRAP_SERVER=127.0.0.1:1 VDBWRAP_TOKEN_FILE=" + token.string());
  EXPECT_EQ(explicit_server.code, 0) << explicit_server.err;
  EXPECT_NE(explicit_server.out.find(id), std::string::npos);
  // A token file in the environment that does not exist: named when a remote command needs
  // it, no concern of the local commands.
  CliRun missing_token = cli("jobs --server " + s.address(), "VDBWRAP_TOKEN_FILE=" + (dir_ / "nope").string());
  EXPECT_EQ(missing_token.code, 2);
  EXPECT_NE(missing_token.err.find((dir_ / "nope").string()), std::string::npos) << missing_token.err;
  CliRun local =
      cli("check " + sphere, "VDBWRAP_TOKEN_FILE=" + (dir_ / "nope").string() + " VDBWRAP_SERVER=127.0.0.1:1");
  EXPECT_EQ(local.code, 0) << local.err;
  // Neither: --server is required.
  CliRun none = cli("jobs");
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("--server"), std::string::npos) << none.err;
}

TEST_F(Service, CliDeletesEndedJobsAndListsJobsAsJson) {
  ServerProcess& s = server({"--workers", "1"});
  Client c(s.address());
  const std::string done = c.submit_ok("unit_sphere.STL");
  const pb::JobStatus done_status = c.wait_done(done);
  ASSERT_EQ(done_status.state(), pb::JOB_STATE_SUCCEEDED);
  const std::string running = c.submit_ok("fuze.obj", slow());
  c.poll(
      running, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING; }, 30s);
  const std::string at = " --server " + s.address();

  CliRun listed = cli("jobs --json" + at);
  ASSERT_EQ(listed.code, 0) << listed.err;
  const nlohmann::json jobs = nlohmann::json::parse(listed.out);
  ASSERT_TRUE(jobs.is_array());
  ASSERT_EQ(jobs.size(), 2u) << listed.out;
  std::map<std::string, nlohmann::json> by_id;
  for (const auto& j : jobs) by_id[j.value("id", "")] = j;
  ASSERT_TRUE(by_id.count(done) && by_id.count(running)) << listed.out;
  EXPECT_EQ(by_id[done].value("state", ""), "succeeded");
  EXPECT_EQ(by_id[done].value("kind", ""), "wrap");
  EXPECT_EQ(by_id[done].value("file_name", ""), "unit_sphere.STL");
  EXPECT_EQ(by_id[done].value("output_triangles", uint64_t(0)), done_status.output_triangles());
  EXPECT_EQ(by_id[done].value("error_kind", "x"), "");
  EXPECT_EQ(by_id[running].value("state", ""), "running");
  EXPECT_EQ(by_id[running].value("file_name", ""), "fuze.obj");

  // A running job is not deleted: the server's FAILED_PRECONDITION, exit 2, the job stays.
  CliRun refused = cli("delete" + at + " " + running);
  EXPECT_EQ(refused.code, 2) << refused.err;
  EXPECT_NE(refused.err.find("FAILED_PRECONDITION"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("cancel it first"), std::string::npos) << refused.err;
  EXPECT_EQ(s.jobs_on_disk(), 2u);
  // An ended job goes, with its files.
  CliRun deleted = cli("delete" + at + " " + done);
  EXPECT_EQ(deleted.code, 0) << deleted.err;
  EXPECT_EQ(s.jobs_on_disk(), 1u);
  pb::JobStatus gone;
  EXPECT_EQ(c.status(done, gone).error_code(), grpc::StatusCode::NOT_FOUND);
  CliRun again = cli("delete" + at + " " + done);
  EXPECT_EQ(again.code, 2) << "an unknown job is a bad argument";
  // Cancelled, then deleted: the spool is empty and the list too.
  ASSERT_EQ(cli("cancel" + at + " " + running).code, 0);
  EXPECT_EQ(c.wait_done(running, 30s).state(), pb::JOB_STATE_CANCELLED);
  CliRun cancelled_gone = cli("delete" + at + " " + running);
  EXPECT_EQ(cancelled_gone.code, 0) << cancelled_gone.err;
  EXPECT_EQ(s.jobs_on_disk(), 0u);
  CliRun empty = cli("jobs --json" + at);
  ASSERT_EQ(empty.code, 0);
  EXPECT_EQ(nlohmann::json::parse(empty.out), nlohmann::json::array());
}

TEST_F(Service, CliRoundRobinSpreadsAndFollowsEachJob) {
  std::vector<ServerProcess*> servers;
  for (const char* name : {"a", "b"}) servers.push_back(&server({"--workers", "1"}, name));
  const std::string target =
      "ipv4:127.0.0.1:" + std::to_string(servers[0]->port()) + ",127.0.0.1:" + std::to_string(servers[1]->port());
  fs::create_directories(dir_ / "rr");
  std::string inputs;
  for (const char* n : {"two_objects_mixed_case_names.stl", "unit_sphere.STL", "fuze.obj", "multibody.stl"})
    inputs += " " + vdbwrap::testing::data_path(n);
  CliRun r = cli("submit --server " + target + " --round-robin" + inputs + " --out-dir " + (dir_ / "rr").string() +
                 " --base-size 5% -q");
  ASSERT_EQ(r.code, 0) << r.err;
  expect_valid_result(read_file(dir_ / "rr" / "fuze_wrap.obj"), vdbwrap::io::Format::Obj, "fuze");
  expect_valid_result(read_file(dir_ / "rr" / "multibody_wrap.stl"), vdbwrap::io::Format::Stl, "multibody");
  EXPECT_EQ(servers[0]->jobs_on_disk() + servers[1]->jobs_on_disk(), 4u);
  EXPECT_GT(servers[0]->jobs_on_disk(), 0u);
  EXPECT_GT(servers[1]->jobs_on_disk(), 0u);
}

TEST_F(Service, CliWaitSurvivesAServerCrashAndRestart) {
  ServerProcess& s = server({"--workers", "1"});
  CliRun r = cli("submit --server " + s.address() + " --detach " + vdbwrap::testing::data_path("fuze.obj") +
                 " --base-size 0.5% --threads 1 --no-features");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string id = r.out.substr(0, 32);
  fs::create_directories(dir_ / "w");
  auto waiter = std::async(std::launch::async, [&] {
    return cli("wait --server " + s.address() + " " + id + " --out-dir " + (dir_ / "w").string() + " --retry 60");
  });
  Client c(s.address());
  c.poll(
      id, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING && st.stage() != "read"; }, 30s);
  EXPECT_EQ(s.kill(SIGKILL), 128 + SIGKILL);
  s.set_listen(s.address());  // same address: the waiting CLI reconnects
  s.start();
  ASSERT_EQ(waiter.wait_for(180s), std::future_status::ready);
  CliRun w = waiter.get();
  EXPECT_EQ(w.code, 0) << w.err;
  expect_valid_result(read_file(dir_ / "w" / "fuze_wrap.obj"), vdbwrap::io::Format::Obj, "fuze after restart");
}

// The long options (--name) a command's help text lists.
std::set<std::string> long_options(const std::string& help) {
  std::set<std::string> out;
  const std::regex opt("--[a-z][a-z0-9-]+");
  for (auto it = std::sregex_iterator(help.begin(), help.end(), opt); it != std::sregex_iterator(); ++it)
    out.insert(it->str());
  return out;
}

// Outputs only a local run writes: the server sends the result mesh and the JSON report, not
// the defect flags, the feature curves or the STL encoding these need (docs/cli.md, submit).
const std::set<std::string> kLocalOutputs = {"--deviation", "--features", "--html", "--stl"};

TEST_F(Service, CliSubmitTakesEveryWrapOption) {
  // `submit` mirrors `wrap`: every long option of one is an option of the other.
  CliRun wrap_help = cli("wrap --help");
  CliRun submit_help = cli("submit --help");
  std::set<std::string> wrap_options = long_options(wrap_help.out), submit_options = long_options(submit_help.out);
  ASSERT_GT(wrap_options.size(), 5u) << wrap_help.out;
  for (const auto& o : wrap_options)
    if (!kLocalOutputs.count(o)) EXPECT_TRUE(submit_options.count(o)) << "submit lacks wrap's " << o;
}

TEST_F(Service, CliSubmitRepairRunsTheRepairOnTheServer) {
  // `submit --repair` takes every option of `vdbwrap repair`, and gives its exit codes.
  const std::set<std::string> repair_options = long_options(cli("repair --help").out),
                              submit_options = long_options(cli("submit --help").out);
  ASSERT_GT(repair_options.size(), 10u);
  for (const auto& o : repair_options)
    if (!kLocalOutputs.count(o)) EXPECT_TRUE(submit_options.count(o)) << "submit lacks repair's " << o;

  ServerProcess& s = server({"--workers", "1"});
  const fs::path folded = dir_ / "folded.obj", out = dir_ / "fixed.obj", report = dir_ / "fixed.json";
  vdbwrap::io::write_mesh(vdbwrap::testing::folded_icosphere(), folded.string());
  CliRun r = cli("submit --repair --server " + s.address() + " " + folded.string() + " -o " + out.string() +
                 " --report " + report.string() + " --max-deviation 5% --alpha 0.3");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(vdbwrap::diagnose(vdbwrap::io::read_mesh(out.string()), true).intersecting_pairs, 0u);
  EXPECT_NE(read_file(report).find("\"all_fixed\": true"), std::string::npos);
  EXPECT_NE(read_file(report).find("\"alpha\": 0.3"), std::string::npos) << "the options reach the server";
  // Intersections left: the result and the report are written, exit code 4 (as `vdbwrap repair`).
  // (Two open sheets crossing edge to edge: nothing to cap, no bodies to unite.)
  const fs::path crossing = dir_ / "sheets.obj";
  vdbwrap::io::write_mesh(vdbwrap::testing::crossing_sheets(), crossing.string());
  fs::create_directories(dir_ / "outs");
  r = cli("submit --repair --server " + s.address() + " " + crossing.string() + " --out-dir " +
          (dir_ / "outs").string() + " -q");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "outs" / "sheets_repaired.obj"));
  EXPECT_TRUE(fs::exists(dir_ / "outs" / "sheets_repaired.json"));
  EXPECT_NE(r.err.find("intersecting pairs left"), std::string::npos) << r.err;
  // One kind's options with the other kind: refused before anything is sent.
  r = cli("submit --repair --server " + s.address() + " " + folded.string() + " -o " + out.string() +
          " --base-size 1%");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--base-size"), std::string::npos) << r.err;
  r = cli("submit --server " + s.address() + " " + folded.string() + " -o " + out.string() + " --alpha 0.3");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--repair"), std::string::npos) << r.err;
  r = cli("submit --repair --server " + s.address() + " " + folded.string() + " -o " + out.string() +
          " --area-ratio 1.5");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(s.jobs_on_disk(), 2u);
}

TEST_F(Service, CliExitCodesMatchTheLocalWrap) {
  write_file(dir_ / "token", "tok");
  ServerProcess& s = server({"--token-file", (dir_ / "token").string()});
  write_file(dir_ / "garbage.stl", std::string(3000, '\x01'));
  const std::string token = " --token-file " + (dir_ / "token").string();
  CliRun bad_input = cli("submit --server " + s.address() + token + " " + (dir_ / "garbage.stl").string() + " -o " +
                         (dir_ / "o.stl").string());
  EXPECT_EQ(bad_input.code, 3) << bad_input.err;
  CliRun bad_levels = cli("submit --server " + s.address() + token + " " + vdbwrap::testing::data_path("fuze.obj") +
                          " -o " + (dir_ / "o.stl").string() + " --levels 9");
  EXPECT_EQ(bad_levels.code, 2) << bad_levels.err;
  CliRun bad_output = cli("submit --server " + s.address() + token + " " + vdbwrap::testing::data_path("fuze.obj") +
                          " -o " + (dir_ / "o.xyz").string());
  EXPECT_EQ(bad_output.code, 2) << bad_output.err;
  CliRun no_token = cli("jobs --server " + s.address());
  EXPECT_EQ(no_token.code, 2) << no_token.err;
  EXPECT_NE(no_token.err.find("UNAUTHENTICATED"), std::string::npos) << no_token.err;
  CliRun unknown = cli("wait --server " + s.address() + token + " " + std::string(32, 'c'));
  EXPECT_EQ(unknown.code, 2) << unknown.err;
  EXPECT_EQ(s.jobs_on_disk(), 0u);
}

}  // namespace
