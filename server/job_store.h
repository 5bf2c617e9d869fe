// The jobs on disk, in the spool directory:
//   <spool>/jobs/<id>/job.json      the job's record (JobStatus as JSON), rewritten atomically
//   <spool>/jobs/<id>/input.<ext>   the uploaded mesh
//   <spool>/jobs/<id>/result.ply    the wrap, lossless (double coordinates, parts)
//   <spool>/jobs/<id>/result.<ext>  the wrap in the job's output format, when not PLY
//   <spool>/jobs/<id>/report.json   the JSON report
//   <spool>/jobs/<id>/attempts      how many times the job was started (a decimal number)
//   <spool>/incoming/<random>/      uploads being received; emptied at start
// A job directory appears in jobs/ by one rename, complete with its input and record, so a
// crash never leaves half a job. Every file is written to a temporary name, fsync'ed and
// renamed; directories are fsync'ed after renames. Ids are 128 random bits in hex.
#pragma once
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "vdbwrap/v1/jobs.pb.h"

namespace vdbwrap::server {

namespace pb = ::vdbwrap::v1;
namespace fs = std::filesystem;

class JobStore {
 public:
  // Creates the spool's folders, locks the spool (one server per spool: <spool>/lock, an
  // flock the kernel releases when the process dies) and empties incoming/.
  // Throws std::runtime_error.
  explicit JobStore(fs::path spool);
  ~JobStore();

  // 32 lowercase hex characters from std::random_device.
  static std::string new_id();
  // True for exactly 32 lowercase hex characters: the only ids that reach the disk.
  static bool valid_id(const std::string& id);

  // An upload being received into incoming/. Deleted with its folder unless committed.
  class Upload {
   public:
    ~Upload();
    void append(std::string_view bytes);  // throws std::runtime_error
    uint64_t size() const { return size_; }
    // Flushes and fsyncs the data; afterwards the bytes can be read back.
    void close();
    std::string read_all() const;
    const fs::path& path() const { return file_; }

   private:
    friend class JobStore;
    fs::path dir_;
    fs::path file_;
    std::ofstream out_;
    uint64_t size_ = 0;
    bool committed_ = false;
  };
  std::unique_ptr<Upload> begin_upload();

  // Makes an upload a job: input.<ext> and job.json go into the upload's folder, which is
  // renamed to jobs/<record.job_id>. Durable when this returns. Throws std::runtime_error.
  void commit(Upload& upload, const pb::JobStatus& record);

  // Atomically rewrites job.json (the report_json field is not stored there).
  void save(const pb::JobStatus& record);
  // Every job found in jobs/, oldest first. Unreadable records are logged and skipped.
  std::vector<pb::JobStatus> load_all();
  void remove(const std::string& id);

  // How many times the job was started (0 when never); set before each start, durably, so
  // that a restart knows how often the server stopped while the job ran.
  int attempts(const std::string& id) const;
  void set_attempts(const std::string& id, int attempts);  // throws std::runtime_error

  fs::path job_dir(const std::string& id) const { return spool_ / "jobs" / id; }
  fs::path input_path(const pb::JobStatus& record) const { return job_dir(record.job_id()) / input_file_name(record); }
  fs::path result_path(const std::string& id, pb::MeshFormat format) const {
    return job_dir(id) / result_file_name(format);
  }
  fs::path report_path(const std::string& id) const { return job_dir(id) / kReportFile; }

  // The names of a job's files inside its folder (the worker process knows only the folder).
  static constexpr const char* kRecordFile = "job.json";
  static constexpr const char* kReportFile = "report.json";
  static std::string input_file_name(const pb::JobStatus& record);  // input.<ext>
  static std::string result_file_name(pb::MeshFormat format);       // result.<ext>
  // Parses a job folder's job.json. Throws std::runtime_error.
  static pb::JobStatus read_record(const fs::path& job_dir);

  // tmp + fsync + rename + fsync of the folder. Throws std::runtime_error.
  static void write_file_atomic(const fs::path& path, std::string_view bytes);
  static std::string read_file(const fs::path& path);  // throws std::runtime_error

 private:
  fs::path spool_;
  int lock_fd_ = -1;
};

}  // namespace vdbwrap::server
