// A value made by a TBB task in the background while the caller goes on: the pipeline
// overlaps work that is serial in part (a CGAL tree build, curve chaining) with stages that
// leave a core idle. The data the maker reads must outlive this.
#pragma once
#include <mutex>

#include <tbb/task_group.h>

namespace vdbwrap {

template <typename T>
class InBackground {
 public:
  template <typename Make>
  explicit InBackground(Make make) {
    task_.run([this, make] { value_ = make(); });
  }
  ~InBackground() {
    try {
      task_.wait();
    } catch (...) {  // the caller is unwinding already
    }
  }
  InBackground(const InBackground&) = delete;
  InBackground& operator=(const InBackground&) = delete;
  // Waits for the value the first time (from any thread); rethrows what the maker threw.
  const T& get() {
    std::call_once(made_, [this] { task_.wait(); });
    return value_;
  }

 private:
  tbb::task_group task_;
  std::once_flag made_;
  T value_{};
};

}  // namespace vdbwrap
