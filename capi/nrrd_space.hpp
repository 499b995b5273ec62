// The NRRD space of the map being read or written on this thread, between occseg_map_read /
// occseg_map_write (plugins.cpp) and the built-in .nrrd reader and writer (builtin_io.cpp): the
// plugin ABI's map carries dims, voxel size and origin only, and a map read from a
// left-posterior-superior file must be written back in that space, not mirrored into RAS.
#pragma once
#include <string>
#include <utility>

namespace occseg::capi {

// This thread's slot (defined in builtin_io.cpp, which every binary with the built-in readers
// holds). Empty: no named space, i.e. the writer's default.
std::string& nrrd_space_slot();

// Sets the slot for one read or write and restores what it held before (nested calls).
class NrrdSpaceScope {
 public:
  explicit NrrdSpaceScope(std::string space = "") : saved_(std::exchange(nrrd_space_slot(), std::move(space))) {}
  ~NrrdSpaceScope() { nrrd_space_slot() = std::move(saved_); }
  NrrdSpaceScope(const NrrdSpaceScope&) = delete;
  NrrdSpaceScope& operator=(const NrrdSpaceScope&) = delete;
  const std::string& value() const { return nrrd_space_slot(); }

 private:
  std::string saved_;
};

}  // namespace occseg::capi
