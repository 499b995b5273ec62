// The parts of a ray walk every level shares (plain C++): marking a voxel crossed, and a finished
// walk's bookkeeping.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "kernels/fusion.hpp"

namespace occseg::kernels {
namespace {

// Marks one voxel as crossed. While rays are walked only this value is ever written (hits are
// collected in lists and written after every walk is done, see insert_scan), so concurrent
// walks need no locked read-modify-write: a relaxed load and, on an unmarked voxel, a relaxed
// store. Reading first keeps the cache line shared between threads where many rays cross (near
// the sensor) instead of bouncing it with stores.
inline void mark_crossed(std::uint8_t* m) {
  if (__atomic_load_n(m, __ATOMIC_RELAXED) == 0) __atomic_store_n(m, std::uint8_t(1), __ATOMIC_RELAXED);
}

// Adds the voxels a finished walk covered to the box: walks are monotone along each axis, and
// went no further than the steps they took (a step out of the grid was counted, not taken). A
// walk that reached its end voxel with a return lists it in `hits`.
inline void finish_walk(const Walk& w, const Dims& dims, TouchBox& box, std::vector<std::uint64_t>& hits) {
  const long moved[3] = {w.room[0] - w.rx, w.room[1] - w.ry, w.room[2] - w.rz};
  const long n[3] = {static_cast<long>(dims.nx), static_cast<long>(dims.ny), static_cast<long>(dims.nz)};
  long fin[3];
  for (int k = 0; k < 3; ++k) fin[k] = std::clamp(w.c0[k] + w.step[k] * moved[k], 0L, n[k] - 1);
  box.add(fin);
  if (w.at_end && w.hit) hits.push_back(w.end);
}

}  // namespace
}  // namespace occseg::kernels
