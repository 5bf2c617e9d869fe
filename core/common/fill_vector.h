// Vectors whose resize leaves plain elements uninitialised, for arrays a parallel loop fills
// right after. The kernel zeroes a fresh page for the thread that first touches it: a
// value-initialising constructor made the calling thread fault in every page of the large
// scratch arrays alone (a second of page clearing on one thread out of every two while
// diagnosing and preparing a million triangles). Filled in parallel, the faults are shared.
#pragma once
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace vdbwrap {

template <typename T>
struct DefaultInitAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <typename U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;  // default-initialised: no zeroing for plain types
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

// Every element must be written before it is read.
template <typename T>
using FillVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace vdbwrap
