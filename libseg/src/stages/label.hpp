// Final labelling: 6-connected components of the voxel states, and the segment table.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "kernels/kernels.hpp"
#include "occseg/grid.hpp"
#include "occseg/params.hpp"
#include "occseg/result.hpp"
#include "occseg/uninit_vector.hpp"

namespace occseg {

// z-planes per labelling slab. Slabs are labelled in parallel. The mean occupancy of a segment
// is summed run by run (a run: a maximal stretch of the segment along x within a row): voxel k of
// a run adds to lane k % 8, the run's sum is ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)),
// run sums are added in scan order within each slab and the slab sums in slab order. The result
// depends on this constant but never on the thread count (docs/algorithm.md).
constexpr std::size_t kLabelSlab = 8;

// Labels each connected region of equal state 0..N-1 (every state a value of occseg::State: 0, 1
// or 2), numbered in the order of their first voxel (x fastest), and fills `segments` (index =
// id). Regions are 6-connected; with `occupied26`, occupied voxels also join across edges and
// corners (26-connectivity). Throws Error(unsupported) beyond 2^32-1 voxels, since labels are
// uint32. `threads` as in Params (0: all cores); results never depend on it, nor on the kernels
// `k` (every level gives the same labels and segments, bit for bit).
void label_components(const std::vector<std::uint8_t>& states, const Grid& grid,
                      LabelArray& labels, std::vector<Segment>& segments, int threads = 0,
                      bool occupied26 = false, const kernels::Table& k = kernels::active());
// The same, taking the states over: they are freed (left empty) as soon as the components are
// known, before the statistics pass (which finds its runs in 1/8 byte per voxel of bits).
void label_components(std::vector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads = 0, bool occupied26 = false,
                      const kernels::Table& k = kernels::active());
void label_components(UninitVector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads = 0, bool occupied26 = false,
                      const kernels::Table& k = kernels::active());

namespace detail {
// The last overload with the run-start bits (1/8 byte per voxel) kept in `run_starts`, whose
// storage a context hands from call to call: fresh storage would be paged in on every call.
void label_components(UninitVector<std::uint8_t>&& states, const Grid& grid, LabelArray& labels,
                      std::vector<Segment>& segments, int threads, bool occupied26,
                      std::vector<std::uint8_t>& run_starts, const kernels::Table& k);
}  // namespace detail

}  // namespace occseg
