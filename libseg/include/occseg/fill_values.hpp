// Arrays of per-voxel values about to be filled whole (readers, conversions): fresh memory set up
// so that the system's work on it is shared by the threads that fill it.
#pragma once
#include <cstddef>
#include <vector>

namespace occseg {

// v.resize(n) (zeros, what v held freed first) for an array that `threads` threads (0: all cores)
// are about to fill whole, such as a grid's values being read or converted: the fresh pages are
// asked to be 2 MB ones and faulted in by the threads before the zeroing, so the system's clearing
// of them is split over the threads instead of being done by the one that zeroes.
void resize_for_fill(std::vector<float>& v, std::size_t n, int threads);

}  // namespace occseg
