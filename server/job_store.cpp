#include "job_store.h"

#include <fcntl.h>
#include <sys/file.h>
#include <google/protobuf/util/json_util.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <mutex>
#include <random>
#include <stdexcept>

#include "params_mapping.h"

namespace vdbwrap::server {

namespace {

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

void fsync_path(const fs::path& path, bool directory) {
  int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) fail("cannot open " + path.string() + " to sync it");
  int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) fail("cannot sync " + path.string());
}

}  // namespace

JobStore::JobStore(fs::path spool) : spool_(std::move(spool)) {
  std::error_code ec;
  fs::create_directories(spool_ / "jobs", ec);
  if (ec) fail("cannot create " + (spool_ / "jobs").string() + ": " + ec.message());
  lock_fd_ = ::open((spool_ / "lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) fail("cannot create " + (spool_ / "lock").string());
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    fail("the spool " + spool_.string() + " is in use by another vdbwrap-server");
  }
  fs::remove_all(spool_ / "incoming", ec);
  fs::create_directories(spool_ / "incoming", ec);
  if (ec) fail("cannot create " + (spool_ / "incoming").string() + ": " + ec.message());
}

JobStore::~JobStore() {
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

std::string JobStore::new_id() {
  static std::mutex lock;
  static std::random_device device;
  uint32_t words[4];
  {
    std::lock_guard<std::mutex> g(lock);
    for (auto& w : words) w = device();
  }
  char hex[33];
  std::snprintf(hex, sizeof hex, "%08x%08x%08x%08x", words[0], words[1], words[2], words[3]);
  return hex;
}

bool JobStore::valid_id(const std::string& id) {
  return id.size() == 32 &&
         std::all_of(id.begin(), id.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

JobStore::Upload::~Upload() {
  if (committed_) return;
  if (out_.is_open()) out_.close();
  std::error_code ec;
  fs::remove_all(dir_, ec);
}

void JobStore::Upload::append(std::string_view bytes) {
  out_.write(bytes.data(), std::streamsize(bytes.size()));
  if (!out_) fail("cannot write the upload to " + file_.string());
  size_ += bytes.size();
}

void JobStore::Upload::close() {
  out_.flush();
  if (!out_) fail("cannot write the upload to " + file_.string());
  out_.close();
  fsync_path(file_, false);
}

std::string JobStore::Upload::read_all() const { return read_file(file_); }

std::unique_ptr<JobStore::Upload> JobStore::begin_upload() {
  auto up = std::unique_ptr<Upload>(new Upload());
  up->dir_ = spool_ / "incoming" / new_id();
  std::error_code ec;
  fs::create_directories(up->dir_, ec);
  if (ec) fail("cannot create " + up->dir_.string() + ": " + ec.message());
  up->file_ = up->dir_ / "upload";
  up->out_.open(up->file_, std::ios::binary | std::ios::trunc);
  if (!up->out_) fail("cannot create " + up->file_.string());
  return up;
}

std::string JobStore::input_file_name(const pb::JobStatus& record) {
  std::string ext = api::extension_of(record.spec().input_format());
  return "input." + (ext.empty() ? std::string("bin") : ext);
}

std::string JobStore::result_file_name(pb::MeshFormat format) { return "result." + api::extension_of(format); }

void JobStore::write_file_atomic(const fs::path& path, std::string_view bytes) {
  fs::path tmp = path;
  tmp += ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) fail("cannot create " + tmp.string());
    out.write(bytes.data(), std::streamsize(bytes.size()));
    out.flush();
    if (!out) fail("cannot write " + tmp.string());
  }
  fsync_path(tmp, false);
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) fail("cannot rename " + tmp.string() + ": " + ec.message());
  fsync_path(path.parent_path(), true);
}

std::string JobStore::read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot open " + path.string());
  in.seekg(0, std::ios::end);
  std::streamoff n = in.tellg();
  in.seekg(0);
  std::string bytes(size_t(std::max<std::streamoff>(n, 0)), '\0');
  in.read(bytes.data(), n);
  if (!in) fail("cannot read " + path.string());
  return bytes;
}

namespace {

std::string to_json(const pb::JobStatus& record) {
  pb::JobStatus copy = record;
  copy.clear_report_json();
  std::string json;
  google::protobuf::util::JsonPrintOptions opts;
  opts.add_whitespace = true;
  opts.preserve_proto_field_names = true;
  auto st = google::protobuf::util::MessageToJsonString(copy, &json, opts);
  if (!st.ok()) fail("cannot encode the job record: " + st.ToString());
  return json;
}

}  // namespace

void JobStore::commit(Upload& upload, const pb::JobStatus& record) {
  if (!valid_id(record.job_id())) fail("invalid job id");
  const fs::path final_dir = job_dir(record.job_id());
  const fs::path input = upload.dir_ / input_path(record).filename();
  std::error_code ec;
  fs::rename(upload.file_, input, ec);
  if (ec) fail("cannot rename the upload: " + ec.message());
  upload.file_ = input;
  write_file_atomic(upload.dir_ / kRecordFile, to_json(record));  // also syncs the folder
  fs::rename(upload.dir_, final_dir, ec);
  if (ec) fail("cannot move the job to " + final_dir.string() + ": " + ec.message());
  upload.committed_ = true;
  fsync_path(spool_ / "jobs", true);
  fsync_path(spool_ / "incoming", true);
}

void JobStore::save(const pb::JobStatus& record) {
  write_file_atomic(job_dir(record.job_id()) / kRecordFile, to_json(record));
}

pb::JobStatus JobStore::read_record(const fs::path& dir) {
  pb::JobStatus record;
  std::string json = read_file(dir / kRecordFile);
  google::protobuf::util::JsonParseOptions opts;
  opts.ignore_unknown_fields = true;
  auto st = google::protobuf::util::JsonStringToMessage(json, &record, opts);
  if (!st.ok()) fail(st.ToString());
  return record;
}

int JobStore::attempts(const std::string& id) const {
  std::ifstream in(job_dir(id) / "attempts");
  int n = 0;
  return (in >> n) && n > 0 ? n : 0;
}

void JobStore::set_attempts(const std::string& id, int attempts) {
  write_file_atomic(job_dir(id) / "attempts", std::to_string(attempts) + "\n");
}

std::vector<pb::JobStatus> JobStore::load_all() {
  std::vector<pb::JobStatus> jobs;
  for (const auto& entry : fs::directory_iterator(spool_ / "jobs")) {
    const std::string id = entry.path().filename().string();
    if (!entry.is_directory() || !valid_id(id)) continue;
    pb::JobStatus record;
    try {
      record = read_record(entry.path());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vdbwrap-server: skipping %s: unreadable job record (%s)\n", entry.path().c_str(), e.what());
      continue;
    }
    if (record.job_id() != id) {
      std::fprintf(stderr, "vdbwrap-server: skipping %s: the record names another job\n", entry.path().c_str());
      continue;
    }
    jobs.push_back(std::move(record));
  }
  std::sort(jobs.begin(), jobs.end(), [](const pb::JobStatus& a, const pb::JobStatus& b) {
    return a.submitted_unix_ms() != b.submitted_unix_ms() ? a.submitted_unix_ms() < b.submitted_unix_ms()
                                                          : a.job_id() < b.job_id();
  });
  return jobs;
}

void JobStore::remove(const std::string& id) {
  if (!valid_id(id)) return;
  // One rename makes the job disappear; incoming/ is emptied at the next start anyway.
  const fs::path trash = spool_ / "incoming" / ("deleted-" + id);
  std::error_code ec;
  fs::rename(job_dir(id), trash, ec);
  if (ec) fail("cannot delete " + job_dir(id).string() + ": " + ec.message());
  fsync_path(spool_ / "jobs", true);
  fs::remove_all(trash, ec);
}

}  // namespace vdbwrap::server
