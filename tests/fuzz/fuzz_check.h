// Shared by the harnesses: a property violation is a finding, reported like a crash.
#pragma once
#include <cstdio>
#include <cstdlib>

// abort(): libFuzzer and the sanitizers report it with the input that caused it; the replay
// test (without libFuzzer) fails the same way.
#define FUZZ_CHECK(cond, ...)                                                      \
  do {                                                                             \
    if (!(cond)) {                                                                 \
      std::fprintf(stderr, "fuzz property violated at %s:%d: %s: ", __FILE__, __LINE__, #cond); \
      std::fprintf(stderr, __VA_ARGS__);                                           \
      std::fprintf(stderr, "\n");                                                  \
      std::abort();                                                                \
    }                                                                              \
  } while (0)
