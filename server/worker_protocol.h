// What a job's worker process tells the server, over a pipe (the worker's fd 3): a stream of
// frames, each a 4-byte little-endian length and a serialized pb::JobStatus. A frame whose
// state is RUNNING is a progress event (stage, fraction, message); a frame with a final
// state is the verdict (error kind and message, result_bytes, output_triangles,
// intersecting_pairs_left; message: the log line's summary). Reusing JobStatus keeps the
// protocol within the API's own messages.
#pragma once
#include <cstdint>
#include <string>

#include "vdbwrap/v1/jobs.pb.h"

namespace vdbwrap::server {

namespace pb = ::vdbwrap::v1;

// The worker's end of the pipe.
inline constexpr int kWorkerEventsFd = 3;
// Larger frames are a broken worker, not a message.
inline constexpr uint32_t kMaxFrameBytes = 1u << 20;

// Writes one frame, whole (retrying short writes and EINTR). False when the pipe is gone.
bool write_frame(int fd, const pb::JobStatus& frame);

// Collects bytes read from the pipe and cuts them into frames.
class FrameReader {
 public:
  void feed(const char* bytes, size_t size) { buffer_.append(bytes, size); }
  // The next complete frame; false when none is complete yet. Throws std::runtime_error for
  // bytes that are not a frame.
  bool next(pb::JobStatus& frame);
  // Bytes of an incomplete frame left over.
  size_t pending() const { return buffer_.size(); }

 private:
  std::string buffer_;
};

}  // namespace vdbwrap::server
