#include "worker_protocol.h"

#include <errno.h>
#include <unistd.h>

#include <stdexcept>

namespace vdbwrap::server {

bool write_frame(int fd, const pb::JobStatus& frame) {
  std::string body;
  if (!frame.SerializeToString(&body) || body.size() > kMaxFrameBytes) return false;
  const uint32_t n = uint32_t(body.size());
  std::string bytes;
  bytes.reserve(4 + body.size());
  for (int i = 0; i < 4; ++i) bytes.push_back(char((n >> (8 * i)) & 0xff));
  bytes += body;
  size_t done = 0;
  while (done < bytes.size()) {
    ssize_t w = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    done += size_t(w);
  }
  return true;
}

bool FrameReader::next(pb::JobStatus& frame) {
  if (buffer_.size() < 4) return false;
  uint32_t n = 0;
  for (int i = 0; i < 4; ++i) n |= uint32_t(static_cast<unsigned char>(buffer_[size_t(i)])) << (8 * i);
  if (n > kMaxFrameBytes) throw std::runtime_error("the worker sent a frame of " + std::to_string(n) + " bytes");
  if (buffer_.size() < 4 + size_t(n)) return false;
  frame.Clear();
  if (!frame.ParseFromArray(buffer_.data() + 4, int(n)))
    throw std::runtime_error("the worker sent an unreadable frame");
  buffer_.erase(0, 4 + size_t(n));
  return true;
}

}  // namespace vdbwrap::server
