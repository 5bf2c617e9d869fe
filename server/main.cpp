// vdbwrap-server: the gRPC job service (vdbwrap.v1.Jobs, see proto/vdbwrap/v1/jobs.proto).
// Flags, wiring, signals. The jobs live in --spool; see job_store.h for the layout. Each job
// runs in a child process, this binary in worker mode (worker.h).
#include <CLI/CLI.hpp>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <signal.h>
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "job_queue.h"
#include "job_store.h"
#include "service.h"
#include "upload_check.h"
#include "worker.h"

using namespace vdbwrap::server;

namespace {

std::string read_text(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(std::string("cannot read the ") + what + " " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string trim(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  return s.substr(i);
}

// "1073741824", "512M", "2G", "64k" (powers of 1024).
uint64_t parse_size(const std::string& text) {
  size_t pos = 0;
  double v = std::stod(text, &pos);
  std::string unit = trim(text.substr(pos));
  double mult = 1;
  if (!unit.empty()) {
    char u = char(std::tolower(static_cast<unsigned char>(unit[0])));
    mult = u == 'k' ? 1024.0 : u == 'm' ? 1024.0 * 1024 : u == 'g' ? 1024.0 * 1024 * 1024 : u == 'b' ? 1 : -1;
    if (mult < 0 || (unit.size() > 1 && unit.substr(1) != "B" && unit.substr(1) != "iB" && unit.substr(1) != "b"))
      throw std::invalid_argument("unknown size unit");
  }
  if (!(v > 0)) throw std::invalid_argument("size must be positive");
  return uint64_t(v * mult);
}

// "7d", "12h", "30m", "45s", "90" (seconds), "0" (forever): seconds.
double parse_duration(const std::string& text) {
  size_t pos = 0;
  double v = std::stod(text, &pos);
  const std::string unit = trim(text.substr(pos));
  const double mult = unit.empty() || unit == "s" ? 1
                      : unit == "m"               ? 60
                      : unit == "h"               ? 3600
                      : unit == "d"               ? 86400
                                                  : -1;
  if (mult < 0) throw std::invalid_argument("unknown unit \"" + unit + "\" (use s, m, h or d)");
  if (!(v >= 0)) throw std::invalid_argument("a duration cannot be negative");
  return v * mult;
}

// This very binary: the default worker command.
std::string own_executable(const char* argv0) {
  char path[4096];
  ssize_t n = ::readlink("/proc/self/exe", path, sizeof path - 1);
  if (n <= 0) return argv0;
  path[n] = '\0';
  return path;
}

}  // namespace

int main(int argc, char** argv) {
  // Worker modes: the server starts itself so for each job and each upload's check (never a
  // client; not in --help).
  if (argc == 3 && std::string(argv[1]) == "--worker") return run_worker(argv[2]);
  if (argc == 5 && std::string(argv[1]) == "--check-upload") return run_upload_check(argv[2], argv[3], argv[4]);

  // Job processes are started with fork+exec: the child runs no gRPC, so gRPC's fork handlers
  // (which pause its threads around every fork) have nothing to protect.
  ::setenv("GRPC_ENABLE_FORK_SUPPORT", "false", 1);

  CLI::App app{"vdbwrap-server: the vdbwrap gRPC job service (vdbwrap.v1.Jobs, health, reflection)"};
  app.set_version_flag("--version", "vdbwrap-server 0.1.0");
  std::string listen = "127.0.0.1:50051", spool = "spool", max_upload = "1G", token_file, tls_cert, tls_key, advertise;
  std::string job_memory = "0", retain = "0", worker_command = own_executable(argv[0]);
  int workers = 1, queue = 16, max_attempts = 2;
  double job_timeout = 0, grace = 10;
  app.add_option("--listen", listen, "Address to listen on, HOST:PORT (port 0: any free port, printed at start)")
      ->capture_default_str();
  app.add_option("--workers", workers, "Jobs run at once (each also uses TBB threads inside)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_option("--queue", queue, "Most jobs waiting; more submissions are answered RESOURCE_EXHAUSTED")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  app.add_option("--spool", spool, "Folder where jobs live on disk (inputs, results, reports)")->capture_default_str();
  app.add_option("--max-upload", max_upload, "Largest accepted upload in bytes (suffixes k, M, G)")
      ->capture_default_str();
  app.add_option("--job-timeout", job_timeout, "Seconds a job may run before it is stopped (0: no limit)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--job-memory", job_memory,
                 "Memory each job's process may allocate (RLIMIT_DATA), bytes with suffixes k, M, G; 0: no limit. "
                 "A job over it fails alone with an out-of-memory message")
      ->capture_default_str();
  app.add_option(
         "--max-attempts", max_attempts,
         "Times a job may be started; a job the server stopped (died) under that often is failed, not run again")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_option("--retain", retain,
                 "Delete ended jobs and their files this long after they ended (e.g. 7d, 12h, 30m; 0: keep them)")
      ->capture_default_str();
  // Operator-level and for tests only (a stand-in that crashes on purpose): the program run as
  // `PATH --worker JOB_DIR` for each job. Not in --help; no client can set it.
  app.add_option("--worker-command", worker_command, "")->group("");
  app.add_option("--token-file", token_file,
                 "File holding a token: every call must carry 'authorization: Bearer TOKEN'");
  app.add_option("--tls-cert", tls_cert, "PEM certificate chain: serve TLS (with --tls-key)");
  app.add_option("--tls-key", tls_key, "PEM private key of --tls-cert");
  app.add_option(
      "--advertise", advertise,
      "Address clients can reach this server (replica) at, returned with each job (for replicas behind a balancer)");
  app.add_option("--shutdown-grace", grace, "On SIGTERM, seconds running jobs get to finish before they are re-queued")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  // SIGTERM/SIGINT are taken by sigwait below; block them before any thread starts.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);

  JobsService::Options service_options;
  std::shared_ptr<grpc::ServerCredentials> credentials;
  uint64_t upload_limit = 0, job_memory_limit = 0;
  double retain_seconds = 0;
  try {
    upload_limit = parse_size(max_upload);
    try {
      job_memory_limit = job_memory == "0" ? 0 : parse_size(job_memory);
    } catch (const std::exception& e) {
      throw std::runtime_error("--job-memory " + job_memory + ": " + e.what());
    }
    try {
      retain_seconds = parse_duration(retain);
    } catch (const std::exception& e) {
      throw std::runtime_error("--retain " + retain + ": " + e.what());
    }
    if (::access(worker_command.c_str(), X_OK) != 0)
      throw std::runtime_error("--worker-command " + worker_command + " is not an executable file");
    if (!token_file.empty()) {
      service_options.token = trim(read_text(token_file, "token file"));
      if (service_options.token.empty()) throw std::runtime_error("the token file " + token_file + " is empty");
    }
    if (tls_cert.empty() != tls_key.empty()) throw std::runtime_error("--tls-cert and --tls-key go together");
    if (!tls_cert.empty()) {
      grpc::SslServerCredentialsOptions ssl;
      ssl.pem_key_cert_pairs.push_back({read_text(tls_key, "TLS key"), read_text(tls_cert, "TLS certificate")});
      credentials = grpc::SslServerCredentials(ssl);
    } else {
      credentials = grpc::InsecureServerCredentials();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vdbwrap-server: error: %s\n", e.what());
    return 2;
  }
  service_options.max_upload = upload_limit;
  service_options.advertise = advertise;

  std::unique_ptr<JobStore> store;
  try {
    store = std::make_unique<JobStore>(spool);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vdbwrap-server: error: %s\n", e.what());
    return 5;
  }
  JobQueue::Options queue_options;
  queue_options.workers = workers;
  queue_options.queue_limit = size_t(queue);
  queue_options.job_timeout_seconds = job_timeout;
  queue_options.advertise = advertise;
  queue_options.worker_command = worker_command;
  queue_options.job_memory = job_memory_limit;
  queue_options.max_attempts = max_attempts;
  queue_options.retain_seconds = retain_seconds;
  JobQueue jobs(*store, queue_options);
  jobs.restore();
  JobsService service(jobs, service_options);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(listen, credentials, &port);
  builder.RegisterService(&service);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    std::fprintf(stderr, "vdbwrap-server: error: cannot listen on %s\n", listen.c_str());
    return 1;
  }
  if (auto* health = server->GetHealthCheckService()) {
    health->SetServingStatus("", true);
    health->SetServingStatus("vdbwrap.v1.Jobs", true);
  }
  jobs.start();
  const std::string actual = listen.substr(0, listen.rfind(':') + 1) + std::to_string(port);
  char summary[512];
  std::snprintf(summary, sizeof summary,
                "vdbwrap-server: listening on %s (%s), spool %s, %d worker(s), queue %d, max upload %llu bytes%s%s",
                actual.c_str(), tls_cert.empty() ? "plaintext" : "TLS", spool.c_str(), workers, queue,
                static_cast<unsigned long long>(upload_limit), service_options.token.empty() ? "" : ", token required",
                job_timeout > 0 ? (", job timeout " + std::to_string(int(job_timeout)) + " s").c_str() : "");
  std::string limits = std::string(summary) + ", job memory " +
                       (job_memory_limit ? std::to_string(job_memory_limit) + " bytes" : std::string("unlimited")) +
                       ", max attempts " + std::to_string(max_attempts) + ", retain " +
                       (retain_seconds > 0 ? std::to_string(int64_t(retain_seconds)) + " s" : std::string("forever"));
  log_line(limits);

  int sig = 0;
  sigwait(&signals, &sig);
  log_line(std::string("vdbwrap-server: ") + (sig == SIGTERM ? "SIGTERM" : "SIGINT") +
           ": shutting down (no new jobs; running jobs finish or are re-queued)");
  service.stop_accepting();
  if (auto* health = server->GetHealthCheckService()) {
    health->SetServingStatus("", false);
    health->SetServingStatus("vdbwrap.v1.Jobs", false);
  }
  jobs.shutdown(grace);
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  log_line("vdbwrap-server: stopped");
  return 0;
}
