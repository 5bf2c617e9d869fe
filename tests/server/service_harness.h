// The job service's test harness: real vdbwrap-server processes on 127.0.0.1 (any free port,
// temporary spools), a client over the generated vdbwrap.v1 stubs, the CLI, and the Service
// fixture that starts and stops them. Every wait is bounded in time.
#pragma once
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

namespace server_test {

namespace pb = vdbwrap::v1;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_file(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

inline std::string data(const std::string& name) { return read_file(vdbwrap::testing::data_path(name)); }

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
inline pb::WrapParameters coarse(double percent = 3) {
  pb::WrapParameters p;
  p.set_base_size_percent(percent);
  return p;
}
// A job that runs for several seconds on one thread (fuze.obj at 0.5 %).
inline pb::WrapParameters slow() {
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
    if (auto it = md.find("vdbwrap-error-kind"); it != md.end())
      out.error_kind = std::string(it->second.data(), it->second.size());
    peer_ = ctx.peer();
    return out;
  }

  std::string submit_ok(const std::string& name, const pb::WrapParameters& params = coarse(),
                        const std::string& key = "") {
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
    return poll(
        id,
        [](const pb::JobStatus& s) {
          return s.state() == pb::JOB_STATE_SUCCEEDED || s.state() == pb::JOB_STATE_FAILED ||
                 s.state() == pb::JOB_STATE_CANCELLED;
        },
        limit);
  }

  grpc::Status download(const std::string& id, std::string& bytes,
                        pb::MeshFormat format = pb::MESH_FORMAT_UNSPECIFIED) {
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

inline void expect_valid_result(const std::string& bytes, vdbwrap::io::Format format, const std::string& what) {
  ASSERT_FALSE(bytes.empty()) << what;
  vdbwrap::Mesh m = vdbwrap::io::read_mesh_from_bytes(bytes, format, what);
  // diagnose() welds bit-identical points first (STL stores 3 points per facet).
  vdbwrap::MeshDiagnostics d = vdbwrap::diagnose(m, true);
  EXPECT_TRUE(d.valid_closed_surface()) << what << ": closed " << d.closed << ", manifold " << d.manifold
                                        << ", oriented " << d.oriented << ", outward " << d.outward
                                        << ", self-intersecting " << d.self_intersecting;
}

inline std::string binary_stl(uint32_t declared, size_t triangles, float fill = 0.0f) {
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
    if (!HasFailure())
      fs::remove_all(dir_);
    else
      std::fprintf(stderr, "kept %s for inspection\n", dir_.c_str());
  }

  ServerProcess& server(std::vector<std::string> extra = {}, const std::string& name = "a") {
    servers_.push_back(
        std::make_unique<ServerProcess>(dir_ / ("spool_" + name), dir_ / ("server_" + name + ".log"), extra));
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

// grpc.health.v1.Health/Check through a generic call: the request is {service: NAME}
// (field 1), the answer {status: SERVING = 1} (field 1, varint).
inline int health(const std::shared_ptr<grpc::Channel>& channel, const std::string& service) {
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

}  // namespace server_test
