#include "remote.h"
#include "output_paths.h"
#include "repair_options.h"
#include "wrap_options.h"

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <memory>
#include <thread>

#include <nlohmann/json.hpp>

#include "params_mapping.h"
#include "vdbwrap/v1/jobs.grpc.pb.h"

namespace vdbwrap::remote {

namespace {

namespace pb = ::vdbwrap::v1;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr size_t kChunk = 1 << 20;

// --- connection --------------------------------------------------------------------------

struct Connection {
  std::string server;        // --server
  std::string token_file;    // --token-file
  std::string tls_ca;        // --tls-ca
  std::string tls_name;      // --tls-server-name
  bool round_robin = false;  // --round-robin
  double retry_seconds = 30;

  std::string token;
  std::string ca_pem;

  void load() {
    auto read = [](const std::string& path, const char* what) {
      std::ifstream in(path, std::ios::binary);
      if (!in) throw Error(ErrorKind::InvalidArgument, path + ": cannot read the " + what);
      std::stringstream ss;
      ss << in.rdbuf();
      return ss.str();
    };
    if (!token_file.empty()) {
      token = read(token_file, "token file");
      while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) token.pop_back();
      if (token.empty()) throw Error(ErrorKind::InvalidArgument, token_file + ": the token file is empty");
    }
    if (!tls_ca.empty()) ca_pem = read(tls_ca, "CA certificate");
  }

  // A channel to `target` (default: --server). name_override: TLS host name to check when
  // the target is an address found at run time.
  std::shared_ptr<grpc::Channel> channel(const std::string& target = "", bool balanced = false) const {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(16 << 20);
    if (balanced) args.SetLoadBalancingPolicyName("round_robin");
    std::shared_ptr<grpc::ChannelCredentials> creds;
    if (ca_pem.empty() && tls_name.empty()) {
      creds = grpc::InsecureChannelCredentials();
    } else {
      grpc::SslCredentialsOptions ssl;
      ssl.pem_root_certs = ca_pem;
      creds = grpc::SslCredentials(ssl);
      std::string name = tls_name;
      if (name.empty() && !target.empty() && target != server) name = host_of(server);
      if (!name.empty()) args.SetSslTargetNameOverride(name);
    }
    return grpc::CreateCustomChannel(target.empty() ? server : target, creds, args);
  }

  void prepare(grpc::ClientContext& ctx) const {
    if (!token.empty()) ctx.AddMetadata("authorization", "Bearer " + token);
  }

  // The host name of a target ("h:p", "dns:///h:p", "ipv4:a:p,b:p", "ipv6:[::1]:p"): the
  // name the server's certificate must carry when the CLI connects to an address found at
  // run time (the replica that accepted a job).
  static std::string host_of(std::string target) {
    if (auto p = target.find(":///"); p != std::string::npos)
      target = target.substr(p + 4);
    else if (target.rfind("ipv4:", 0) == 0 || target.rfind("ipv6:", 0) == 0)
      target = target.substr(5);
    else if (target.rfind("dns:", 0) == 0)
      target = target.substr(4);
    target = target.substr(0, target.find(','));
    if (!target.empty() && target.front() == '[') return target.substr(1, target.find(']') - 1);
    const auto colon = target.rfind(':');
    if (colon != std::string::npos && target.find(':') == colon) target = target.substr(0, colon);
    return target;
  }
};

// The exit code of a failed call, like the local wrap's.
int exit_code_of(const grpc::Status& st, const grpc::ClientContext& ctx) {
  const auto& md = ctx.GetServerTrailingMetadata();
  auto it = md.find(api::kErrorKindMetadata);
  if (it != md.end()) {
    int kind = std::atoi(std::string(it->second.data(), it->second.size()).c_str());
    if (kind >= 1 && kind <= 6) return kind;
  }
  switch (st.error_code()) {
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::UNAUTHENTICATED:
    case grpc::StatusCode::PERMISSION_DENIED:
    case grpc::StatusCode::NOT_FOUND:
      return exit_code(ErrorKind::InvalidArgument);
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return exit_code(ErrorKind::InvalidInput);  // upload too large
    default:
      return exit_code(ErrorKind::Internal);
  }
}

const char* code_name(grpc::StatusCode c) {
  switch (c) {
    case grpc::StatusCode::CANCELLED:
      return "CANCELLED";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND:
      return "NOT_FOUND";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    case grpc::StatusCode::UNAUTHENTICATED:
      return "UNAUTHENTICATED";
    case grpc::StatusCode::INTERNAL:
      return "INTERNAL";
    default:
      return "ERROR";
  }
}

std::string describe(const grpc::Status& st) {
  return std::string(code_name(st.error_code())) + ": " + st.error_message();
}

// --- progress display --------------------------------------------------------------------

// A progress bar per job on a terminal (redrawn in place), plain lines otherwise.
class Display {
 public:
  Display(bool quiet, std::vector<std::string> names) : quiet_(quiet), names_(std::move(names)) {
    tty_ = ::isatty(2) == 1;
    lines_.resize(names_.size());
    width_ = 0;
    for (auto& n : names_) width_ = std::max(width_, n.size());
    width_ = std::min<size_t>(width_, 32);
    start_ = Clock::now();
  }
  ~Display() { finish(); }

  void event(size_t i, const pb::ProgressEvent& ev) {
    if (quiet_) return;
    std::lock_guard<std::mutex> g(lock_);
    const char* state = api::state_name(ev.state());
    if (!tty_) {
      std::string prefix = names_.size() > 1 ? pad(names_[i]) + " " : std::string();
      std::fprintf(stderr, "[%7.2fs] %s%-15s %3.0f%%  %s%s\n", elapsed(), prefix.c_str(),
                   ev.stage().empty() ? state : ev.stage().c_str(), 100.0 * ev.fraction(), ev.message().c_str(),
                   ev.state() == pb::JOB_STATE_QUEUED ? " (queued)" : "");
      std::fflush(stderr);
      return;
    }
    const int cells = 20;
    int filled = int(std::clamp(ev.fraction(), 0.0, 1.0) * cells + 0.5);
    if (ev.state() == pb::JOB_STATE_SUCCEEDED) filled = cells;
    std::string bar = "[" + std::string(size_t(filled), '#') + std::string(size_t(cells - filled), '-') + "]";
    char pct[16];
    std::snprintf(pct, sizeof pct, "%3.0f%%", 100.0 * ev.fraction());
    std::string stage = ev.stage().empty() || api::is_final(ev.state()) || ev.state() == pb::JOB_STATE_QUEUED
                            ? std::string(state)
                            : ev.stage();
    lines_[i] =
        pad(names_[i]) + " " + bar + " " + pct + " " + stage + (ev.message() == stage ? "" : ": " + ev.message());
    redraw(api::is_final(ev.state()));
  }

  // A final line for job i (replaces its bar on a terminal).
  void note(size_t i, const std::string& text) {
    std::lock_guard<std::mutex> g(lock_);
    if (quiet_ && text.rfind("error", 0) != 0) return;
    if (!tty_ || quiet_) {
      std::fprintf(stderr, "%s\n", text.c_str());
      std::fflush(stderr);
      return;
    }
    lines_[i] = text;
    redraw(true);
  }

  void finish() {
    std::lock_guard<std::mutex> g(lock_);
    if (tty_ && !quiet_ && drawn_ > 0) redraw(true);
    drawn_ = 0;
  }

 private:
  std::string pad(const std::string& n) const {
    std::string s = n.size() > width_ ? n.substr(0, width_ - 3) + "..." : n;
    return s + std::string(width_ - s.size(), ' ');
  }
  double elapsed() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  void redraw(bool force) {
    auto now = Clock::now();
    if (!force && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    struct winsize ws {};
    size_t cols = (::ioctl(2, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 10) ? ws.ws_col : 100;
    std::string out;
    if (drawn_ > 0) out += "\033[" + std::to_string(drawn_) + "A";
    for (const auto& l : lines_) out += "\r\033[K" + (l.size() >= cols ? l.substr(0, cols - 1) : l) + "\n";
    drawn_ = lines_.size();
    std::fputs(out.c_str(), stderr);
    std::fflush(stderr);
  }

  bool quiet_, tty_ = false;
  std::vector<std::string> names_;
  std::vector<std::string> lines_;
  size_t width_;
  size_t drawn_ = 0;
  Clock::time_point start_, last_draw_{};
  std::mutex lock_;
};

// --- one job: follow it, download it ----------------------------------------------------

struct Target {
  std::string output;     // result file
  std::string report;     // report file, or empty
  std::string leak_path;  // where a leak's passage and path go (OBJ), or empty
};

std::string random_key() {
  std::random_device rd;
  char hex[33];
  std::snprintf(hex, sizeof hex, "%08x%08x%08x%08x", rd(), rd(), rd(), rd());
  return hex;
}

void write_file(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(ErrorKind::OutputFailed, path + ": cannot write");
    out.write(bytes.data(), std::streamsize(bytes.size()));
    if (!out) throw Error(ErrorKind::OutputFailed, path + ": cannot write");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw Error(ErrorKind::OutputFailed, path + ": cannot write");
}

// A call retried while the server is unreachable, for up to --retry seconds. wait_for_ready
// covers a server not up yet; a call in flight when the server goes down (a crash, a restart)
// fails at once with UNAVAILABLE, and is made again. `ctx` is the last attempt's context (its
// trailing metadata give the exit code). The calls retried must be safe to repeat. A bounded
// call has a deadline (30 s at most); a download is not bounded (a large result takes longer).
template <typename Call>
grpc::Status call_retrying(const Connection& conn, std::unique_ptr<grpc::ClientContext>& ctx, Call&& call,
                           bool bounded = true) {
  const auto give_up =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(conn.retry_seconds));
  for (int attempt = 0;; ++attempt) {
    ctx = std::make_unique<grpc::ClientContext>();
    conn.prepare(*ctx);
    // Unbounded, it fails fast while nothing listens (else it would wait for ever), and the
    // loop tries again.
    ctx->set_wait_for_ready(bounded);
    const auto left = std::max<Clock::duration>(std::chrono::seconds(1), give_up - Clock::now());
    if (bounded)
      ctx->set_deadline(std::chrono::system_clock::now() +
                        std::chrono::duration_cast<std::chrono::system_clock::duration>(
                            std::min<Clock::duration>(left, std::chrono::seconds(30))));
    grpc::Status st = call(*ctx);
    if (st.error_code() != grpc::StatusCode::UNAVAILABLE || Clock::now() > give_up) return st;
    std::this_thread::sleep_for(std::chrono::milliseconds(std::min(2000, 200 * (attempt + 1))));
  }
}

// Watches job `id` on `channel` until it ends (reconnecting while the server restarts), then
// downloads its result into target. Returns the exit code.
int follow(const Connection& conn, const std::shared_ptr<grpc::Channel>& channel, const std::string& id,
           const Target& target, pb::MeshFormat format, Display& display, size_t index) {
  auto stub = pb::Jobs::NewStub(channel);
  const auto give_up =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(conn.retry_seconds));
  // Watch until a final state.
  for (int attempt = 0;; ++attempt) {
    grpc::ClientContext ctx;
    conn.prepare(ctx);
    ctx.set_wait_for_ready(attempt > 0);
    pb::JobId req;
    req.set_job_id(id);
    auto reader = stub->Watch(&ctx, req);
    pb::ProgressEvent ev;
    bool ended = false;
    while (reader->Read(&ev)) {
      display.event(index, ev);
      if (api::is_final(ev.state())) ended = true;
    }
    grpc::Status st = reader->Finish();
    if (ended) break;
    if (st.ok()) continue;  // the stream ended without a final state: watch again
    const bool transient = st.error_code() == grpc::StatusCode::UNAVAILABLE;
    if (!transient || Clock::now() > give_up) {
      display.note(index, "error: job " + id + ": " + describe(st));
      return exit_code_of(st, ctx);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(std::min(2000, 200 * (attempt + 1))));
  }
  // Final status and report.
  pb::JobStatus status;
  {
    std::unique_ptr<grpc::ClientContext> ctx;
    pb::JobId req;
    req.set_job_id(id);
    grpc::Status st =
        call_retrying(conn, ctx, [&](grpc::ClientContext& c) { return stub->GetStatus(&c, req, &status); });
    if (!st.ok()) {
      display.note(index, "error: job " + id + ": " + describe(st));
      return exit_code_of(st, *ctx);
    }
  }
  if (status.state() != pb::JOB_STATE_SUCCEEDED) {
    display.note(index, "error: job " + id + " (" + status.spec().file_name() + ") " + api::state_name(status.state()) +
                            ": " + status.error_message());
    // A failed job's report (a leak's location) is kept like a successful one's.
    if (!status.report_json().empty()) {
      try {
        if (!target.report.empty()) write_file(target.report, status.report_json() + "\n");
        const LeakReport leak = leak_from_report_json(status.report_json());
        if (leak.detected && !target.leak_path.empty()) {
          write_file(target.leak_path, leak_to_obj(leak));
          display.note(index, "leak: narrowest passage and path written to " + target.leak_path);
        }
      } catch (const Error&) {
      }
    }
    return exit_code(api::to_error_kind(status.error_kind()));
  }
  // Download, straight to OUTPUT.tmp; renamed when complete. Made again from the start while
  // the server is unreachable (it keeps finished jobs across a restart).
  const std::string tmp = target.output + ".tmp";
  {
    std::unique_ptr<grpc::ClientContext> ctx;
    uint64_t total = 0, got = 0;
    bool written = true;
    pb::DownloadRequest req;
    req.set_job_id(id);
    req.set_format(format);
    grpc::Status st = call_retrying(
        conn, ctx,
        [&](grpc::ClientContext& c) {
          std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
          total = got = 0;
          auto reader = stub->Download(&c, req);
          pb::DownloadChunk chunk;
          bool first = true;
          while (reader->Read(&chunk)) {
            if (first) total = chunk.total_size();
            first = false;
            out.write(chunk.data().data(), std::streamsize(chunk.data().size()));
            got += chunk.data().size();
          }
          grpc::Status s = reader->Finish();
          out.close();
          written = bool(out);
          return s;
        },
        false);
    if (!st.ok() || got != total || !written) {
      std::remove(tmp.c_str());
      if (!st.ok()) {
        display.note(index, "error: job " + id + ": download failed: " + describe(st));
        return exit_code_of(st, *ctx);
      }
      display.note(index,
                   "error: job " + id + (got != total ? ": download incomplete" : ": cannot write " + target.output));
      return exit_code(got != total ? ErrorKind::Internal : ErrorKind::OutputFailed);
    }
  }
  try {
    if (std::rename(tmp.c_str(), target.output.c_str()) != 0)
      throw Error(ErrorKind::OutputFailed, target.output + ": cannot write");
    if (!target.report.empty()) write_file(target.report, status.report_json() + "\n");
  } catch (const Error& e) {
    display.note(index, std::string("error: ") + e.what());
    return exit_code(e.kind());
  }
  char line[512];
  std::snprintf(line, sizeof line, "wrote %s: %llu triangles (job %s)%s%s", target.output.c_str(),
                static_cast<unsigned long long>(status.output_triangles()), id.c_str(),
                target.report.empty() ? "" : "; report ", target.report.c_str());
  display.note(index, line);
  // A repair that left intersections: the result is written, the exit code says so (as
  // `vdbwrap repair`).
  if (api::is_repair(status.spec()) && status.intersecting_pairs_left() > 0) {
    display.note(index, "error: job " + id + ": " + std::to_string(status.intersecting_pairs_left()) +
                            " intersecting pairs left in the result (written; the report lists where)");
    return exit_code(ErrorKind::WrapFailed);
  }
  return 0;
}

std::string stem_of(const std::string& file_name) {
  std::string s = fs::path(file_name).stem().string();
  for (char& c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) c = '_';
  return s.empty() ? std::string("job") : s;
}

// Outputs in DIR for names, unique within this run: NAME_wrap, or NAME_repaired for repair jobs.
std::vector<Target> targets_in(const std::string& dir, const std::vector<std::string>& stems, const std::string& ext,
                               const std::vector<std::string>& ids, const std::vector<bool>& repairs = {}) {
  std::vector<Target> out;
  std::map<std::string, int> seen;
  for (size_t i = 0; i < stems.size(); ++i) {
    std::string base = stems[i] + (i < repairs.size() && repairs[i] ? "_repaired" : "_wrap");
    if (seen[base]++ > 0) base += "_" + (i < ids.size() && !ids[i].empty() ? ids[i].substr(0, 8) : std::to_string(i));
    out.push_back({(fs::path(dir) / (base + "." + ext)).string(), (fs::path(dir) / (base + ".json")).string()});
  }
  return out;
}

int worst(const std::vector<int>& codes) {
  for (int c : codes)
    if (c != 0) return c;
  return 0;
}

// Runs follow() for every job at once (the server runs them concurrently).
std::vector<int> follow_all(const Connection& conn, const std::vector<std::shared_ptr<grpc::Channel>>& channels,
                            const std::vector<std::string>& ids, const std::vector<Target>& targets,
                            const std::vector<pb::MeshFormat>& formats, Display& display) {
  std::vector<int> codes(ids.size(), 0);
  std::vector<std::thread> threads;
  for (size_t i = 0; i < ids.size(); ++i)
    threads.emplace_back([&, i] {
      try {
        codes[i] = follow(conn, channels[i], ids[i], targets[i], formats[i], display, i);
      } catch (const std::exception& e) {
        display.note(i, std::string("error: ") + e.what());
        codes[i] = exit_code(ErrorKind::Internal);
      }
    });
  for (auto& t : threads) t.join();
  display.finish();
  return codes;
}

}  // namespace

// --- the subcommands -----------------------------------------------------------------------

struct RemoteCommands::Impl {
  CLI::App* submit = nullptr;
  CLI::App* wait = nullptr;
  CLI::App* jobs = nullptr;
  CLI::App* cancel = nullptr;
  CLI::App* remove = nullptr;
  CLI::App* health = nullptr;
  Connection conn;
  std::string health_service = "vdbwrap.v1.Jobs";

  // submit
  std::vector<std::string> inputs;
  std::string output, out_dir, format, report, leak_path;
  cli::WrapOptions wrap_options;
  cli::RepairOptions repair_options;
  bool detach = false, quiet = false, repair_job = false;
  double queue_wait = 600;
  // --server and --token-file, per command (see add_connection).
  struct EnvBacked {
    std::string server, token_file;
  };
  std::map<const CLI::App*, EnvBacked> env_backed;  // nodes stay put: the options point into them
  // wait / cancel / delete
  std::vector<std::string> ids;
  bool json_list = false;  // jobs --json

  void add_connection(CLI::App* cmd) {
    // Each command's own strings for the options backed by the environment: CLI11 fills them
    // from it in every command, given or not, and one shared string would take the last.
    EnvBacked& own = env_backed[cmd];
    cmd->add_option("--server", own.server,
                    "Server address HOST:PORT, or a gRPC target (ipv4:H1:P1,H2:P2, dns:///name:port)")
        ->required()
        ->envname("VDBWRAP_SERVER")
        ->group("Server");
    // No ExistingFile check: CLI11 would apply it to the environment's value in every command,
    // `vdbwrap wrap` included; Connection::load() says when the file cannot be read.
    cmd->add_option("--token-file", own.token_file, "File holding the server's bearer token")
        ->envname("VDBWRAP_TOKEN_FILE")
        ->group("Server");
    cmd->add_option("--tls-ca", conn.tls_ca,
                    "PEM file of the CA that signed the server's certificate: connect with TLS")
        ->check(CLI::ExistingFile)
        ->group("Server");
    cmd->add_option("--tls-server-name", conn.tls_name, "Host name to expect in the server's certificate (TLS)")
        ->group("Server");
    cmd->add_option("--retry", conn.retry_seconds, "Seconds to keep retrying while the server is unreachable")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber)
        ->group("Server");
  }

  explicit Impl(CLI::App& app) {
    submit = app.add_subcommand(
        "submit",
        "Wrap (or with --repair, repair) INPUT... on a vdbwrap-server: upload, show progress, download the results");
    add_connection(submit);
    submit
        ->add_option("input", inputs,
                     "Input meshes (.stl .obj .off .ply .vtp .nas .bdf); several run concurrently on the server")
        ->required()
        ->check(CLI::ExistingFile);
    // The wrap options, as in `vdbwrap wrap`; with --repair, the repair options of `vdbwrap repair`.
    wrap_options.add_to(submit, "Worker threads on the server (0: all its cores)");
    submit->add_option("-o,--output", output, "Output mesh (one input); the format follows the extension")
        ->group("Output");
    submit
        ->add_option("--out-dir", out_dir,
                     "Folder for the results NAME_wrap.EXT (repairs: NAME_repaired.EXT) and reports NAME_wrap.json; "
                     "created when missing")
        ->group("Output");
    submit->add_option("--format", format, "Output format with --out-dir (default: the input's)")
        ->check(CLI::IsMember({"stl", "obj", "off", "ply"}))
        ->group("Output");
    submit->add_option("--report", report, "Write the JSON report (one input)")->group("Output");
    submit
        ->add_option(
            "--leak-path", leak_path,
            "When a seed point's volume leaks: write the narrowest passage and the path to it here (OBJ; one input)")
        ->group("Output");
    submit->add_flag("-q,--quiet", quiet, "No progress on stderr")->group("Output");
    submit->add_flag("--detach", detach, "Print the job ids (one per line) once accepted and exit; see `vdbwrap wait`")
        ->group("Job");
    submit
        ->add_flag("--round-robin", conn.round_robin,
                   "Spread the jobs over every address of --server (gRPC round_robin); each job is then followed on "
                   "the server that accepted it")
        ->group("Job");
    submit->add_option("--queue-wait", queue_wait, "Seconds to keep retrying while the server's queue is full")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber)
        ->group("Job");
    submit
        ->add_flag("--repair", repair_job,
                   "Repair the self-intersections of each input locally, as `vdbwrap repair`, instead of wrapping it "
                   "(takes the repair options below, not the wrap options; exit code 4 when intersections are left)")
        ->group("Job");
    repair_options.add_to(submit, false);
    submit->footer(
        "Examples:\n"
        "  vdbwrap submit --server host:50051 part.stl -o part_wrap.stl --base-size 0.5% --report part_wrap.json\n"
        "  vdbwrap submit --server host:50051 a.stl b.obj --out-dir results --format stl\n"
        "  vdbwrap submit --server host:50051 a.stl b.stl --detach > ids.txt; vdbwrap wait --server host:50051 $(cat "
        "ids.txt)\n"
        "The server's address and token file can come from VDBWRAP_SERVER and VDBWRAP_TOKEN_FILE.");

    wait = app.add_subcommand("wait", "Wait for jobs on a vdbwrap-server and download their results");
    add_connection(wait);
    wait->add_option("id", ids, "Job ids")->required();
    wait->add_option("--out-dir", out_dir,
                     "Folder for the results NAME_wrap.EXT (repairs: NAME_repaired.EXT) and reports NAME_wrap.json; "
                     "created when missing")
        ->capture_default_str()
        ->group("Output");
    wait->add_flag("-q,--quiet", quiet, "No progress on stderr")->group("Output");

    jobs = app.add_subcommand("jobs", "List the jobs of a vdbwrap-server with their state");
    add_connection(jobs);
    jobs->add_flag("--json", json_list, "Print the jobs as a JSON array, one object per job (for scripts)");

    cancel = app.add_subcommand("cancel", "Cancel jobs on a vdbwrap-server");
    add_connection(cancel);
    cancel->add_option("id", ids, "Job ids")->required();

    remove = app.add_subcommand("delete",
                                "Delete ended jobs and their files from a vdbwrap-server (cancel a running job first)");
    add_connection(remove);
    remove->add_option("id", ids, "Job ids")->required();

    health =
        app.add_subcommand("health", "Exit 0 when the server's gRPC health service answers SERVING (no token needed)");
    add_connection(health);
    health->add_option("--service", health_service, "Service name to ask about (empty: the whole server)")
        ->capture_default_str();
  }

  int run_submit();
  int run_wait();
  int run_jobs();
  int run_cancel();
  int run_delete();
  template <typename Reply, typename Rpc, typename Done, typename CodeOf>
  int for_each_job(Rpc rpc, Done done, CodeOf code_of);
  int run_health();
};

// grpc.health.v1.Health/Check through a generic call (no generated code needed): the request
// is {service: NAME} (field 1, string), the answer {status} (field 1, varint; 1 = SERVING).
int RemoteCommands::Impl::run_health() {
  conn.load();
  if (health_service.size() > 127) throw Error(ErrorKind::InvalidArgument, "--service: name too long");
  grpc::GenericStub stub(conn.channel());
  std::string request;
  if (!health_service.empty()) request = std::string("\x0a") + char(health_service.size()) + health_service;
  grpc::Slice slice(request);
  grpc::ByteBuffer in(&slice, 1), out;
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() +
                   std::chrono::duration_cast<std::chrono::system_clock::duration>(
                       std::chrono::duration<double>(std::max(1.0, std::min(conn.retry_seconds, 10.0)))));
  std::mutex m;
  std::condition_variable cv;
  bool done = false;
  grpc::Status status;
  stub.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &in, &out, [&](grpc::Status st) {
    std::lock_guard<std::mutex> g(m);
    status = st;
    done = true;
    cv.notify_all();
  });
  {
    std::unique_lock<std::mutex> g(m);
    cv.wait(g, [&] { return done; });  // the call's deadline bounds this
  }
  if (!status.ok()) {
    std::fprintf(stderr, "vdbwrap: health: %s\n", describe(status).c_str());
    return exit_code(ErrorKind::Internal);
  }
  std::vector<grpc::Slice> slices;
  out.Dump(&slices);
  std::string bytes;
  for (auto& sl : slices) bytes.append(reinterpret_cast<const char*>(sl.begin()), sl.size());
  const bool serving = bytes.size() >= 2 && bytes[0] == 0x08 && bytes[1] == 0x01;
  std::printf("%s\n", serving ? "SERVING" : "NOT_SERVING");
  return serving ? 0 : exit_code(ErrorKind::Internal);
}

int RemoteCommands::Impl::run_submit() {
  if (inputs.size() > 1 && !output.empty())
    throw Error(ErrorKind::InvalidArgument, "-o names one output: use --out-dir DIR with several inputs");
  if (!detach && output.empty() && out_dir.empty())
    throw Error(ErrorKind::InvalidArgument, "give -o OUTPUT, --out-dir DIR or --detach");
  if (!report.empty() && inputs.size() > 1)
    throw Error(ErrorKind::InvalidArgument,
                "--report names one file: with --out-dir the reports are NAME_wrap.json (NAME_repaired.json)");
  if (!output.empty() && io::format_from_extension(output) == io::Format::Unknown)
    throw Error(ErrorKind::InvalidArgument,
                output + ": unknown output format (use .stl, .obj, .off, .ply, .vtp, .nas or .bdf)");
  cli::check_output_path("-o", output);
  cli::check_output_path("--report", report);
  cli::check_output_path("--leak-path", leak_path);
  // The job's parameters: a wrap's, or with --repair a repair's (and not the other's).
  pb::WrapParameters wire_params;
  pb::RepairParameters wire_repair;
  if (repair_job) {
    for (const std::string& name : wrap_options.given())
      if (name != "--threads")
        throw Error(ErrorKind::InvalidArgument, name + " is a wrap option: it has no meaning with --repair");
    if (!leak_path.empty())
      throw Error(ErrorKind::InvalidArgument, "--leak-path is a wrap option: it has no meaning with --repair");
    RepairParams rp = repair_options.resolve();
    rp.threads = wrap_options.resolve().threads;
    wire_repair = api::to_proto(rp);
    api::to_repair_params(wire_repair);  // the server's checks, here first
  } else {
    const std::vector<std::string> stray = repair_options.given();
    if (!stray.empty()) throw Error(ErrorKind::InvalidArgument, stray.front() + " is a repair option: add --repair");
    wire_params = api::to_proto(wrap_options.resolve());
  }
  conn.load();
  if (!out_dir.empty() && !detach) cli::ensure_output_folder("--out-dir", out_dir);

  // Output format per input.
  std::vector<pb::MeshFormat> formats;
  std::vector<std::string> names, stems;
  for (const auto& in : inputs) {
    pb::MeshFormat f = pb::MESH_FORMAT_UNSPECIFIED;
    if (!output.empty())
      f = api::format_from_file_name(output);
    else if (!format.empty())
      f = api::format_from_file_name("x." + format);
    else
      f = api::format_from_file_name(in);
    if (f == pb::MESH_FORMAT_UNSPECIFIED) f = pb::MESH_FORMAT_PLY;
    formats.push_back(f);
    names.push_back(fs::path(in).filename().string());
    stems.push_back(stem_of(in));
  }

  auto channel = conn.channel(conn.server, conn.round_robin);
  auto stub = pb::Jobs::NewStub(channel);

  // Upload every input; retried with the same idempotency key while the server is
  // unreachable or its queue is full.
  std::vector<std::string> ids(inputs.size());
  std::vector<std::shared_ptr<grpc::Channel>> job_channels(inputs.size(), channel);
  std::vector<int> codes(inputs.size(), 0);
  for (size_t i = 0; i < inputs.size(); ++i) {
    pb::JobSpec spec;
    spec.set_file_name(names[i]);
    spec.set_input_format(api::format_from_file_name(inputs[i]));
    if (repair_job) {
      spec.set_kind(pb::JOB_KIND_REPAIR);
      *spec.mutable_repair_params() = wire_repair;
    } else {
      *spec.mutable_params() = wire_params;
    }
    spec.set_output_format(formats[i]);
    spec.set_idempotency_key(random_key());
    std::error_code ec;
    spec.set_size_bytes(fs::file_size(inputs[i], ec));
    const auto start = Clock::now();
    for (int attempt = 0;; ++attempt) {
      grpc::ClientContext ctx;
      conn.prepare(ctx);
      ctx.set_wait_for_ready(attempt > 0);
      if (attempt > 0) ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
      pb::SubmitReply reply;
      std::unique_ptr<grpc::ClientWriter<pb::SubmitRequest>> writer(stub->Submit(&ctx, &reply));
      pb::SubmitRequest req;
      *req.mutable_spec() = spec;
      bool open = writer->Write(req);
      std::ifstream in(inputs[i], std::ios::binary);
      if (!in) throw Error(ErrorKind::InvalidInput, inputs[i] + ": cannot open");
      std::string buf(kChunk, '\0');
      while (open && in) {
        in.read(buf.data(), std::streamsize(kChunk));
        if (in.gcount() == 0) break;
        req.set_chunk(buf.data(), size_t(in.gcount()));
        open = writer->Write(req);
      }
      if (open) writer->WritesDone();
      grpc::Status st = writer->Finish();
      if (st.ok()) {
        ids[i] = reply.job_id();
        // Spread over replicas: follow each job on the replica that accepted it (the
        // address this call reached; else the one the server advertises). Otherwise the
        // channel's one connection stays on one server.
        if (conn.round_robin) {
          if (!ctx.peer().empty())
            job_channels[i] = conn.channel(ctx.peer());
          else if (!reply.server().empty())
            job_channels[i] = conn.channel(reply.server());
        }
        break;
      }
      const double waited = std::chrono::duration<double>(Clock::now() - start).count();
      const bool queue_full = st.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED &&
                              st.error_message().find("queue is full") != std::string::npos;
      const bool unreachable = st.error_code() == grpc::StatusCode::UNAVAILABLE;
      if ((queue_full && waited < queue_wait) || (unreachable && waited < conn.retry_seconds)) {
        if (attempt == 0 && !quiet)
          std::fprintf(stderr, "%s: %s; retrying\n", names[i].c_str(), st.error_message().c_str());
        std::this_thread::sleep_for(std::chrono::milliseconds(std::min(5000, 500 * (attempt + 1))));
        continue;
      }
      std::fprintf(stderr, "vdbwrap: error: %s: %s\n", inputs[i].c_str(), describe(st).c_str());
      codes[i] = exit_code_of(st, ctx);
      break;
    }
  }
  if (detach) {
    for (const auto& id : ids)
      if (!id.empty()) std::printf("%s\n", id.c_str());
    std::fflush(stdout);
    return worst(codes);
  }

  std::vector<Target> targets;
  if (!output.empty())
    targets.push_back({output, report, leak_path});
  else
    targets = targets_in(out_dir, stems, api::extension_of(formats.empty() ? pb::MESH_FORMAT_PLY : formats[0]), ids,
                         std::vector<bool>(ids.size(), repair_job));
  if (output.empty() && format.empty())  // per-input formats
    for (size_t i = 0; i < targets.size(); ++i)
      targets[i].output = fs::path(targets[i].output).replace_extension(api::extension_of(formats[i])).string();

  // Follow the accepted jobs.
  std::vector<size_t> accepted;
  for (size_t i = 0; i < ids.size(); ++i)
    if (!ids[i].empty()) accepted.push_back(i);
  std::vector<std::string> a_ids, a_names;
  std::vector<Target> a_targets;
  std::vector<pb::MeshFormat> a_formats;
  std::vector<std::shared_ptr<grpc::Channel>> a_channels;
  for (size_t i : accepted) {
    a_ids.push_back(ids[i]);
    a_names.push_back(names[i]);
    a_targets.push_back(targets[i]);
    a_formats.push_back(formats[i]);
    a_channels.push_back(job_channels[i]);
  }
  Display follow_display(quiet, a_names);
  std::vector<int> a_codes = follow_all(conn, a_channels, a_ids, a_targets, a_formats, follow_display);
  for (size_t k = 0; k < accepted.size(); ++k) codes[accepted[k]] = a_codes[k];
  return worst(codes);
}

int RemoteCommands::Impl::run_wait() {
  conn.load();
  if (out_dir.empty()) out_dir = ".";
  cli::ensure_output_folder("--out-dir", out_dir);
  auto channel = conn.channel();
  auto stub = pb::Jobs::NewStub(channel);
  // Names and formats from the server.
  std::vector<std::string> names, stems;
  std::vector<pb::MeshFormat> formats;
  std::vector<bool> repairs;
  for (const auto& id : ids) {
    std::unique_ptr<grpc::ClientContext> ctx;
    pb::JobId req;
    req.set_job_id(id);
    pb::JobStatus status;
    grpc::Status st =
        call_retrying(conn, ctx, [&](grpc::ClientContext& c) { return stub->GetStatus(&c, req, &status); });
    if (!st.ok()) {
      std::fprintf(stderr, "vdbwrap: error: job %s: %s\n", id.c_str(), describe(st).c_str());
      return exit_code_of(st, *ctx);
    }
    names.push_back(status.spec().file_name().empty() ? id : status.spec().file_name());
    stems.push_back(stem_of(names.back()));
    formats.push_back(status.spec().output_format());
    repairs.push_back(api::is_repair(status.spec()));
  }
  std::vector<Target> targets = targets_in(out_dir, stems, "ply", ids, repairs);
  for (size_t i = 0; i < targets.size(); ++i)
    targets[i].output = fs::path(targets[i].output).replace_extension(api::extension_of(formats[i])).string();
  Display display(quiet, names);
  std::vector<std::shared_ptr<grpc::Channel>> channels(ids.size(), channel);
  return worst(follow_all(conn, channels, ids, targets, formats, display));
}

int RemoteCommands::Impl::run_jobs() {
  conn.load();
  auto stub = pb::Jobs::NewStub(conn.channel());
  grpc::ClientContext ctx;
  conn.prepare(ctx);
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  pb::ListReply reply;
  grpc::Status st = stub->List(&ctx, pb::ListRequest(), &reply);
  if (!st.ok()) {
    std::fprintf(stderr, "vdbwrap: error: %s\n", describe(st).c_str());
    return exit_code_of(st, ctx);
  }
  if (json_list) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& j : reply.jobs()) {
      // "ERROR_KIND_WRAP_FAILED" -> "wrap_failed"; empty when the job has no error.
      std::string kind;
      if (j.error_kind() != pb::ERROR_KIND_UNSPECIFIED) {
        kind = pb::ErrorKind_Name(j.error_kind()).substr(std::string("ERROR_KIND_").size());
        for (char& c : kind) c = char(std::tolower(static_cast<unsigned char>(c)));
      }
      list.push_back({{"id", j.job_id()},
                      {"state", api::state_name(j.state())},
                      {"kind", api::is_repair(j.spec()) ? "repair" : "wrap"},
                      {"file_name", j.spec().file_name()},
                      {"submitted_unix_ms", j.submitted_unix_ms()},
                      {"started_unix_ms", j.started_unix_ms()},
                      {"finished_unix_ms", j.finished_unix_ms()},
                      {"stage", j.stage()},
                      {"fraction", j.fraction()},
                      {"message", j.message()},
                      {"error_kind", kind},
                      {"error_message", j.error_message()},
                      {"input_bytes", j.input_bytes()},
                      {"result_bytes", j.result_bytes()},
                      {"output_triangles", j.output_triangles()},
                      {"server", j.server()}});
    }
    std::printf("%s\n", list.dump(2).c_str());
    return 0;
  }
  std::printf("%-32s  %-9s  %-19s  %-24s  %s\n", "ID", "STATE", "SUBMITTED", "PROGRESS", "FILE");
  for (const auto& j : reply.jobs()) {
    std::time_t t = std::time_t(j.submitted_unix_ms() / 1000);
    std::tm tm{};
    localtime_r(&t, &tm);
    char when[32];
    std::strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S", &tm);
    char progress[64] = "";
    if (j.state() == pb::JOB_STATE_RUNNING)
      std::snprintf(progress, sizeof progress, "%s %.0f%%", j.stage().c_str(), 100 * j.fraction());
    std::string detail = j.state() == pb::JOB_STATE_FAILED ? j.error_message() : std::string();
    std::printf("%-32s  %-9s  %-19s  %-24s  %s%s%s\n", j.job_id().c_str(), api::state_name(j.state()), when, progress,
                j.spec().file_name().c_str(), detail.empty() ? "" : ": ", detail.c_str());
  }
  return 0;
}

// Calls `rpc(stub, ctx, request)` for each job id; on an error, prints it and keeps the first
// exit code (`code_of` maps the failed status), else prints `done(reply)` after the id.
template <typename Reply, typename Rpc, typename Done, typename CodeOf>
int RemoteCommands::Impl::for_each_job(Rpc rpc, Done done, CodeOf code_of) {
  conn.load();
  auto stub = pb::Jobs::NewStub(conn.channel());
  int code = 0;
  for (const auto& id : ids) {
    grpc::ClientContext ctx;
    conn.prepare(ctx);
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    pb::JobId req;
    req.set_job_id(id);
    Reply reply;
    const grpc::Status st = rpc(*stub, &ctx, req, &reply);
    if (!st.ok()) {
      std::fprintf(stderr, "vdbwrap: error: job %s: %s\n", id.c_str(), describe(st).c_str());
      if (code == 0) code = code_of(st, ctx);
      continue;
    }
    std::printf("%s %s\n", id.c_str(), done(reply));
  }
  return code;
}

int RemoteCommands::Impl::run_cancel() {
  return for_each_job<pb::JobStatus>(
      [](pb::Jobs::Stub& stub, grpc::ClientContext* ctx, const pb::JobId& req, pb::JobStatus* status) {
        return stub.Cancel(ctx, req, status);
      },
      [](const pb::JobStatus& status) {
        return status.state() == pb::JOB_STATE_CANCELLED ? "cancelled"
                                                         : "cancel requested (the job stops within moments)";
      },
      [](const grpc::Status& st, grpc::ClientContext& ctx) { return exit_code_of(st, ctx); });
}

int RemoteCommands::Impl::run_delete() {
  return for_each_job<pb::DeleteReply>(
      [](pb::Jobs::Stub& stub, grpc::ClientContext* ctx, const pb::JobId& req, pb::DeleteReply* reply) {
        return stub.Delete(ctx, req, reply);
      },
      [](const pb::DeleteReply&) { return "deleted"; },
      // A queued or running job is not the user's to delete yet: a usage error, like an unknown id.
      [](const grpc::Status& st, grpc::ClientContext& ctx) {
        return st.error_code() == grpc::StatusCode::FAILED_PRECONDITION ? exit_code(ErrorKind::InvalidArgument)
                                                                        : exit_code_of(st, ctx);
      });
}

RemoteCommands::RemoteCommands(CLI::App& app) : impl_(std::make_unique<Impl>(app)) {}
RemoteCommands::~RemoteCommands() = default;

std::optional<int> RemoteCommands::run() {
  auto guarded = [](auto&& fn) -> int {
    try {
      return fn();
    } catch (const Error& e) {
      std::fprintf(stderr, "vdbwrap: error: %s\n", e.what());
      return exit_code(e.kind());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vdbwrap: internal error: %s\n", e.what());
      return exit_code(ErrorKind::Internal);
    }
  };
  for (const auto& [cmd, own] : impl_->env_backed)
    if (cmd->parsed()) {
      impl_->conn.server = own.server;
      impl_->conn.token_file = own.token_file;
    }
  if (*impl_->submit) return guarded([&] { return impl_->run_submit(); });
  if (*impl_->wait) return guarded([&] { return impl_->run_wait(); });
  if (*impl_->jobs) return guarded([&] { return impl_->run_jobs(); });
  if (*impl_->cancel) return guarded([&] { return impl_->run_cancel(); });
  if (*impl_->remove) return guarded([&] { return impl_->run_delete(); });
  if (*impl_->health) return guarded([&] { return impl_->run_health(); });
  return std::nullopt;
}

}  // namespace vdbwrap::remote
