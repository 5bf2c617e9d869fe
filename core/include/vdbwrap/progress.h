// Progress and cancellation of a long call (wrap, repair), passed in by the caller.
#pragma once
#include <string>

namespace vdbwrap {

// Progress and cancellation, passed in by the caller. Methods may be called from any thread.
class ProgressSink {
 public:
  virtual ~ProgressSink() = default;
  // stage: short stage name; fraction: 0..1 within the stage.
  virtual void progress(const std::string& stage, double fraction, const std::string& message) = 0;
  // Polled often; returning true makes wrap() throw Error(Cancelled) within moments.
  virtual bool cancelled() { return false; }
};

}  // namespace vdbwrap
