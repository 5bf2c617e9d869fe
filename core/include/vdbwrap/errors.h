// Errors that cross the public API. Each kind maps to one CLI exit code and one gRPC status.
#pragma once
#include <stdexcept>
#include <string>

namespace vdbwrap {

enum class ErrorKind {
  Internal = 1,         // a bug: should never happen
  InvalidArgument = 2,  // bad parameters or command line
  InvalidInput = 3,     // unreadable file or invalid mesh content
  WrapFailed = 4,       // no valid surface could be produced
  OutputFailed = 5,     // result could not be written
  Cancelled = 6,        // the caller cancelled the job
};

class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  ErrorKind kind() const { return kind_; }

 private:
  ErrorKind kind_;
};

inline int exit_code(ErrorKind kind) { return static_cast<int>(kind); }

}  // namespace vdbwrap
