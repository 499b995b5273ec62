// Scratch arrays that threads allocate for themselves inside a parallel loop (internal). Two such
// arrays can be neighbours on the heap, and a cache line holding the end of one and the start of
// the other, written by both threads, moves between the cores at every write (false sharing;
// docs/performance.md, "Thread pool and kernels"). A ThreadScratch keeps a cache line of padding on both sides
// of its elements.
#pragma once
#include <cstddef>
#include <vector>

namespace occseg::detail {

template <class T>
class ThreadScratch {
 public:
  static constexpr std::size_t kPad = (64 + sizeof(T) - 1) / sizeof(T);  // elements per side

  ThreadScratch() = default;
  explicit ThreadScratch(std::size_t n, const T& value = T()) : v_(n + 2 * kPad, value) {}
  // n elements (the first min(n, size()) kept, new ones = value).
  void resize(std::size_t n, const T& value = T()) {
    if (v_.empty()) v_.resize(2 * kPad);
    v_.resize(n + 2 * kPad, value);
  }
  std::size_t size() const { return v_.empty() ? 0 : v_.size() - 2 * kPad; }
  T* data() { return v_.data() + kPad; }
  const T* data() const { return v_.data() + kPad; }
  T& operator[](std::size_t i) { return v_[kPad + i]; }
  const T& operator[](std::size_t i) const { return v_[kPad + i]; }
  T* begin() { return data(); }
  T* end() { return data() + size(); }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size(); }

 private:
  std::vector<T> v_;
};

}  // namespace occseg::detail
