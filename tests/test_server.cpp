// The gRPC job service as clients see it: real vdbwrap-server processes on 127.0.0.1 (any
// free port, temporary spools), driven through the generated vdbwrap.v1 stubs and the CLI.
// Every wait below is bounded in time.
#include <gtest/gtest.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "vdbwrap/io.h"
#include "params_mapping.h"
#include "test_meshes.h"
#include "vdbwrap/source.h"
#include "vdbwrap/v1/jobs.grpc.pb.h"

#ifndef VDBWRAP_SERVER
#define VDBWRAP_SERVER "vdbwrap-server"
#endif
#ifndef VDBWRAP_CLI
#define VDBWRAP_CLI "vdbwrap"
#endif
#ifndef VDBWRAP_WORKER_HOOK
#define VDBWRAP_WORKER_HOOK "server_worker_hook"
#endif

extern char** environ;

namespace {

namespace pb = vdbwrap::v1;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_file(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

std::string data(const std::string& name) { return read_file(vdbwrap::testing::data_path(name)); }

// A vdbwrap-server child process. Its stderr (the job log) goes to a file.
class ServerProcess {
 public:
  ServerProcess(fs::path spool, fs::path log, std::vector<std::string> extra = {})
      : spool_(std::move(spool)), log_(std::move(log)), extra_(std::move(extra)) {}
  ~ServerProcess() { kill(SIGKILL); }

  void start() {
    std::vector<std::string> args = {VDBWRAP_SERVER, "--listen", listen_, "--spool", spool_.string()};
    args.insert(args.end(), extra_.begin(), extra_.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 2, log_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    ASSERT_EQ(posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ), 0) << "cannot start " << argv[0];
    posix_spawn_file_actions_destroy(&actions);
    // The port is in the log line "listening on 127.0.0.1:PORT (".
    const std::regex listening("listening on 127\\.0\\.0\\.1:([0-9]+) ");
    const auto deadline = Clock::now() + 30s;
    for (;;) {
      std::string text = log();
      // Only this start's line counts (the log is appended to across restarts).
      std::smatch m;
      std::string::const_iterator from = text.begin();
      size_t count = 0;
      int port = 0;
      while (std::regex_search(from, text.cend(), m, listening)) {
        ++count;
        port = std::stoi(m[1]);
        from = m.suffix().first;
      }
      if (count > starts_ && port > 0) {
        port_ = port;
        starts_ = count;
        break;
      }
      int status = 0;
      ASSERT_EQ(waitpid(pid_, &status, WNOHANG), 0) << "the server exited at start:\n" << text;
      ASSERT_LT(Clock::now(), deadline) << "the server did not start listening within 30 s:\n" << text;
      std::this_thread::sleep_for(20ms);
    }
  }

  // Signals the server; returns its exit status (or -1) after waiting at most `wait`.
  int kill(int sig, std::chrono::seconds wait = 30s) {
    if (pid_ <= 0) return -1;
    ::kill(pid_, sig);
    const auto deadline = Clock::now() + wait;
    int status = 0;
    while (waitpid(pid_, &status, WNOHANG) == 0) {
      if (Clock::now() > deadline) {
        ::kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
        pid_ = -1;
        return -1;
      }
      std::this_thread::sleep_for(20ms);
    }
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  // The next start() listens here (default: any free port).
  void set_listen(const std::string& address) { listen_ = address; }
  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  std::string log() const { return read_file(log_); }
  const fs::path& spool() const { return spool_; }
  size_t jobs_on_disk() const {
    size_t n = 0;
    std::error_code ec;
    for (auto& e : fs::directory_iterator(spool_ / "jobs", ec)) n += e.is_directory() ? 1 : 0;
    return n;
  }

 private:
  fs::path spool_, log_;
  std::vector<std::string> extra_;
  std::string listen_ = "127.0.0.1:0";
  pid_t pid_ = -1;
  int port_ = 0;
  size_t starts_ = 0;
};

struct SubmitOutcome {
  grpc::Status status;
  std::string job_id;
  bool duplicate = false;
  std::string error_kind;  // trailing metadata vdbwrap-error-kind
};

// Job parameters: the coarse ones keep the tests fast.
pb::WrapParameters coarse(double percent = 3) {
  pb::WrapParameters p;
  p.set_base_size_percent(percent);
  return p;
}
// A job that runs for several seconds on one thread (fuze.obj at 0.5 %).
pb::WrapParameters slow() {
  pb::WrapParameters p = coarse(0.5);
  p.set_threads(1);
  p.set_snap_features(false);
  return p;
}

class Client {
 public:
  explicit Client(const std::string& address, std::string token = "")
      : Client(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()), std::move(token)) {}
  Client(std::shared_ptr<grpc::Channel> channel, std::string token)
      : channel_(std::move(channel)), stub_(pb::Jobs::NewStub(channel_)), token_(std::move(token)) {}

  void prepare(grpc::ClientContext& ctx, std::chrono::seconds timeout = 60s) const {
    if (!token_.empty()) ctx.AddMetadata("authorization", "Bearer " + token_);
    ctx.set_deadline(std::chrono::system_clock::now() + timeout);
  }

  SubmitOutcome submit(const std::string& bytes, const std::string& file_name, const pb::WrapParameters& params,
                       const std::string& key = "", pb::MeshFormat output = pb::MESH_FORMAT_UNSPECIFIED,
                       uint64_t declared_size = 0) {
    pb::JobSpec spec;
    spec.set_file_name(file_name);
    *spec.mutable_params() = params;
    spec.set_idempotency_key(key);
    spec.set_output_format(output);
    spec.set_size_bytes(declared_size);
    return submit_spec(bytes, spec);
  }

  SubmitOutcome submit_spec(const std::string& bytes, const pb::JobSpec& job) {
    grpc::ClientContext ctx;
    prepare(ctx);
    pb::SubmitReply reply;
    auto writer = stub_->Submit(&ctx, &reply);
    pb::SubmitRequest req;
    *req.mutable_spec() = job;
    bool open = writer->Write(req);
    const size_t chunk = 64 * 1024;
    for (size_t off = 0; open && off < bytes.size(); off += chunk) {
      req.set_chunk(bytes.substr(off, chunk));
      open = writer->Write(req);
    }
    if (open) writer->WritesDone();
    SubmitOutcome out;
    out.status = writer->Finish();
    out.job_id = reply.job_id();
    out.duplicate = reply.duplicate();
    auto md = ctx.GetServerTrailingMetadata();
    if (auto it = md.find("vdbwrap-error-kind"); it != md.end()) out.error_kind = std::string(it->second.data(), it->second.size());
    peer_ = ctx.peer();
    return out;
  }

  std::string submit_ok(const std::string& name, const pb::WrapParameters& params = coarse(), const std::string& key = "") {
    SubmitOutcome o = submit(data(name), name, params, key);
    EXPECT_TRUE(o.status.ok()) << o.status.error_message();
    return o.job_id;
  }

  grpc::Status status(const std::string& id, pb::JobStatus& out) {
    grpc::ClientContext ctx;
    prepare(ctx);
    pb::JobId req;
    req.set_job_id(id);
    return stub_->GetStatus(&ctx, req, &out);
  }

  pb::JobStatus status(const std::string& id) {
    pb::JobStatus s;
    grpc::Status st = status(id, s);
    EXPECT_TRUE(st.ok()) << st.error_message();
    return s;
  }

  // Polls until pred(status) or the time is up; returns the last status.
  template <class Pred>
  pb::JobStatus poll(const std::string& id, Pred pred, std::chrono::seconds limit = 120s) {
    const auto deadline = Clock::now() + limit;
    pb::JobStatus s;
    for (int i = 0; i < 100000 && Clock::now() < deadline; ++i) {
      s = pb::JobStatus();
      grpc::Status st = status(id, s);
      if (st.ok() && pred(s)) return s;
      std::this_thread::sleep_for(50ms);
    }
    ADD_FAILURE() << "job " << id << " did not reach the expected state in time (last: " << pb::JobState_Name(s.state())
                  << " " << s.stage() << ")";
    return s;
  }
  pb::JobStatus wait_done(const std::string& id, std::chrono::seconds limit = 120s) {
    return poll(id, [](const pb::JobStatus& s) {
      return s.state() == pb::JOB_STATE_SUCCEEDED || s.state() == pb::JOB_STATE_FAILED || s.state() == pb::JOB_STATE_CANCELLED;
    }, limit);
  }

  grpc::Status download(const std::string& id, std::string& bytes, pb::MeshFormat format = pb::MESH_FORMAT_UNSPECIFIED) {
    grpc::ClientContext ctx;
    prepare(ctx);
    pb::DownloadRequest req;
    req.set_job_id(id);
    req.set_format(format);
    auto reader = stub_->Download(&ctx, req);
    pb::DownloadChunk c;
    uint64_t total = 0;
    bool first = true;
    bytes.clear();
    while (reader->Read(&c)) {
      if (first) total = c.total_size();
      first = false;
      bytes += c.data();
    }
    grpc::Status st = reader->Finish();
    if (st.ok()) EXPECT_EQ(bytes.size(), total);
    return st;
  }

  std::vector<pb::ProgressEvent> watch(const std::string& id, grpc::Status& st, std::chrono::seconds limit = 120s) {
    grpc::ClientContext ctx;
    prepare(ctx, limit);
    pb::JobId req;
    req.set_job_id(id);
    auto reader = stub_->Watch(&ctx, req);
    std::vector<pb::ProgressEvent> events;
    pb::ProgressEvent ev;
    while (reader->Read(&ev)) events.push_back(ev);
    st = reader->Finish();
    return events;
  }

  grpc::Status cancel(const std::string& id, pb::JobStatus* out = nullptr) {
    grpc::ClientContext ctx;
    prepare(ctx);
    pb::JobId req;
    req.set_job_id(id);
    pb::JobStatus s;
    grpc::Status st = stub_->Cancel(&ctx, req, &s);
    if (out) *out = s;
    return st;
  }

  grpc::Status list(pb::ListReply& out) {
    grpc::ClientContext ctx;
    prepare(ctx);
    return stub_->List(&ctx, pb::ListRequest(), &out);
  }

  grpc::Status remove(const std::string& id) {
    grpc::ClientContext ctx;
    prepare(ctx);
    pb::JobId req;
    req.set_job_id(id);
    pb::DeleteReply r;
    return stub_->Delete(&ctx, req, &r);
  }

  const std::string& last_peer() const { return peer_; }
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }

 private:
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<pb::Jobs::Stub> stub_;
  std::string token_;
  std::string peer_;
};

void expect_valid_result(const std::string& bytes, vdbwrap::io::Format format, const std::string& what) {
  ASSERT_FALSE(bytes.empty()) << what;
  vdbwrap::Mesh m = vdbwrap::io::read_mesh_from_bytes(bytes, format, what);
  // diagnose() welds bit-identical points first (STL stores 3 points per facet).
  vdbwrap::MeshDiagnostics d = vdbwrap::diagnose(m, true);
  EXPECT_TRUE(d.valid_closed_surface()) << what << ": closed " << d.closed << ", manifold " << d.manifold << ", oriented "
                                        << d.oriented << ", outward " << d.outward << ", self-intersecting "
                                        << d.self_intersecting;
}

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

struct CliRun {
  int code;
  std::string out, err;
};

class Service : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vdbwrap_server_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    servers_.clear();  // SIGKILL whatever still runs
    if (!HasFailure()) fs::remove_all(dir_);
    else std::fprintf(stderr, "kept %s for inspection\n", dir_.c_str());
  }

  ServerProcess& server(std::vector<std::string> extra = {}, const std::string& name = "a") {
    servers_.push_back(std::make_unique<ServerProcess>(dir_ / ("spool_" + name), dir_ / ("server_" + name + ".log"), extra));
    servers_.back()->start();
    return *servers_.back();
  }

  // env: assignments put before the command (VAR=value ...).
  CliRun cli(const std::string& args, const std::string& env = "") {
    const std::string out = (dir_ / "cli_out.txt").string(), err = (dir_ / "cli_err.txt").string();
    std::string cmd = env + " " + std::string(VDBWRAP_CLI) + " " + args + " > " + out + " 2> " + err;
    int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_file(out), read_file(err)};
  }

  fs::path dir_;
  std::vector<std::unique_ptr<ServerProcess>> servers_;
};

// True when `map` refuses the message that `set` fills, as bad parameters.
template <typename Message, typename Map, typename Set>
bool refused_by(Map map, Set set) {
  Message m;
  set(m);
  try {
    map(m);
  } catch (const vdbwrap::Error& e) {
    return e.kind() == vdbwrap::ErrorKind::InvalidArgument;
  }
  return false;
}

// --- tests ----------------------------------------------------------------------------

TEST(ParamsMapping, RoundTripsEveryFieldAndRefusesOutOfRange) {
  vdbwrap::WrapParams p;
  p.base_size = {0.25, false};
  p.levels = 4;
  p.feature_angle_deg = 42;
  p.volume = vdbwrap::VolumeChoice::Inside;
  p.threads = 3;
  p.refine_max_triangles = 7;
  p.refine_normal_spread_deg = 11;
  p.refine_at_features = false;
  p.weld_tolerance = 1e-5;
  p.surface_offset = 0.1;
  p.presmooth_iterations = 5;
  p.validity_rounds = 7;
  p.snap_features = !vdbwrap::WrapParams().snap_features;
  p.remesh = !vdbwrap::WrapParams().remesh;
  p.corner_angle_deg = 55;
  p.compute_distances = false;
  vdbwrap::WrapParams q = vdbwrap::api::to_wrap_params(vdbwrap::api::to_proto(p));
  EXPECT_EQ(q.base_size.value, 0.25);
  EXPECT_FALSE(q.base_size.percent_of_diagonal);
  EXPECT_EQ(q.levels, 4);
  EXPECT_EQ(q.feature_angle_deg, 42);
  EXPECT_EQ(q.volume, vdbwrap::VolumeChoice::Inside);
  EXPECT_EQ(q.threads, 3);
  EXPECT_EQ(q.refine_max_triangles, 7);
  EXPECT_EQ(q.refine_normal_spread_deg, 11);
  EXPECT_FALSE(q.refine_at_features);
  EXPECT_EQ(q.weld_tolerance, 1e-5);
  EXPECT_EQ(q.surface_offset, 0.1);
  EXPECT_EQ(q.presmooth_iterations, 5);
  EXPECT_EQ(q.validity_rounds, 7);
  EXPECT_EQ(q.snap_features, p.snap_features);
  EXPECT_EQ(q.remesh, p.remesh);
  EXPECT_EQ(q.corner_angle_deg, 55);
  EXPECT_FALSE(q.compute_distances);
  // The voxel-stage controls (issue 5), through the API and back.
  vdbwrap::WrapParams c;
  vdbwrap::parse_volume_choice("1,2,3;4,5,6", c.volume, c.seed_points);
  c.gap_closure = vdbwrap::Length{0.5, false};
  c.contact_floor = vdbwrap::Length{0.05, true};
  for (const char* cv : {"box:0,0,0,1,2,3:1%", "sphere:1,1,1,0.5:0.2", "cylinder:0,0,0,0,0,1,0.3:0.5%",
                         "cone:0,0,0,1,0,0,0.5,0.1:0.25%"})
    c.control_volumes.push_back(vdbwrap::ControlVolume::parse(cv));
  c.part_sizes.push_back(vdbwrap::PartSize::parse("wing=0.1%"));
  c.contact_prevention.push_back(vdbwrap::ContactRule::parse("a,b:c"));
  c.contact_prevention.push_back(vdbwrap::ContactRule::parse("x,y,z"));
  vdbwrap::WrapParams c2 = vdbwrap::api::to_wrap_params(vdbwrap::api::to_proto(c));
  EXPECT_EQ(c2.volume, vdbwrap::VolumeChoice::SeedPoints);
  EXPECT_EQ(c2.seed_points, c.seed_points);
  ASSERT_TRUE(c2.gap_closure && c2.contact_floor);
  EXPECT_EQ(c2.gap_closure->to_string(), "0.5");
  EXPECT_EQ(c2.contact_floor->to_string(), "0.05%");
  ASSERT_EQ(c2.control_volumes.size(), 4u);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(c2.control_volumes[i].to_string(), c.control_volumes[i].to_string());
  ASSERT_EQ(c2.part_sizes.size(), 1u);
  EXPECT_EQ(c2.part_sizes[0].part, "wing");
  ASSERT_EQ(c2.contact_prevention.size(), 2u);
  EXPECT_EQ(c2.contact_prevention[0].to_string(), "a,b:c");
  EXPECT_EQ(c2.contact_prevention[1].to_string(), "x,y,z");
  pb::WrapParameters seeds_without_points;
  seeds_without_points.set_volume(pb::VOLUME_SEED_POINTS);
  EXPECT_THROW(vdbwrap::api::to_wrap_params(seeds_without_points), vdbwrap::Error);

  // Unset fields: the core's (the CLI's) defaults.
  vdbwrap::WrapParams d = vdbwrap::api::to_wrap_params(pb::WrapParameters());
  EXPECT_EQ(d.levels, vdbwrap::WrapParams().levels);
  EXPECT_EQ(d.base_size.value, vdbwrap::WrapParams().base_size.value);
  EXPECT_EQ(d.surface_offset, vdbwrap::WrapParams().surface_offset);
  // Out of range.
  auto refused = [](auto set) {
    return refused_by<pb::WrapParameters>([](const auto& w) { vdbwrap::api::to_wrap_params(w); }, set);
  };
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_levels(7); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_base_size_percent(0); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_base_size_model_units(std::nan("")); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_feature_angle_deg(180); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_threads(-1); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_refine_max_triangles(0); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_presmooth_iterations(101); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_validity_rounds(-1); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_corner_angle_deg(0); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_surface_offset(0.5); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_volume(static_cast<pb::Volume>(9)); }));
}

TEST(ParamsMapping, RepairParametersRoundTripRefuseOutOfRangeAndMatchTheJobKind) {
  vdbwrap::RepairParams p;
  p.local_iterations = 7;
  p.alpha = 0.3;
  p.beta = 0.2;
  p.delta = 0.4;
  p.gamma = 0.002;
  p.area_ratio = 0.9;
  p.accuracy = 1e-4;
  p.refill_iterations = 2;
  p.refill_area_ratio = 0.6;
  p.fair = false;
  p.max_deviation = {0.05, false};
  p.remove_small_pieces = false;
  p.small_piece_triangles = 5;
  p.small_piece_area = 0.01;
  p.threads = 2;
  p.compute_distances = false;
  p.unite_bodies = false;
  const vdbwrap::RepairParams q = vdbwrap::api::to_repair_params(vdbwrap::api::to_proto(p));
  EXPECT_EQ(q.local_iterations, 7);
  EXPECT_EQ(q.alpha, 0.3);
  EXPECT_EQ(q.beta, 0.2);
  EXPECT_EQ(q.delta, 0.4);
  EXPECT_EQ(q.gamma, 0.002);
  EXPECT_EQ(q.area_ratio, 0.9);
  EXPECT_EQ(q.accuracy, 1e-4);
  EXPECT_EQ(q.refill_iterations, 2);
  EXPECT_EQ(q.refill_area_ratio, 0.6);
  EXPECT_FALSE(q.fair);
  EXPECT_EQ(q.max_deviation.to_string(), "0.05");
  EXPECT_FALSE(q.remove_small_pieces);
  EXPECT_EQ(q.small_piece_triangles, 5);
  EXPECT_EQ(q.small_piece_area, 0.01);
  EXPECT_EQ(q.threads, 2);
  EXPECT_FALSE(q.compute_distances);
  EXPECT_FALSE(q.unite_bodies);
  // Unset: `vdbwrap repair`'s defaults.
  const vdbwrap::RepairParams d = vdbwrap::api::to_repair_params(pb::RepairParameters());
  EXPECT_EQ(d.alpha, vdbwrap::RepairParams().alpha);
  EXPECT_EQ(d.max_deviation.to_string(), vdbwrap::RepairParams().max_deviation.to_string());
  EXPECT_TRUE(d.fair);
  EXPECT_TRUE(d.unite_bodies);
  auto refused = [](auto set) {
    return refused_by<pb::RepairParameters>([](const auto& r) { vdbwrap::api::to_repair_params(r); }, set);
  };
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_alpha(1); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_alpha(std::nan("")); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_beta(0); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_area_ratio(1.5); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_local_iterations(-1); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_refill_iterations(101); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_accuracy(-1); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_small_piece_area(2); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_threads(-1); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.mutable_max_deviation()->set_percent(0); }));
  EXPECT_FALSE(refused([](pb::RepairParameters& r) { r.set_small_piece_area(0); }));
  // A job names its own kind's parameters only.
  pb::JobSpec repair_job;
  repair_job.set_kind(pb::JOB_KIND_REPAIR);
  EXPECT_NO_THROW(vdbwrap::api::check_job_parameters(repair_job));
  repair_job.mutable_params()->set_levels(2);
  EXPECT_THROW(vdbwrap::api::check_job_parameters(repair_job), vdbwrap::Error);
  pb::JobSpec wrap_job;
  EXPECT_NO_THROW(vdbwrap::api::check_job_parameters(wrap_job));
  wrap_job.mutable_repair_params()->set_alpha(0.3);
  EXPECT_THROW(vdbwrap::api::check_job_parameters(wrap_job), vdbwrap::Error);
  pb::JobSpec unknown;
  unknown.set_kind(static_cast<pb::JobKind>(9));
  EXPECT_THROW(vdbwrap::api::check_job_parameters(unknown), vdbwrap::Error);
}

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
  const vdbwrap::MeshDiagnostics after = vdbwrap::diagnose(vdbwrap::io::read_mesh_from_bytes(result, vdbwrap::io::Format::Obj, "r"), true);
  EXPECT_LT(after.intersecting_pairs, before.intersecting_pairs);
  EXPECT_EQ(after.intersecting_pairs, 0u);
  EXPECT_TRUE(after.valid_closed_surface());
  EXPECT_EQ(after.triangles, folded.triangles.size()) << "a local repair: no re-wrap";
  // As STL (single precision): converted on download, still free of intersections.
  ASSERT_TRUE(c.download(st.job_id(), result, pb::MESH_FORMAT_STL).ok());
  EXPECT_EQ(vdbwrap::diagnose(vdbwrap::io::read_mesh_from_bytes(result, vdbwrap::io::Format::Stl, "r"), true).intersecting_pairs, 0u);

  // Two open sheets crossing edge to edge: beyond repair (nothing to cap). The job succeeds
  // with the result written and says how many pairs are left.
  spec.set_file_name("sheets.obj");
  o = c.submit_spec(vdbwrap::io::write_mesh_to_bytes(vdbwrap::testing::crossing_sheets(), vdbwrap::io::Format::Obj), spec);
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
    if (!events[i].stage().empty() && (stages.empty() || stages.back() != events[i].stage())) stages.push_back(events[i].stage());
  }
  EXPECT_EQ(events.front().state(), pb::JOB_STATE_QUEUED);
  EXPECT_EQ(events.back().state(), pb::JOB_STATE_SUCCEEDED);
  // The pipeline's stages, in the pipeline's order (first appearances).
  auto pos = [&](const std::string& name) {
    auto it = std::find(stages.begin(), stages.end(), name);
    return it == stages.end() ? -1 : int(it - stages.begin());
  };
  std::vector<std::string> expected = {"read", "diagnose input", "prepare", "refine", "flood fill", "extract", "project", "validate", "write"};
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
  c.poll(slow_id, [](const pb::JobStatus& st) {
    return st.state() == pb::JOB_STATE_RUNNING && (st.stage() == "extract" || st.stage() == "project" || st.stage() == "flood fill");
  }, 60s);
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
  c.poll(running, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING; }, 30s);
  std::string waiting = c.submit_ok("two_objects_mixed_case_names.stl");
  SubmitOutcome full = c.submit(data("unit_sphere.STL"), "unit_sphere.STL", coarse());
  EXPECT_EQ(full.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(full.status.error_message().find("queue is full"), std::string::npos) << full.status.error_message();
  EXPECT_EQ(s.jobs_on_disk(), 2u);
  // Room again once the waiting job has started.
  c.cancel(running);
  c.poll(waiting, [](const pb::JobStatus& st) { return st.state() != pb::JOB_STATE_QUEUED; }, 30s);
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
    c.poll(ids[1], [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING; }, 30s);
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
    c.poll(id, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING && st.stage() != "read"; }, 30s);
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
  EXPECT_NE(truncated.status.error_message().find("truncated.stl"), std::string::npos) << truncated.status.error_message();
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
  EXPECT_EQ(wrong.submit(data("fuze.obj"), "fuze.obj", coarse()).status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
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

// grpc.health.v1.Health/Check through a generic call: the request is {service: NAME}
// (field 1), the answer {status: SERVING = 1} (field 1, varint).
int health(const std::shared_ptr<grpc::Channel>& channel, const std::string& service) {
  grpc::GenericStub stub(channel);
  std::string request = std::string("\x0a") + char(service.size()) + service;
  grpc::Slice slice(request);
  grpc::ByteBuffer in(&slice, 1), out;
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + 10s);
  std::mutex m;
  std::condition_variable cv;
  bool done = false;
  grpc::Status status;
  stub.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &in, &out, [&](grpc::Status s) {
    std::lock_guard<std::mutex> g(m);
    status = s;
    done = true;
    cv.notify_all();
  });
  std::unique_lock<std::mutex> g(m);
  cv.wait_for(g, 15s, [&] { return done; });
  if (!done || !status.ok()) return -1;
  std::vector<grpc::Slice> slices;
  out.Dump(&slices);
  std::string bytes;
  for (auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  return bytes.size() >= 2 && bytes[0] == 0x08 ? int(bytes[1]) : 0;  // 0 = UNKNOWN (field left out)
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
  for (size_t i = 0; i < servers.size(); ++i) target += (i ? ",127.0.0.1:" : "127.0.0.1:") + std::to_string(servers[i]->port());
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
  std::string cmd = "openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=localhost -addext "
                    "subjectAltName=DNS:localhost,IP:127.0.0.1 -keyout " + key.string() + " -out " + cert.string() +
                    " > /dev/null 2>&1";
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

// --- the CLI's remote mode ------------------------------------------------------------

TEST_F(Service, CliSubmitDownloadsTheResult) {
  ServerProcess& s = server({"--workers", "2"});
  const fs::path out = dir_ / "fuze_remote.stl", report = dir_ / "fuze_remote.json";
  CliRun r = cli("submit --server " + s.address() + " " + vdbwrap::testing::data_path("fuze.obj") + " -o " + out.string() +
              " --base-size 3% --report " + report.string());
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
  expect_valid_result(read_file(dir_ / "outs" / "two_objects_mixed_case_names_wrap.ply"), vdbwrap::io::Format::Ply, "two");
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
  write_file(dir_ / "p.yaml", "volume: seed_points\nseed_points: [{x: 0.5, y: 0.5, z: 0.5}]\ngap_closure: {model_units: 0.15}\n");
  r = cli("submit --server " + s.address() + " " + in.string() + " -o " + (dir_ / "c.ply").string() + " --params " +
          (dir_ / "p.yaml").string() + " -q");
  ASSERT_EQ(r.code, 0) << r.err;
  expect_valid_result(read_file(dir_ / "c.ply"), vdbwrap::io::Format::Ply, "inside of the holed cube");
}

TEST_F(Service, CliDetachWaitJobsCancel) {
  ServerProcess& s = server({"--workers", "1"});
  CliRun r = cli("submit --server " + s.address() + " --detach " + vdbwrap::testing::data_path("two_objects_mixed_case_names.stl") +
              " " + vdbwrap::testing::data_path("unit_sphere.STL") + " --base-size 3%");
  ASSERT_EQ(r.code, 0) << r.err;
  std::istringstream lines(r.out);
  std::vector<std::string> ids;
  for (std::string line; std::getline(lines, line);) ids.push_back(line);
  ASSERT_EQ(ids.size(), 2u) << r.out;
  CliRun listed = cli("jobs --server " + s.address());
  ASSERT_EQ(listed.code, 0) << listed.err;
  for (auto& id : ids) EXPECT_NE(listed.out.find(id), std::string::npos);
  fs::create_directories(dir_ / "w");
  CliRun waited = cli("wait --server " + s.address() + " " + ids[0] + " " + ids[1] + " --out-dir " + (dir_ / "w").string());
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
  CliRun early_report = cli("submit " + sphere + " -o " + (dir_ / "o.stl").string() + " --report " +
                            (missing / "r.json").string(), env);
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
  CliRun explicit_server = cli("jobs --server " + s.address(), "VDBWRAP_SERVER=127.0.0.1:1 VDBWRAP_TOKEN_FILE=" + token.string());
  EXPECT_EQ(explicit_server.code, 0) << explicit_server.err;
  EXPECT_NE(explicit_server.out.find(id), std::string::npos);
  // A token file in the environment that does not exist: named when a remote command needs
  // it, no concern of the local commands.
  CliRun missing_token = cli("jobs --server " + s.address(), "VDBWRAP_TOKEN_FILE=" + (dir_ / "nope").string());
  EXPECT_EQ(missing_token.code, 2);
  EXPECT_NE(missing_token.err.find((dir_ / "nope").string()), std::string::npos) << missing_token.err;
  CliRun local = cli("check " + sphere, "VDBWRAP_TOKEN_FILE=" + (dir_ / "nope").string() + " VDBWRAP_SERVER=127.0.0.1:1");
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
  c.poll(running, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING; }, 30s);
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
  const std::string target = "ipv4:127.0.0.1:" + std::to_string(servers[0]->port()) + ",127.0.0.1:" +
                             std::to_string(servers[1]->port());
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
  c.poll(id, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING && st.stage() != "read"; }, 30s);
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
  for (auto it = std::sregex_iterator(help.begin(), help.end(), opt); it != std::sregex_iterator(); ++it) out.insert(it->str());
  return out;
}

TEST_F(Service, CliSubmitTakesEveryWrapOption) {
  // `submit` mirrors `wrap`: every long option of one is an option of the other.
  CliRun wrap_help = cli("wrap --help");
  CliRun submit_help = cli("submit --help");
  std::set<std::string> wrap_options = long_options(wrap_help.out), submit_options = long_options(submit_help.out);
  ASSERT_GT(wrap_options.size(), 5u) << wrap_help.out;
  for (const auto& o : wrap_options) EXPECT_TRUE(submit_options.count(o)) << "submit lacks wrap's " << o;
}

TEST_F(Service, CliSubmitRepairRunsTheRepairOnTheServer) {
  // `submit --repair` takes every option of `vdbwrap repair`, and gives its exit codes.
  const std::set<std::string> repair_options = long_options(cli("repair --help").out), submit_options = long_options(cli("submit --help").out);
  ASSERT_GT(repair_options.size(), 10u);
  for (const auto& o : repair_options) EXPECT_TRUE(submit_options.count(o)) << "submit lacks repair's " << o;

  ServerProcess& s = server({"--workers", "1"});
  const fs::path folded = dir_ / "folded.obj", out = dir_ / "fixed.obj", report = dir_ / "fixed.json";
  vdbwrap::io::write_mesh(vdbwrap::testing::folded_icosphere(), folded.string());
  CliRun r = cli("submit --repair --server " + s.address() + " " + folded.string() + " -o " + out.string() + " --report " +
                 report.string() + " --max-deviation 5% --alpha 0.3");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(vdbwrap::diagnose(vdbwrap::io::read_mesh(out.string()), true).intersecting_pairs, 0u);
  EXPECT_NE(read_file(report).find("\"all_fixed\": true"), std::string::npos);
  EXPECT_NE(read_file(report).find("\"alpha\": 0.3"), std::string::npos) << "the options reach the server";
  // Intersections left: the result and the report are written, exit code 4 (as `vdbwrap repair`).
  // (Two open sheets crossing edge to edge: nothing to cap, no bodies to unite.)
  const fs::path crossing = dir_ / "sheets.obj";
  vdbwrap::io::write_mesh(vdbwrap::testing::crossing_sheets(), crossing.string());
  fs::create_directories(dir_ / "outs");
  r = cli("submit --repair --server " + s.address() + " " + crossing.string() + " --out-dir " + (dir_ / "outs").string() + " -q");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "outs" / "sheets_repaired.obj"));
  EXPECT_TRUE(fs::exists(dir_ / "outs" / "sheets_repaired.json"));
  EXPECT_NE(r.err.find("intersecting pairs left"), std::string::npos) << r.err;
  // One kind's options with the other kind: refused before anything is sent.
  r = cli("submit --repair --server " + s.address() + " " + folded.string() + " -o " + out.string() + " --base-size 1%");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--base-size"), std::string::npos) << r.err;
  r = cli("submit --server " + s.address() + " " + folded.string() + " -o " + out.string() + " --alpha 0.3");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--repair"), std::string::npos) << r.err;
  r = cli("submit --repair --server " + s.address() + " " + folded.string() + " -o " + out.string() + " --area-ratio 1.5");
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
  CliRun bad_levels = cli("submit --server " + s.address() + token + " " + vdbwrap::testing::data_path("fuze.obj") + " -o " +
                       (dir_ / "o.stl").string() + " --levels 9");
  EXPECT_EQ(bad_levels.code, 2) << bad_levels.err;
  CliRun bad_output = cli("submit --server " + s.address() + token + " " + vdbwrap::testing::data_path("fuze.obj") + " -o " +
                       (dir_ / "o.xyz").string());
  EXPECT_EQ(bad_output.code, 2) << bad_output.err;
  CliRun no_token = cli("jobs --server " + s.address());
  EXPECT_EQ(no_token.code, 2) << no_token.err;
  EXPECT_NE(no_token.err.find("UNAUTHENTICATED"), std::string::npos) << no_token.err;
  CliRun unknown = cli("wait --server " + s.address() + token + " " + std::string(32, 'c'));
  EXPECT_EQ(unknown.code, 2) << unknown.err;
  EXPECT_EQ(s.jobs_on_disk(), 0u);
}

// --- crash isolation: each job in its own process ----------------------------------------
// The misbehaving jobs run under tests/server_worker_hook.cpp (--worker-command), which
// crashes or hangs when the job's file name says so and runs the real worker otherwise.

// The processes whose parent is `parent`, with their state letter (R, S, Z...).
std::map<pid_t, char> children_of(pid_t parent) {
  std::map<pid_t, char> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || !std::all_of(name.begin(), name.end(), ::isdigit)) continue;
    const std::string stat = read_file(entry.path() / "stat");
    const size_t close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(stat.substr(close + 1));
    char state = 0;
    pid_t ppid = 0;
    if (rest >> state >> ppid && ppid == parent) out[pid_t(std::stoi(name))] = state;
  }
  return out;
}

bool process_gone(pid_t pid, std::chrono::seconds limit) {
  const auto deadline = Clock::now() + limit;
  for (;;) {
    const std::string stat = read_file("/proc/" + std::to_string(pid) + "/stat");
    const size_t close = stat.rfind(')');
    if (stat.empty() || (close != std::string::npos && close + 2 < stat.size() && stat[close + 2] == 'Z')) return true;
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(20ms);
  }
}

// Asks the health service every 100 ms on its own channel until stopped; counts the answers
// that were not SERVING.
class HealthWatch {
 public:
  explicit HealthWatch(const std::string& address)
      : channel_(grpc::CreateChannel(address, grpc::InsecureChannelCredentials())), thread_([this] { loop(); }) {}
  ~HealthWatch() { stop(); }
  void stop() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
  }
  int asked() const { return asked_; }
  int failed() const { return failed_; }

 private:
  void loop() {
    while (!done_) {
      ++asked_;
      if (health(channel_, "vdbwrap.v1.Jobs") != 1) ++failed_;
      std::this_thread::sleep_for(100ms);
    }
  }
  std::shared_ptr<grpc::Channel> channel_;
  std::atomic<bool> done_{false};
  std::atomic<int> asked_{0}, failed_{0};
  std::thread thread_;
};

TEST_F(Service, CrashingJobFailsAloneWhileTheServerServesOn) {
  ServerProcess& s = server({"--workers", "2", "--worker-command", VDBWRAP_WORKER_HOOK});
  HealthWatch health_watch(s.address());
  Client c(s.address());
  std::vector<std::string> good = {c.submit_ok("two_objects_mixed_case_names.stl"), c.submit_ok("fuze.obj")};
  SubmitOutcome crash = c.submit(data("fuze.obj"), "crash-segv.obj", coarse());
  ASSERT_TRUE(crash.status.ok()) << crash.status.error_message();
  good.push_back(c.submit_ok("unit_sphere.STL"));
  SubmitOutcome early = c.submit(data("fuze.obj"), "exit-early.obj", coarse());
  SubmitOutcome garbage = c.submit(data("fuze.obj"), "garbage.obj", coarse());
  ASSERT_TRUE(early.status.ok() && garbage.status.ok());
  // An upload whose check crashes the mesh reader is refused, and no job is created.
  SubmitOutcome unreadable = c.submit(data("fuze.obj"), "crash-read.obj", coarse());
  EXPECT_EQ(unreadable.status.error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_NE(unreadable.status.error_message().find("crash-read.obj: the mesh reader's process ended with signal 11 (SIGSEGV)"),
            std::string::npos)
      << unreadable.status.error_message();
  EXPECT_EQ(s.jobs_on_disk(), 6u);

  pb::JobStatus crashed = c.wait_done(crash.job_id, 60s);
  EXPECT_EQ(crashed.state(), pb::JOB_STATE_FAILED);
  EXPECT_EQ(crashed.error_kind(), pb::ERROR_KIND_INTERNAL);
  EXPECT_NE(crashed.error_message().find("the wrap process ended with signal 11 (SIGSEGV) in stage extract"),
            std::string::npos)
      << crashed.error_message();
  for (const auto& id : good) {
    pb::JobStatus st = c.wait_done(id, 120s);
    ASSERT_EQ(st.state(), pb::JOB_STATE_SUCCEEDED) << st.spec().file_name() << ": " << st.error_message();
    std::string bytes;
    ASSERT_TRUE(c.download(id, bytes).ok());
    expect_valid_result(bytes, vdbwrap::io::format_from_extension(st.spec().file_name()), st.spec().file_name());
  }
  // A process that exits without a verdict, or writes what is not a frame, fails its job alone.
  pb::JobStatus ended = c.wait_done(early.job_id, 60s);
  EXPECT_EQ(ended.state(), pb::JOB_STATE_FAILED);
  EXPECT_NE(ended.error_message().find("the wrap process ended with exit code 3 in stage read without a result"),
            std::string::npos)
      << ended.error_message();
  pb::JobStatus broken = c.wait_done(garbage.job_id, 60s);
  EXPECT_EQ(broken.state(), pb::JOB_STATE_FAILED);
  EXPECT_NE(broken.error_message().find("broke the worker protocol"), std::string::npos) << broken.error_message();
  // The watchers saw the crash as the job's last event, with the reason.
  grpc::Status st;
  std::vector<pb::ProgressEvent> events = c.watch(crash.job_id, st, 10s);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().state(), pb::JOB_STATE_FAILED);
  EXPECT_NE(events.back().error_message().find("SIGSEGV"), std::string::npos);
  // The failure is final: no attempt to run it again.
  std::this_thread::sleep_for(500ms);
  EXPECT_EQ(c.status(crash.job_id).state(), pb::JOB_STATE_FAILED);
  health_watch.stop();
  EXPECT_GT(health_watch.asked(), 5);
  EXPECT_EQ(health_watch.failed(), 0) << "the health service did not answer SERVING throughout";
  // Every job process was reaped: no children left, zombies or not.
  EXPECT_TRUE(children_of(s.pid()).empty());
  EXPECT_NE(s.log().find("failed: the wrap process ended with signal 11 (SIGSEGV) in stage extract"), std::string::npos)
      << s.log();
  EXPECT_EQ(s.kill(SIGTERM), 0);
}

TEST_F(Service, JobOverTheMemoryLimitFailsAlone) {
  // On one thread, a coarse wrap of fuze.obj fits in about 100 MiB; at 0.3 % it needs over 200.
  auto one_thread = [](double percent) {
    pb::WrapParameters p = coarse(percent);
    p.set_threads(1);
    return p;
  };
  ServerProcess& s = server({"--workers", "2", "--job-memory", "150M"});
  HealthWatch health_watch(s.address());
  Client c(s.address());
  std::string big = c.submit_ok("fuze.obj", one_thread(0.3));
  std::string small = c.submit_ok("fuze.obj", one_thread(3));
  pb::JobStatus over = c.wait_done(big, 120s);
  EXPECT_EQ(over.state(), pb::JOB_STATE_FAILED);
  EXPECT_EQ(over.error_kind(), pb::ERROR_KIND_INTERNAL);
  EXPECT_NE(over.error_message().find("out of memory"), std::string::npos) << over.error_message();
  EXPECT_NE(over.error_message().find("--job-memory"), std::string::npos) << over.error_message();
  EXPECT_EQ(c.wait_done(small, 120s).state(), pb::JOB_STATE_SUCCEEDED);
  health_watch.stop();
  EXPECT_EQ(health_watch.failed(), 0);
  // The limit is what failed it: the same job succeeds on a server without one.
  ServerProcess& unlimited = server({}, "b");
  Client u(unlimited.address());
  EXPECT_EQ(u.wait_done(u.submit_ok("fuze.obj", one_thread(0.3)), 120s).state(), pb::JOB_STATE_SUCCEEDED);
}

TEST_F(Service, CancelAndTimeoutKillAJobProcessThatIgnoresThem) {
  ServerProcess& s = server({"--workers", "2", "--job-timeout", "2", "--worker-command", VDBWRAP_WORKER_HOOK});
  Client c(s.address());
  SubmitOutcome timed = c.submit(data("fuze.obj"), "hang-timeout.obj", coarse());
  SubmitOutcome cancelled = c.submit(data("fuze.obj"), "hang-cancel.obj", coarse());
  ASSERT_TRUE(timed.status.ok() && cancelled.status.ok());
  c.poll(cancelled.job_id, [](const pb::JobStatus& st) { return st.stage() == "read"; }, 30s);
  const auto t0 = Clock::now();
  ASSERT_TRUE(c.cancel(cancelled.job_id).ok());
  // The stand-in ignores SIGTERM: it ends by the SIGKILL that follows a grace period.
  pb::JobStatus st = c.wait_done(cancelled.job_id, 30s);
  EXPECT_EQ(st.state(), pb::JOB_STATE_CANCELLED);
  EXPECT_LT(Clock::now() - t0, 6s);
  pb::JobStatus late = c.wait_done(timed.job_id, 30s);
  EXPECT_EQ(late.state(), pb::JOB_STATE_FAILED);
  EXPECT_EQ(late.error_kind(), pb::ERROR_KIND_TIMED_OUT);
  EXPECT_TRUE(children_of(s.pid()).empty());
}

TEST_F(Service, ServerKilledWhileAJobRunsGivesUpAfterMaxAttempts) {
  ServerProcess& s = server(
      {"--workers", "1", "--max-attempts", "2", "--job-memory", "3G", "--worker-command", VDBWRAP_WORKER_HOOK});
  std::string id;
  {
    Client c(s.address());
    SubmitOutcome o = c.submit(data("fuze.obj"), "hang.obj", coarse());
    ASSERT_TRUE(o.status.ok());
    id = o.job_id;
  }
  for (int run = 1; run <= 2; ++run) {
    Client c(s.address());
    c.poll(id, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING && st.stage() == "read"; }, 30s);
    std::map<pid_t, char> workers = children_of(s.pid());
    ASSERT_EQ(workers.size(), 1u) << "run " << run;
    if (run == 1) {
      // How the server started it: fds 0-3 only, its own process group, the memory limit.
      const fs::path proc = "/proc/" + std::to_string(workers.begin()->first);
      std::set<std::string> fds;
      for (const auto& e : fs::directory_iterator(proc / "fd")) fds.insert(e.path().filename().string());
      EXPECT_EQ(fds, (std::set<std::string>{"0", "1", "2", "3"}));
      const std::string stat = read_file(proc / "stat");
      std::istringstream rest(stat.substr(stat.rfind(')') + 1));
      char state = 0;
      pid_t ppid = 0, pgrp = 0;
      rest >> state >> ppid >> pgrp;
      EXPECT_EQ(pgrp, workers.begin()->first);
      EXPECT_TRUE(std::regex_search(read_file(proc / "limits"), std::regex("Max data size +3221225472 +3221225472 ")))
          << read_file(proc / "limits");
    }
    EXPECT_EQ(s.kill(SIGKILL), 128 + SIGKILL);
    // The job's process does not outlive the server.
    EXPECT_TRUE(process_gone(workers.begin()->first, 10s)) << "run " << run;
    s.start();
  }
  Client c(s.address());
  pb::JobStatus st = c.wait_done(id, 30s);
  EXPECT_EQ(st.state(), pb::JOB_STATE_FAILED);
  EXPECT_NE(st.error_message().find("the server stopped 2 times while this job ran"), std::string::npos)
      << st.error_message();
  EXPECT_TRUE(children_of(s.pid()).empty());
  // Once failed, it stays failed: a further restart queues nothing.
  EXPECT_EQ(s.kill(SIGKILL), 128 + SIGKILL);
  s.start();
  Client again(s.address());
  EXPECT_EQ(again.status(id).state(), pb::JOB_STATE_FAILED);
  const std::string log = s.log();
  EXPECT_NE(log.rfind("0 job(s) queued again, 1 ended job(s) kept"), std::string::npos) << log;
  EXPECT_EQ(read_file(s.spool() / "jobs" / id / "attempts"), "2\n");
}

TEST_F(Service, RetainPrunesOldEndedJobs) {
  ServerProcess& s = server();
  std::string old_id, new_id;
  {
    Client c(s.address());
    old_id = c.submit_ok("two_objects_mixed_case_names.stl");
    new_id = c.submit_ok("unit_sphere.STL");
    ASSERT_EQ(c.wait_done(old_id).state(), pb::JOB_STATE_SUCCEEDED);
    ASSERT_EQ(c.wait_done(new_id).state(), pb::JOB_STATE_SUCCEEDED);
  }
  EXPECT_EQ(s.kill(SIGTERM), 0);
  // One job ended eight days ago.
  const fs::path record = s.spool() / "jobs" / old_id / "job.json";
  const int64_t eight_days_ago =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count() -
      8 * 86400 * 1000LL;
  const std::string json = std::regex_replace(read_file(record), std::regex("\"finished_unix_ms\": \"[0-9]+\""),
                                              "\"finished_unix_ms\": \"" + std::to_string(eight_days_ago) + "\"");
  ASSERT_NE(json, read_file(record));
  write_file(record, json);

  // The same spool, with a retention of seven days.
  servers_.push_back(std::make_unique<ServerProcess>(s.spool(), dir_ / "server_retain.log", std::vector<std::string>{"--retain", "7d"}));
  ServerProcess& kept = *servers_.back();
  kept.start();
  Client c(kept.address());
  pb::JobStatus gone;
  EXPECT_EQ(c.status(old_id, gone).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_FALSE(fs::exists(s.spool() / "jobs" / old_id));
  std::string bytes;
  EXPECT_TRUE(c.download(new_id, bytes).ok());
  EXPECT_EQ(kept.jobs_on_disk(), 1u);
  EXPECT_EQ(kept.kill(SIGTERM), 0);

  // Periodically too, and never a job that has not ended.
  ServerProcess& quick = server({"--retain", "2s", "--workers", "2", "--worker-command", VDBWRAP_WORKER_HOOK}, "b");
  Client q(quick.address());
  SubmitOutcome hanging = q.submit(data("fuze.obj"), "hang.obj", coarse());
  ASSERT_TRUE(hanging.status.ok());
  std::string done = q.submit_ok("two_objects_mixed_case_names.stl");
  ASSERT_EQ(q.wait_done(done).state(), pb::JOB_STATE_SUCCEEDED);
  EXPECT_TRUE(q.status(done, gone).ok()) << "pruned at once";
  const auto deadline = Clock::now() + 15s;
  while (Clock::now() < deadline && q.status(done, gone).error_code() != grpc::StatusCode::NOT_FOUND)
    std::this_thread::sleep_for(100ms);
  EXPECT_EQ(q.status(done, gone).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(q.status(hanging.job_id).state(), pb::JOB_STATE_RUNNING);
  EXPECT_EQ(quick.jobs_on_disk(), 1u);
  EXPECT_NE(quick.log().find("pruned"), std::string::npos);

  // A duration that is not one is refused at start.
  std::string cmd = std::string(VDBWRAP_SERVER) + " --listen 127.0.0.1:0 --spool " + (dir_ / "spool_c").string() +
                    " --retain 5x 2> " + (dir_ / "c.log").string();
  int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2);
  EXPECT_NE(read_file(dir_ / "c.log").find("--retain 5x"), std::string::npos);
}

}  // namespace
