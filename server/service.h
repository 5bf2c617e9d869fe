// The gRPC handlers of vdbwrap.v1.Jobs: authentication, validation of uploads, and calls
// into the JobQueue. No pipeline logic here.
#pragma once
#include <atomic>
#include <string>

#include "job_queue.h"
#include "vdbwrap/v1/jobs.grpc.pb.h"

namespace vdbwrap::server {

class JobsService final : public pb::Jobs::Service {
 public:
  struct Options {
    std::string token;  // empty: no authentication
    uint64_t max_upload = 1ull << 30;
    std::string advertise;  // returned in SubmitReply.server
  };
  JobsService(JobQueue& queue, Options options) : queue_(queue), options_(std::move(options)) {}

  // New submissions are answered UNAVAILABLE from now on.
  void stop_accepting() { accepting_ = false; }

  grpc::Status Submit(grpc::ServerContext* ctx, grpc::ServerReader<pb::SubmitRequest>* reader,
                      pb::SubmitReply* reply) override;
  grpc::Status Watch(grpc::ServerContext* ctx, const pb::JobId* req,
                     grpc::ServerWriter<pb::ProgressEvent>* writer) override;
  grpc::Status GetStatus(grpc::ServerContext* ctx, const pb::JobId* req, pb::JobStatus* reply) override;
  grpc::Status Download(grpc::ServerContext* ctx, const pb::DownloadRequest* req,
                        grpc::ServerWriter<pb::DownloadChunk>* writer) override;
  grpc::Status Cancel(grpc::ServerContext* ctx, const pb::JobId* req, pb::JobStatus* reply) override;
  grpc::Status List(grpc::ServerContext* ctx, const pb::ListRequest* req, pb::ListReply* reply) override;
  grpc::Status Delete(grpc::ServerContext* ctx, const pb::JobId* req, pb::DeleteReply* reply) override;

 private:
  grpc::Status authenticate(grpc::ServerContext* ctx) const;
  grpc::Status lookup(const std::string& id, std::shared_ptr<Job>& job) const;

  JobQueue& queue_;
  Options options_;
  std::atomic<bool> accepting_{true};
};

}  // namespace vdbwrap::server
