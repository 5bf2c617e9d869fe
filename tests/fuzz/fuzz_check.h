// Shared by the harnesses: a property violation is a finding, reported like a crash.
#pragma once
#include <cstdio>
#include <cstdlib>

#include "vdbwrap/errors.h"

// abort(): libFuzzer and the sanitizers report it with the input that caused it; the replay
// test (without libFuzzer) fails the same way.
#define FUZZ_CHECK(cond, ...)                                                                   \
  do {                                                                                          \
    if (!(cond)) {                                                                              \
      std::fprintf(stderr, "fuzz property violated at %s:%d: %s: ", __FILE__, __LINE__, #cond); \
      std::fprintf(stderr, __VA_ARGS__);                                                        \
      std::fprintf(stderr, "\n");                                                               \
      std::abort();                                                                             \
    }                                                                                           \
  } while (0)

// Runs f: true when it returns, false when it refuses with Error(InvalidArgument), the one
// refusal the parameter harnesses accept; any other error kind is a finding.
template <class F>
bool accepted(F&& f) {
  try {
    f();
    return true;
  } catch (const vdbwrap::Error& e) {
    FUZZ_CHECK(e.kind() == vdbwrap::ErrorKind::InvalidArgument, "kind %d: %s", int(e.kind()), e.what());
    return false;
  }
}
