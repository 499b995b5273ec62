// Vectors whose new elements are left uninitialised (default-initialised) instead of zeroed.
// The per-voxel arrays of a segmentation (the label array, 4 bytes per voxel) are written in full
// by the stages that fill them, in parallel; std::vector's value-initialisation would zero them
// first in one serial pass that also takes every page fault (docs/performance.md, "Memory and pages").
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace occseg {

// std::allocator, except that construct(p) with no arguments default-initialises: for trivial
// types, nothing is written. Construction with arguments (copies, fills with a value) is as
// usual, so v.assign(n, 0) and v.resize(n, 0) still zero.
template <class T>
struct DefaultInitAllocator {
  using value_type = T;
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) { return std::allocator<T>().allocate(n); }
  void deallocate(T* p, std::size_t n) noexcept { std::allocator<T>().deallocate(p, n); }
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const DefaultInitAllocator<U>&) const noexcept { return true; }
  template <class U>
  bool operator!=(const DefaultInitAllocator<U>&) const noexcept { return false; }
};

template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

// Segment id per voxel, x fastest (Result::labels).
using LabelArray = UninitVector<std::uint32_t>;

}  // namespace occseg
