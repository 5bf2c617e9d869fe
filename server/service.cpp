#include "service.h"

#include <fstream>

#include "vdbwrap/io.h"
#include "params_mapping.h"
#include "upload_check.h"

namespace vdbwrap::server {

namespace {

constexpr size_t kChunk = 1 << 20;  // download chunk size
constexpr size_t kMaxKey = 128;

grpc::Status status(grpc::StatusCode code, const std::string& message) { return grpc::Status(code, message); }

// A failed call caused by the parameters or the input: the kind goes into trailing metadata.
grpc::Status core_error(grpc::ServerContext* ctx, const Error& e) {
  ctx->AddTrailingMetadata(api::kErrorKindMetadata, std::to_string(int(e.kind())));
  return status(api::status_code_for(e.kind()), e.what());
}

bool equal_constant_time(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::string& c = a.size() == b.size() ? b : a;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ c[i]);
  return diff == 0;
}

// The client's file name, reduced to a harmless display name.
std::string display_name(const std::string& file_name) {
  std::string name =
      file_name.substr(file_name.find_last_of("/\\") == std::string::npos ? 0 : file_name.find_last_of("/\\") + 1);
  if (name.size() > 200) name = name.substr(name.size() - 200);
  for (char& c : name)
    if (static_cast<unsigned char>(c) < 0x20 || c == '"') c = '_';
  return name.empty() ? std::string("upload") : name;
}

struct Reservation {
  JobQueue& queue;
  bool held = true;
  ~Reservation() {
    if (held) queue.release_reservation();
  }
};

}  // namespace

grpc::Status JobsService::authenticate(grpc::ServerContext* ctx) const {
  if (options_.token.empty()) return grpc::Status::OK;
  const auto& md = ctx->client_metadata();
  auto it = md.find("authorization");
  if (it == md.end())
    return status(grpc::StatusCode::UNAUTHENTICATED,
                  "missing bearer token (metadata \"authorization: Bearer <token>\")");
  std::string value(it->second.data(), it->second.size());
  if (!equal_constant_time(value, "Bearer " + options_.token))
    return status(grpc::StatusCode::UNAUTHENTICATED, "wrong bearer token");
  return grpc::Status::OK;
}

grpc::Status JobsService::lookup(const std::string& id, std::shared_ptr<Job>& job) const {
  if (!JobStore::valid_id(id))
    return status(grpc::StatusCode::INVALID_ARGUMENT,
                  "malformed job id \"" + id.substr(0, 64) + "\" (expected 32 hex digits)");
  job = queue_.find(id);
  if (!job) return status(grpc::StatusCode::NOT_FOUND, "no job " + id + " on this server");
  return grpc::Status::OK;
}

grpc::Status JobsService::Submit(grpc::ServerContext* ctx, grpc::ServerReader<pb::SubmitRequest>* reader,
                                 pb::SubmitReply* reply) {
  if (auto st = authenticate(ctx); !st.ok()) return st;
  pb::SubmitRequest req;
  if (!reader->Read(&req)) return status(grpc::StatusCode::INVALID_ARGUMENT, "empty Submit stream");
  if (!req.has_spec())
    return status(grpc::StatusCode::INVALID_ARGUMENT, "the first Submit message must carry the JobSpec");
  pb::JobSpec spec = req.spec();
  const std::string name = display_name(spec.file_name());
  auto reject = [&](grpc::Status st) {
    log_line("upload \"" + name + "\" rejected: " + st.error_message());
    return st;
  };

  // Parameters and formats.
  if (spec.idempotency_key().size() > kMaxKey)
    return reject(status(grpc::StatusCode::INVALID_ARGUMENT, "idempotency_key is longer than 128 characters"));
  try {
    api::check_job_parameters(spec);
  } catch (const Error& e) {
    return reject(core_error(ctx, e));
  }
  if (!pb::MeshFormat_IsValid(spec.input_format()) || !pb::MeshFormat_IsValid(spec.output_format()))
    return reject(status(grpc::StatusCode::INVALID_ARGUMENT, "unknown mesh format value"));
  if (spec.input_format() == pb::MESH_FORMAT_UNSPECIFIED) spec.set_input_format(api::format_from_file_name(name));
  if (spec.output_format() == pb::MESH_FORMAT_UNSPECIFIED)
    spec.set_output_format(spec.input_format() == pb::MESH_FORMAT_UNSPECIFIED ? pb::MESH_FORMAT_PLY
                                                                              : spec.input_format());

  if (!spec.idempotency_key().empty()) {
    if (auto job = queue_.find_by_key(spec.idempotency_key())) {
      reply->set_job_id(job->record.job_id());
      reply->set_duplicate(true);
      reply->set_server(options_.advertise);
      return grpc::Status::OK;
    }
  }
  if (!accepting_) return status(grpc::StatusCode::UNAVAILABLE, "the server is shutting down");
  if (spec.size_bytes() > options_.max_upload)
    return reject(status(grpc::StatusCode::RESOURCE_EXHAUSTED, "upload of " + std::to_string(spec.size_bytes()) +
                                                                   " bytes is larger than the server's limit of " +
                                                                   std::to_string(options_.max_upload) + " bytes"));
  if (!queue_.try_reserve())
    return reject(
        status(grpc::StatusCode::RESOURCE_EXHAUSTED,
               "the queue is full (" + std::to_string(queue_.options().queue_limit) + " jobs waiting); retry later"));
  Reservation reservation{queue_};

  // The bytes, to a file in the spool.
  std::unique_ptr<JobStore::Upload> upload;
  try {
    upload = queue_.store().begin_upload();
    while (reader->Read(&req)) {
      if (req.has_spec())
        return reject(status(grpc::StatusCode::INVALID_ARGUMENT, "only the first Submit message may carry a JobSpec"));
      const std::string& chunk = req.chunk();
      if (upload->size() + chunk.size() > options_.max_upload)
        return reject(status(grpc::StatusCode::RESOURCE_EXHAUSTED, "upload is larger than the server's limit of " +
                                                                       std::to_string(options_.max_upload) + " bytes"));
      upload->append(chunk);
    }
    if (ctx->IsCancelled()) return status(grpc::StatusCode::CANCELLED, "upload cancelled by the client");
    upload->close();
  } catch (const std::exception& e) {
    return reject(status(grpc::StatusCode::INTERNAL, std::string("cannot store the upload: ") + e.what()));
  }
  if (upload->size() == 0) return reject(status(grpc::StatusCode::INVALID_ARGUMENT, name + ": file is empty"));

  // The mesh must be readable before the job is accepted. It is read in a process of its own,
  // under the jobs' memory limit: a reader that crashes on a hostile file ends that process only.
  size_t triangles = 0;
  {
    const pb::JobStatus check =
        check_upload(queue_.options().worker_command, queue_.options().job_memory, upload->path().string(),
                     spec.input_format(), name, [&] { return ctx->IsCancelled() || !accepting_; });
    if (check.state() == pb::JOB_STATE_CANCELLED)
      return status(grpc::StatusCode::CANCELLED, "upload abandoned: the client went away or the server is stopping");
    if (check.state() != pb::JOB_STATE_SUCCEEDED) {
      const std::string& why = check.error_message();
      if (check.error_kind() == pb::ERROR_KIND_INVALID_INPUT || check.error_kind() == pb::ERROR_KIND_INVALID_ARGUMENT)
        return reject(core_error(ctx, Error(api::to_error_kind(check.error_kind()), why)));
      if (why.rfind("out of memory", 0) == 0)
        return reject(
            status(grpc::StatusCode::RESOURCE_EXHAUSTED, name + ": not enough memory on the server to read this mesh"));
      return reject(status(grpc::StatusCode::INTERNAL, why));
    }
    triangles = check.output_triangles();
  }

  pb::JobStatus record;
  record.set_job_id(JobStore::new_id());
  record.set_state(pb::JOB_STATE_QUEUED);
  spec.set_size_bytes(upload->size());
  *record.mutable_spec() = spec;
  record.set_message("queued");
  record.set_submitted_unix_ms(unix_ms_now());
  record.set_input_bytes(upload->size());
  record.set_server(options_.advertise);
  bool duplicate = false;
  std::shared_ptr<Job> job;
  try {
    job = queue_.accept(*upload, record, duplicate);
    reservation.held = false;
  } catch (const std::exception& e) {
    return reject(status(grpc::StatusCode::INTERNAL, std::string("cannot store the job: ") + e.what()));
  }
  reply->set_job_id(job->record.job_id());
  reply->set_duplicate(duplicate);
  reply->set_server(options_.advertise);
  if (!duplicate)
    log_line("job " + record.job_id() + " accepted: \"" + name + "\", " + std::to_string(upload->size()) + " bytes, " +
             std::to_string(triangles) + " triangles" + (api::is_repair(spec) ? ", repair" : ""));
  return grpc::Status::OK;
}

grpc::Status JobsService::Watch(grpc::ServerContext* ctx, const pb::JobId* req,
                                grpc::ServerWriter<pb::ProgressEvent>* writer) {
  if (auto st = authenticate(ctx); !st.ok()) return st;
  std::shared_ptr<Job> job;
  if (auto st = lookup(req->job_id(), job); !st.ok()) return st;
  size_t next = 0;
  for (;;) {
    std::vector<pb::ProgressEvent> batch;
    bool ended = false;
    {
      std::unique_lock<std::mutex> g(job->lock);
      job->changed.wait_for(g, std::chrono::milliseconds(250), [&] {
        return job->events.size() > next || api::is_final(job->record.state()) || queue_.stopped();
      });
      batch.assign(job->events.begin() + long(next), job->events.end());
      next = job->events.size();
      ended = api::is_final(job->record.state());
    }
    for (const auto& ev : batch)
      if (!writer->Write(ev)) return status(grpc::StatusCode::CANCELLED, "the client went away");
    if (ended) return grpc::Status::OK;
    if (ctx->IsCancelled()) return status(grpc::StatusCode::CANCELLED, "the client went away");
    if (queue_.stopped())
      return status(grpc::StatusCode::UNAVAILABLE,
                    "the server is shutting down; the job stays queued, watch it again later");
  }
}

grpc::Status JobsService::GetStatus(grpc::ServerContext* ctx, const pb::JobId* req, pb::JobStatus* reply) {
  if (auto st = authenticate(ctx); !st.ok()) return st;
  std::shared_ptr<Job> job;
  if (auto st = lookup(req->job_id(), job); !st.ok()) return st;
  *reply = job->snapshot();
  if (reply->state() == pb::JOB_STATE_SUCCEEDED) {
    try {
      reply->set_report_json(JobStore::read_file(queue_.store().report_path(reply->job_id())));
    } catch (const std::exception& e) {
      return status(grpc::StatusCode::INTERNAL, std::string("cannot read the report: ") + e.what());
    }
  } else if (reply->state() == pb::JOB_STATE_FAILED) {
    // A failed job may have a report (a leak's location); none is fine.
    try {
      reply->set_report_json(JobStore::read_file(queue_.store().report_path(reply->job_id())));
    } catch (const std::exception&) {
    }
  }
  return grpc::Status::OK;
}

grpc::Status JobsService::Download(grpc::ServerContext* ctx, const pb::DownloadRequest* req,
                                   grpc::ServerWriter<pb::DownloadChunk>* writer) {
  if (auto st = authenticate(ctx); !st.ok()) return st;
  std::shared_ptr<Job> job;
  if (auto st = lookup(req->job_id(), job); !st.ok()) return st;
  const pb::JobStatus r = job->snapshot();
  if (r.state() != pb::JOB_STATE_SUCCEEDED) {
    std::string why = "job " + r.job_id() + " is " + api::state_name(r.state());
    if (!r.error_message().empty()) why += ": " + r.error_message();
    if (!api::is_final(r.state())) why += "; its result is not ready yet";
    return status(grpc::StatusCode::FAILED_PRECONDITION, why);
  }
  if (!pb::MeshFormat_IsValid(req->format()))
    return status(grpc::StatusCode::INVALID_ARGUMENT, "unknown mesh format value");
  const pb::MeshFormat format = req->format() == pb::MESH_FORMAT_UNSPECIFIED ? r.spec().output_format() : req->format();

  auto send = [&](auto&& read_some, uint64_t total) -> grpc::Status {
    pb::DownloadChunk chunk;
    chunk.set_total_size(total);
    chunk.set_format(format);
    uint64_t sent = 0;
    std::string buffer;
    do {
      read_some(buffer);
      sent += buffer.size();
      chunk.set_data(buffer);
      if (!writer->Write(chunk)) return status(grpc::StatusCode::CANCELLED, "the client went away");
      chunk.clear_total_size();
      chunk.clear_format();
    } while (sent < total && !buffer.empty());
    if (sent != total) return status(grpc::StatusCode::INTERNAL, "the result file changed while it was sent");
    return grpc::Status::OK;
  };

  const auto path = queue_.store().result_path(r.job_id(), format);
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    std::ifstream in(path, std::ios::binary);
    const uint64_t total = std::filesystem::file_size(path, ec);
    if (!in || ec) return status(grpc::StatusCode::INTERNAL, "cannot open the result");
    return send(
        [&](std::string& buf) {
          buf.resize(kChunk);
          in.read(buf.data(), std::streamsize(kChunk));
          buf.resize(size_t(in.gcount()));
        },
        total);
  }
  // Another format than the stored ones: converted from the lossless PLY.
  std::string bytes;
  try {
    std::string ply = JobStore::read_file(queue_.store().result_path(r.job_id(), pb::MESH_FORMAT_PLY));
    Mesh mesh = io::read_mesh_from_bytes(ply, io::Format::Ply, "result");
    if (format == pb::MESH_FORMAT_STL) {
      // Binary STL stores floats: a result validated in double precision is checked again
      // as it will be written, and refused rather than handed back invalid (a repair's
      // result: with more intersections than the repair left).
      MeshDiagnostics d = diagnose(io::rounded_to_float(mesh), true);
      const bool worse =
          api::is_repair(r.spec()) ? d.intersecting_pairs > r.intersecting_pairs_left() : !d.valid_closed_surface();
      if (worse)
        return status(grpc::StatusCode::FAILED_PRECONDITION,
                      "this result is not valid once rounded to single precision for STL (" +
                          std::to_string(d.intersecting_triangles) +
                          " intersecting triangles); download it as PLY or OBJ, "
                          "or submit the job with output format STL");
    }
    bytes = io::write_mesh_to_bytes(mesh, api::to_io_format(format));
  } catch (const std::exception& e) {
    return status(grpc::StatusCode::INTERNAL, std::string("cannot convert the result: ") + e.what());
  }
  size_t offset = 0;
  return send(
      [&](std::string& buf) {
        buf.assign(bytes, offset, kChunk);
        offset += buf.size();
      },
      bytes.size());
}

grpc::Status JobsService::Cancel(grpc::ServerContext* ctx, const pb::JobId* req, pb::JobStatus* reply) {
  if (auto st = authenticate(ctx); !st.ok()) return st;
  std::shared_ptr<Job> job;
  if (auto st = lookup(req->job_id(), job); !st.ok()) return st;
  auto result = queue_.cancel(job);
  *reply = job->snapshot();
  if (result == JobQueue::CancelResult::AlreadyEnded)
    return status(grpc::StatusCode::FAILED_PRECONDITION,
                  "job " + req->job_id() + " has already ended (" + api::state_name(reply->state()) + ")");
  return grpc::Status::OK;
}

grpc::Status JobsService::List(grpc::ServerContext* ctx, const pb::ListRequest*, pb::ListReply* reply) {
  if (auto st = authenticate(ctx); !st.ok()) return st;
  for (const auto& job : queue_.list()) *reply->add_jobs() = job->snapshot();
  return grpc::Status::OK;
}

grpc::Status JobsService::Delete(grpc::ServerContext* ctx, const pb::JobId* req, pb::DeleteReply*) {
  if (auto st = authenticate(ctx); !st.ok()) return st;
  std::shared_ptr<Job> job;
  if (auto st = lookup(req->job_id(), job); !st.ok()) return st;
  try {
    if (!queue_.remove(job))
      return status(grpc::StatusCode::FAILED_PRECONDITION,
                    "job " + req->job_id() + " is " + api::state_name(job->snapshot().state()) + "; cancel it first");
  } catch (const std::exception& e) {
    return status(grpc::StatusCode::INTERNAL, e.what());
  }
  return grpc::Status::OK;
}

}  // namespace vdbwrap::server
