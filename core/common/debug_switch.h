// Developer diagnostics (a rejected wrap kept as a file, repair's trace on stderr) are compiled
// in only with the CMake option VDBWRAP_DEBUG_DUMPS: in a release build a library call, say in
// the job server, never writes files or prints because of its environment.
#pragma once
#include <cstdlib>

namespace vdbwrap::debug {

// The value of the environment variable `name` in a debug-dump build; null otherwise.
inline const char* setting(const char* name) {
#ifdef VDBWRAP_DEBUG_DUMPS
  return std::getenv(name);
#else
  (void)name;
  return nullptr;
#endif
}

}  // namespace vdbwrap::debug
