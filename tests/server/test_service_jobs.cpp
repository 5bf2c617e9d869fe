// The job service through its gRPC API: wraps and repairs, progress, cancellation, queue
// limits, restarts, bad uploads, tokens, health, idempotency, several servers, TLS.
#include "service_harness.h"

using namespace server_test;

namespace {

TEST_F(Service, RepairJobRepairsAnUploadedMesh) {
  ServerProcess& s = server({"--workers", "1"});
  Client c(s.address());
  const vdbwrap::Mesh folded = vdbwrap::testing::folded_icosphere();
  const vdbwrap::MeshDiagnostics before = vdbwrap::diagnose(folded, true);
  ASSERT_GT(before.intersecting_pairs, 0u);
  const std::string bytes = vdbwrap::io::write_mesh_to_bytes(folded, vdbwrap::io::Format::Obj);
  pb::JobSpec spec;
  spec.set_file_name("folded.obj");
  spec.set_kind(pb::JOB_KIND_REPAIR);
  spec.set_output_format(pb::MESH_FORMAT_OBJ);
  spec.mutable_repair_params()->mutable_max_deviation()->set_percent(5);
  SubmitOutcome o = c.submit_spec(bytes, spec);
  ASSERT_TRUE(o.status.ok()) << o.status.error_message();
  const pb::JobStatus st = c.wait_done(o.job_id);
  ASSERT_EQ(st.state(), pb::JOB_STATE_SUCCEEDED) << st.error_message();
  EXPECT_EQ(st.spec().kind(), pb::JOB_KIND_REPAIR);
  EXPECT_EQ(st.intersecting_pairs_left(), 0u);
  EXPECT_NE(st.report_json().find("\"all_fixed\": true"), std::string::npos) << st.report_json();
  EXPECT_NE(st.report_json().find("\"fixed_by_local_operations\""), std::string::npos);
  EXPECT_EQ(st.report_json().find("\"quality\""), std::string::npos) << "a repair's report, not a wrap's";
  // The tool and the input, as in `vdbwrap repair --report`.
  const nlohmann::json repair_report = nlohmann::json::parse(st.report_json());
  EXPECT_EQ(repair_report.value("vdbwrap_version", ""), vdbwrap::version());
  EXPECT_EQ(repair_report["source"].value("file_name", ""), "folded.obj");
  ASSERT_EQ(repair_report["source"]["parts"].size(), 1u);
  EXPECT_EQ(repair_report["source"]["parts"][0].value("triangles", size_t(0)), folded.triangles.size());
  std::string result;
  ASSERT_TRUE(c.download(st.job_id(), result).ok());
  const vdbwrap::MeshDiagnostics after =
      vdbwrap::diagnose(vdbwrap::io::read_mesh_from_bytes(result, vdbwrap::io::Format::Obj, "r"), true);
  EXPECT_LT(after.intersecting_pairs, before.intersecting_pairs);
  EXPECT_EQ(after.intersecting_pairs, 0u);
  EXPECT_TRUE(after.valid_closed_surface());
  EXPECT_EQ(after.triangles, folded.triangles.size()) << "a local repair: no re-wrap";
  // As STL (single precision): converted on download, still free of intersections.
  ASSERT_TRUE(c.download(st.job_id(), result, pb::MESH_FORMAT_STL).ok());
  EXPECT_EQ(vdbwrap::diagnose(vdbwrap::io::read_mesh_from_bytes(result, vdbwrap::io::Format::Stl, "r"), true)
                .intersecting_pairs,
            0u);

  // Two open sheets crossing edge to edge: beyond repair (nothing to cap). The job succeeds
  // with the result written and says how many pairs are left.
  spec.set_file_name("sheets.obj");
  o = c.submit_spec(vdbwrap::io::write_mesh_to_bytes(vdbwrap::testing::crossing_sheets(), vdbwrap::io::Format::Obj),
                    spec);
  ASSERT_TRUE(o.status.ok()) << o.status.error_message();
  const pb::JobStatus left = c.wait_done(o.job_id);
  ASSERT_EQ(left.state(), pb::JOB_STATE_SUCCEEDED) << left.error_message();
  EXPECT_GT(left.intersecting_pairs_left(), 0u);
  EXPECT_NE(left.report_json().find("\"all_fixed\": false"), std::string::npos);
  EXPECT_TRUE(c.download(left.job_id(), result).ok());

  // Parameters of the other kind, or out of range: refused on arrival.
  pb::JobSpec mixed = spec;
  mixed.mutable_params()->set_levels(2);
  o = c.submit_spec(bytes, mixed);
  EXPECT_EQ(o.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(o.error_kind, "2");
  EXPECT_NE(o.status.error_message().find("params"), std::string::npos) << o.status.error_message();
  pb::JobSpec bad_alpha = spec;
  bad_alpha.mutable_repair_params()->set_alpha(2);
  o = c.submit_spec(bytes, bad_alpha);
  EXPECT_EQ(o.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(o.status.error_message().find("alpha"), std::string::npos) << o.status.error_message();
  EXPECT_EQ(s.jobs_on_disk(), 2u);
}

TEST_F(Service, ConcurrentSubmissionsGiveValidResults) {
  ServerProcess& s = server({"--workers", "2"});
  const std::vector<std::string> names = {"fuze.obj", "unit_sphere.STL", "two_objects_mixed_case_names.stl"};
  std::vector<std::string> ids(names.size());
  std::vector<std::thread> threads;
  for (size_t i = 0; i < names.size(); ++i)
    threads.emplace_back([&, i] {
      Client c(s.address());
      ids[i] = c.submit_ok(names[i]);
    });
  for (auto& t : threads) t.join();
  Client c(s.address());
  for (size_t i = 0; i < names.size(); ++i) {
    ASSERT_EQ(ids[i].size(), 32u);
    pb::JobStatus st = c.wait_done(ids[i]);
    ASSERT_EQ(st.state(), pb::JOB_STATE_SUCCEEDED) << names[i] << ": " << st.error_message();
    EXPECT_NE(st.report_json().find("\"valid_closed_surface\": true"), std::string::npos);
    EXPECT_NE(st.report_json().find("distance_output_to_input"), std::string::npos);
    EXPECT_GT(st.output_triangles(), 0u);
    // The tool and the input, as in `vdbwrap wrap --report`.
    const nlohmann::json report = nlohmann::json::parse(st.report_json());
    EXPECT_EQ(report.value("vdbwrap_version", ""), vdbwrap::version());
    EXPECT_EQ(report["source"].value("file_name", ""), names[i]);
    size_t source_triangles = 0;
    for (const auto& part : report["source"]["parts"]) source_triangles += part.value("triangles", size_t(0));
    EXPECT_EQ(source_triangles, report["input"].value("triangles", size_t(1) << 40)) << names[i];
    std::string bytes;
    ASSERT_TRUE(c.download(ids[i], bytes).ok());
    // The result comes in the input's format by default.
    expect_valid_result(bytes, vdbwrap::io::format_from_extension(names[i]), names[i]);
    // And in any other format on request.
    std::string obj;
    ASSERT_TRUE(c.download(ids[i], obj, pb::MESH_FORMAT_OBJ).ok());
    vdbwrap::Mesh m = vdbwrap::io::read_mesh_from_bytes(obj, vdbwrap::io::Format::Obj, "obj");
    EXPECT_EQ(m.triangles.size(), st.output_triangles());
  }
  std::set<std::string> distinct(ids.begin(), ids.end());
  EXPECT_EQ(distinct.size(), ids.size());
  pb::ListReply list;
  ASSERT_TRUE(c.list(list).ok());
  EXPECT_EQ(list.jobs_size(), 3);
  // One log line per job event.
  std::string log = s.log();
  for (const auto& id : ids) {
    EXPECT_NE(log.find("job " + id + " accepted"), std::string::npos);
    EXPECT_NE(log.find("job " + id + " started"), std::string::npos);
    EXPECT_NE(log.find("job " + id + " finished"), std::string::npos);
  }
}

TEST_F(Service, ProgressEventsArriveInOrder) {
  ServerProcess& s = server();
  Client c(s.address());
  std::string id = c.submit_ok("fuze.obj");
  grpc::Status st;
  std::vector<pb::ProgressEvent> events = c.watch(id, st);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_GE(events.size(), 10u);
  // Gapless sequence from 1, states never go back, the last one is final.
  std::vector<std::string> stages;
  for (size_t i = 0; i < events.size(); ++i) {
    EXPECT_EQ(events[i].sequence(), i + 1);
    if (i > 0) {
      EXPECT_GE(int(events[i].state()), int(events[i - 1].state()));
      EXPECT_GE(events[i].elapsed_seconds() + 1e-9, events[i - 1].elapsed_seconds());
    }
    if (!events[i].stage().empty() && (stages.empty() || stages.back() != events[i].stage()))
      stages.push_back(events[i].stage());
  }
  EXPECT_EQ(events.front().state(), pb::JOB_STATE_QUEUED);
  EXPECT_EQ(events.back().state(), pb::JOB_STATE_SUCCEEDED);
  // The pipeline's stages, in the pipeline's order (first appearances).
  auto pos = [&](const std::string& name) {
    auto it = std::find(stages.begin(), stages.end(), name);
    return it == stages.end() ? -1 : int(it - stages.begin());
  };
  std::vector<std::string> expected = {"read",    "diagnose input", "prepare",  "refine", "flood fill",
                                       "extract", "project",        "validate", "write"};
  for (size_t i = 0; i < expected.size(); ++i) {
    ASSERT_GE(pos(expected[i]), 0) << expected[i];
    if (i > 0) EXPECT_LT(pos(expected[i - 1]), pos(expected[i]));
  }
  // A watcher of an ended job gets its final state at once.
  std::vector<pb::ProgressEvent> again = c.watch(id, st, 10s);
  ASSERT_TRUE(st.ok());
  ASSERT_FALSE(again.empty());
  EXPECT_EQ(again.back().state(), pb::JOB_STATE_SUCCEEDED);
}

TEST_F(Service, CancelStopsARunningJobAndOthersRunOn) {
  ServerProcess& s = server({"--workers", "2"});
  Client c(s.address());
  std::string slow_id = c.submit_ok("fuze.obj", slow());
  std::string small_id = c.submit_ok("two_objects_mixed_case_names.stl");
  // Cancel once the slow job is inside the voxel stages.
  c.poll(
      slow_id,
      [](const pb::JobStatus& st) {
        return st.state() == pb::JOB_STATE_RUNNING &&
               (st.stage() == "extract" || st.stage() == "project" || st.stage() == "flood fill");
      },
      60s);
  pb::JobStatus after;
  const auto t0 = Clock::now();
  ASSERT_TRUE(c.cancel(slow_id, &after).ok());
  pb::JobStatus st = c.wait_done(slow_id, 30s);
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(st.state(), pb::JOB_STATE_CANCELLED);
  EXPECT_EQ(st.error_kind(), pb::ERROR_KIND_CANCELLED);
  EXPECT_LT(seconds, 3.0) << "cancellation took " << seconds << " s";
  // The other job is unharmed.
  pb::JobStatus small = c.wait_done(small_id);
  EXPECT_EQ(small.state(), pb::JOB_STATE_SUCCEEDED);
  // No result for a cancelled job; cancelling again is a no-op; a succeeded job cannot be cancelled.
  std::string bytes;
  EXPECT_EQ(c.download(slow_id, bytes).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_TRUE(c.cancel(slow_id).ok());
  EXPECT_EQ(c.cancel(small_id).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  // A queued job is cancelled at once.
  std::string a = c.submit_ok("fuze.obj", slow());
  std::string b = c.submit_ok("fuze.obj", slow());
  std::string queued = c.submit_ok("fuze.obj", slow());
  EXPECT_TRUE(c.cancel(queued, &after).ok());
  EXPECT_EQ(after.state(), pb::JOB_STATE_CANCELLED);
  c.cancel(a);
  c.cancel(b);
  EXPECT_EQ(c.wait_done(a, 30s).state(), pb::JOB_STATE_CANCELLED);
  EXPECT_EQ(c.wait_done(b, 30s).state(), pb::JOB_STATE_CANCELLED);
}

TEST_F(Service, FullQueueIsResourceExhausted) {
  ServerProcess& s = server({"--workers", "1", "--queue", "1"});
  Client c(s.address());
  std::string running = c.submit_ok("fuze.obj", slow());
  c.poll(
      running, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING; }, 30s);
  std::string waiting = c.submit_ok("two_objects_mixed_case_names.stl");
  SubmitOutcome full = c.submit(data("unit_sphere.STL"), "unit_sphere.STL", coarse());
  EXPECT_EQ(full.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(full.status.error_message().find("queue is full"), std::string::npos) << full.status.error_message();
  EXPECT_EQ(s.jobs_on_disk(), 2u);
  // Room again once the waiting job has started.
  c.cancel(running);
  c.poll(
      waiting, [](const pb::JobStatus& st) { return st.state() != pb::JOB_STATE_QUEUED; }, 30s);
  SubmitOutcome again = c.submit(data("unit_sphere.STL"), "unit_sphere.STL", coarse());
  EXPECT_TRUE(again.status.ok()) << again.status.error_message();
  EXPECT_EQ(c.wait_done(waiting).state(), pb::JOB_STATE_SUCCEEDED);
  EXPECT_EQ(c.wait_done(again.job_id).state(), pb::JOB_STATE_SUCCEEDED);
}

TEST_F(Service, SigkillAndRestartFinishesEveryAcceptedJob) {
  ServerProcess& s = server({"--workers", "1", "--queue", "8"});
  std::vector<std::string> ids;
  {
    Client c(s.address());
    // One job ends before the crash: its result must be served after it.
    ids.push_back(c.submit_ok("two_objects_mixed_case_names.stl"));
    ASSERT_EQ(c.wait_done(ids[0]).state(), pb::JOB_STATE_SUCCEEDED);
    ids.push_back(c.submit_ok("fuze.obj", slow()));
    ids.push_back(c.submit_ok("unit_sphere.STL"));
    ids.push_back(c.submit_ok("fuze.obj"));
    ids.push_back(c.submit_ok("two_objects_mixed_case_names.stl", coarse(5)));
    c.poll(
        ids[1], [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING; }, 30s);
  }
  EXPECT_EQ(s.kill(SIGKILL), 128 + SIGKILL);
  EXPECT_EQ(s.jobs_on_disk(), ids.size());
  s.start();  // same spool
  Client c(s.address());
  for (size_t i = 0; i < ids.size(); ++i) {
    pb::JobStatus st = c.wait_done(ids[i], 180s);
    ASSERT_EQ(st.state(), pb::JOB_STATE_SUCCEEDED) << "job " << i << ": " << st.error_message();
    std::string bytes;
    ASSERT_TRUE(c.download(ids[i], bytes).ok());
    expect_valid_result(bytes, vdbwrap::io::format_from_extension(st.spec().file_name()), st.spec().file_name());
  }
  EXPECT_NE(s.log().find("4 job(s) queued again, 1 ended job(s) kept"), std::string::npos) << s.log();
}

TEST_F(Service, SigtermRequeuesTheRunningJob) {
  ServerProcess& s = server({"--workers", "1", "--shutdown-grace", "0"});
  std::string id;
  {
    Client c(s.address());
    id = c.submit_ok("fuze.obj", slow());
    c.poll(
        id, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING && st.stage() != "read"; }, 30s);
  }
  const auto t0 = Clock::now();
  EXPECT_EQ(s.kill(SIGTERM), 0);
  EXPECT_LT(Clock::now() - t0, 10s);
  EXPECT_NE(read_file(s.spool() / "jobs" / id / "job.json").find("JOB_STATE_QUEUED"), std::string::npos);
  s.start();
  Client c(s.address());
  EXPECT_EQ(c.wait_done(id, 180s).state(), pb::JOB_STATE_SUCCEEDED);
}

TEST_F(Service, OneServerPerSpool) {
  ServerProcess& s = server();
  std::string cmd = std::string(VDBWRAP_SERVER) + " --listen 127.0.0.1:0 --spool " + s.spool().string() + " 2> " +
                    (dir_ / "second.log").string();
  int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) != 0);
  EXPECT_NE(read_file(dir_ / "second.log").find("in use by another vdbwrap-server"), std::string::npos);
}

TEST_F(Service, BadUploadsAreRefusedWhileAJobRunsUnharmed) {
  ServerProcess& s = server({"--workers", "1", "--max-upload", "200k"});
  Client c(s.address());
  std::string good = c.submit_ok("fuze.obj");

  SubmitOutcome garbage = c.submit(std::string(5000, '\x7f') + "garbage", "garbage.stl", coarse());
  EXPECT_EQ(garbage.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << garbage.status.error_message();
  EXPECT_EQ(garbage.error_kind, "3");
  SubmitOutcome unknown = c.submit("this is not a mesh\n", "notes.txt", coarse());
  EXPECT_EQ(unknown.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  SubmitOutcome truncated = c.submit(binary_stl(100, 10), "truncated.stl", coarse());
  EXPECT_EQ(truncated.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(truncated.status.error_message().find("truncated.stl"), std::string::npos)
      << truncated.status.error_message();
  std::string half = data("unit_sphere.STL");
  half.resize(half.size() / 2);
  EXPECT_EQ(c.submit(half, "unit_sphere.STL", coarse()).status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  SubmitOutcome nan = c.submit(binary_stl(2, 2, std::numeric_limits<float>::quiet_NaN()), "nan.stl", coarse());
  EXPECT_EQ(nan.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(nan.error_kind, "3");
  SubmitOutcome nan_obj = c.submit("v 0 0 0\nv 1 0 0\nv 0 nan 1\nf 1 2 3\n", "nan.obj", coarse());
  EXPECT_EQ(nan_obj.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  std::string big = binary_stl(5000, 5000);  // 250 kB > 200 kB
  SubmitOutcome too_big = c.submit(big, "big.stl", coarse());
  EXPECT_EQ(too_big.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << too_big.status.error_message();
  SubmitOutcome declared = c.submit(big, "big.stl", coarse(), "", pb::MESH_FORMAT_UNSPECIFIED, big.size());
  EXPECT_EQ(declared.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);

  pb::WrapParameters bad = coarse();
  bad.set_levels(9);
  SubmitOutcome bad_params = c.submit(data("fuze.obj"), "fuze.obj", bad);
  EXPECT_EQ(bad_params.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad_params.status.error_message().find("levels"), std::string::npos);
  EXPECT_EQ(bad_params.error_kind, "2");
  pb::WrapParameters bad_size;
  bad_size.set_base_size_percent(-1);
  EXPECT_EQ(c.submit(data("fuze.obj"), "fuze.obj", bad_size).status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(c.submit("", "empty.stl", coarse()).status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);

  // Ids that are not ids, or not known.
  pb::JobStatus st;
  EXPECT_EQ(c.status("../../etc/passwd", st).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(c.status(std::string(32, 'a'), st).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(c.cancel(std::string(32, 'b')).error_code(), grpc::StatusCode::NOT_FOUND);

  // Nothing was created for the refused uploads; the good job finished.
  EXPECT_EQ(s.jobs_on_disk(), 1u);
  pb::JobStatus done = c.wait_done(good);
  EXPECT_EQ(done.state(), pb::JOB_STATE_SUCCEEDED);
  std::string bytes;
  ASSERT_TRUE(c.download(good, bytes).ok());
  expect_valid_result(bytes, vdbwrap::io::Format::Obj, "fuze.obj");
  EXPECT_NE(s.log().find("rejected"), std::string::npos);
}

TEST_F(Service, ResultNotReadyIsFailedPrecondition) {
  ServerProcess& s = server({"--workers", "1"});
  Client c(s.address());
  std::string id = c.submit_ok("fuze.obj", slow());
  std::string bytes;
  grpc::Status st = c.download(id, bytes);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(st.error_message().find("not ready"), std::string::npos) << st.error_message();
  EXPECT_EQ(c.remove(id).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  c.cancel(id);
  c.wait_done(id, 30s);
  // Delete removes an ended job and its files.
  EXPECT_TRUE(c.remove(id).ok());
  EXPECT_EQ(s.jobs_on_disk(), 0u);
  pb::JobStatus gone;
  EXPECT_EQ(c.status(id, gone).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(Service, JobTimeoutStopsTheJob) {
  ServerProcess& s = server({"--job-timeout", "1"});
  Client c(s.address());
  std::string id = c.submit_ok("fuze.obj", slow());
  const auto t0 = Clock::now();
  pb::JobStatus st = c.wait_done(id, 30s);
  EXPECT_EQ(st.state(), pb::JOB_STATE_FAILED);
  EXPECT_EQ(st.error_kind(), pb::ERROR_KIND_TIMED_OUT);
  EXPECT_LT(Clock::now() - t0, 5s);
}

TEST_F(Service, TokenIsRequiredInEveryCall) {
  write_file(dir_ / "token", "s3cret-token\n");
  ServerProcess& s = server({"--token-file", (dir_ / "token").string()});
  Client none(s.address()), wrong(s.address(), "guess"), right(s.address(), "s3cret-token");
  EXPECT_EQ(none.submit(data("fuze.obj"), "fuze.obj", coarse()).status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(wrong.submit(data("fuze.obj"), "fuze.obj", coarse()).status.error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  pb::ListReply list;
  EXPECT_EQ(none.list(list).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(wrong.list(list).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  std::string id = right.submit_ok("two_objects_mixed_case_names.stl");
  pb::JobStatus st;
  EXPECT_EQ(none.status(id, st).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(wrong.cancel(id).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  std::string bytes;
  EXPECT_EQ(wrong.download(id, bytes).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  grpc::Status ws;
  none.watch(id, ws, 10s);
  EXPECT_EQ(ws.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(wrong.remove(id).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(right.wait_done(id).state(), pb::JOB_STATE_SUCCEEDED);
  EXPECT_TRUE(right.download(id, bytes).ok());
  EXPECT_EQ(s.jobs_on_disk(), 1u);
}

// grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo (a bidi stream) through a
// generic call: one request {list_services: ""} (field 7); returns the raw answer, which
// holds the service names.
std::string reflection_answer(const std::shared_ptr<grpc::Channel>& channel) {
  grpc::GenericStub stub(channel);
  grpc::CompletionQueue cq;
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + 10s);
  auto call = stub.PrepareCall(&ctx, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &cq);
  auto step = [&](intptr_t expect) {
    void* tag = nullptr;
    bool ok = false;
    return cq.Next(&tag, &ok) && reinterpret_cast<intptr_t>(tag) == expect && ok;
  };
  std::string answer;
  call->StartCall(reinterpret_cast<void*>(1));
  if (step(1)) {
    grpc::Slice slice(std::string("\x3a\x00", 2));
    grpc::ByteBuffer request(&slice, 1), response;
    call->Write(request, reinterpret_cast<void*>(2));
    if (step(2)) {
      call->Read(&response, reinterpret_cast<void*>(3));
      if (step(3)) {
        std::vector<grpc::Slice> slices;
        response.Dump(&slices);
        for (auto& sl : slices) answer.append(reinterpret_cast<const char*>(sl.begin()), sl.size());
      }
    }
  }
  ctx.TryCancel();
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(5));
  cq.Shutdown();
  void* tag;
  bool ok;
  while (cq.Next(&tag, &ok)) {
  }
  return answer;
}

TEST_F(Service, HealthAndReflectionNeedNoToken) {
  write_file(dir_ / "token", "s3cret-token");
  ServerProcess& s = server({"--token-file", (dir_ / "token").string()});
  auto channel = grpc::CreateChannel(s.address(), grpc::InsecureChannelCredentials());
  EXPECT_EQ(health(channel, ""), 1);
  EXPECT_EQ(health(channel, "vdbwrap.v1.Jobs"), 1);
  EXPECT_EQ(health(channel, "no.such.Service"), -1);  // NOT_FOUND
  std::string services = reflection_answer(channel);
  EXPECT_NE(services.find("vdbwrap.v1.Jobs"), std::string::npos) << services;
  EXPECT_NE(services.find("grpc.health.v1.Health"), std::string::npos) << services;
  // The CLI's probe (Docker health check).
  CliRun probe = cli("health --server " + s.address());
  EXPECT_EQ(probe.code, 0) << probe.err;
  EXPECT_EQ(probe.out, "SERVING\n");
  EXPECT_NE(cli("health --server " + s.address() + " --service no.such.Service").code, 0);
}

TEST_F(Service, IdempotencyKeyReturnsTheSameJob) {
  ServerProcess& s = server();
  Client c(s.address());
  SubmitOutcome first = c.submit(data("two_objects_mixed_case_names.stl"), "two.stl", coarse(), "retry-key-1");
  SubmitOutcome second = c.submit(data("two_objects_mixed_case_names.stl"), "two.stl", coarse(), "retry-key-1");
  ASSERT_TRUE(first.status.ok());
  ASSERT_TRUE(second.status.ok());
  EXPECT_EQ(first.job_id, second.job_id);
  EXPECT_FALSE(first.duplicate);
  EXPECT_TRUE(second.duplicate);
  SubmitOutcome other = c.submit(data("two_objects_mixed_case_names.stl"), "two.stl", coarse(), "retry-key-2");
  EXPECT_NE(other.job_id, first.job_id);
  EXPECT_EQ(s.jobs_on_disk(), 2u);
  // Also after a restart.
  c.wait_done(first.job_id);
  c.wait_done(other.job_id);
  EXPECT_EQ(s.kill(SIGTERM), 0);
  s.start();
  Client c2(s.address());
  SubmitOutcome third = c2.submit(data("two_objects_mixed_case_names.stl"), "two.stl", coarse(), "retry-key-1");
  EXPECT_EQ(third.job_id, first.job_id);
  EXPECT_TRUE(third.duplicate);
}

TEST_F(Service, RoundRobinSpreadsJobsOverServers) {
  std::vector<ServerProcess*> servers;
  for (const char* name : {"a", "b", "c"}) servers.push_back(&server({"--workers", "1"}, name));
  std::string target = "ipv4:";
  for (size_t i = 0; i < servers.size(); ++i)
    target += (i ? ",127.0.0.1:" : "127.0.0.1:") + std::to_string(servers[i]->port());
  grpc::ChannelArguments args;
  args.SetLoadBalancingPolicyName("round_robin");
  Client balanced(grpc::CreateCustomChannel(target, grpc::InsecureChannelCredentials(), args), "");
  // Let the policy connect to every address before the jobs go out.
  balanced.channel()->WaitForConnected(std::chrono::system_clock::now() + 10s);
  for (int i = 0; i < 20; ++i) {
    pb::ListReply l;
    balanced.list(l);
  }
  std::map<std::string, std::string> job_peer;  // job id -> server that accepted it
  for (int i = 0; i < 6; ++i) {
    std::string id = balanced.submit_ok("two_objects_mixed_case_names.stl", coarse(5));
    job_peer[id] = balanced.last_peer();
  }
  size_t used = 0, total = 0;
  for (auto* s : servers) {
    used += s->jobs_on_disk() > 0 ? 1 : 0;
    total += s->jobs_on_disk();
  }
  EXPECT_EQ(total, 6u);
  EXPECT_GE(used, 2u) << "round robin left jobs on one server";
  // Each job finishes on the server that holds it (named by the call's peer address).
  for (auto& [id, peer] : job_peer) {
    ASSERT_EQ(peer.rfind("ipv4:127.0.0.1:", 0), 0u) << peer;
    Client direct(peer);
    EXPECT_EQ(direct.wait_done(id).state(), pb::JOB_STATE_SUCCEEDED);
  }
}

TEST_F(Service, TlsServesEncryptedClientsOnly) {
  if (std::system("command -v openssl > /dev/null 2>&1") != 0) GTEST_SKIP() << "openssl not installed";
  const fs::path key = dir_ / "key.pem", cert = dir_ / "cert.pem";
  std::string cmd =
      "openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=localhost -addext "
      "subjectAltName=DNS:localhost,IP:127.0.0.1 -keyout " +
      key.string() + " -out " + cert.string() + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  ServerProcess& s = server({"--tls-cert", cert.string(), "--tls-key", key.string()});
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = read_file(cert);
  Client secure(grpc::CreateChannel(s.address(), grpc::SslCredentials(ssl)), "");
  pb::ListReply list;
  EXPECT_TRUE(secure.list(list).ok());
  Client plain(s.address());
  EXPECT_FALSE(plain.list(list).ok());
  std::string id = secure.submit_ok("two_objects_mixed_case_names.stl");
  EXPECT_EQ(secure.wait_done(id).state(), pb::JOB_STATE_SUCCEEDED);
  // The CLI with --tls-ca.
  CliRun r = cli("jobs --server " + s.address() + " --tls-ca " + cert.string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(id), std::string::npos);
}

}  // namespace
