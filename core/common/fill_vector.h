// Vectors whose resize leaves plain elements uninitialised, for arrays a parallel loop fills
// right after. The kernel zeroes a fresh page for the thread that first touches it: a
// value-initialising constructor made the calling thread fault in every page of the large
// scratch arrays alone (a second of page clearing on one thread out of every two while
// diagnosing and preparing a million triangles). Filled in parallel, the faults are shared.
#pragma once
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace vdbwrap {

// Plain: default-initialised (no zeroing for plain types). kSkipInitialisers: not even
// the default member initialisers run (plain structs only).
template <typename T, bool kSkipInitialisers = false>
struct DefaultInitAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U, kSkipInitialisers>;
  };
  DefaultInitAllocator() = default;
  template <typename U>
  DefaultInitAllocator(const DefaultInitAllocator<U, kSkipInitialisers>&) noexcept {}
  template <typename U>
  void construct(U* p) noexcept {
    if constexpr (kSkipInitialisers)
      static_assert(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>, "plain data only");
    else
      ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

// Every element must be written before it is read.
template <typename T>
using FillVector = std::vector<T, DefaultInitAllocator<T>>;

// The same for plain structs with default member initialisers (a Box3 starts empty): resize
// leaves new elements unwritten, so that a parallel loop faults their pages in (making
// millions of boxes empty first is serial page clearing). resize(n, value) still writes them. Every element must be
// written before it is read, initialisers or not.
template <typename T>
using RawFillVector = std::vector<T, DefaultInitAllocator<T, true>>;

}  // namespace vdbwrap
