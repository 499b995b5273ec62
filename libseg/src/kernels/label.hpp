// The labelling's kernels (kernels.hpp): the slots, and how a table fills them. Each slot is a
// whole loop over a run or a block of rows; stages/label.cpp holds the algorithm around them.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/isa.hpp"

namespace occseg::kernels {

struct LabelKernels {
  // First x in [x, e) with s[x] == v, or e.
  std::size_t (*find_state)(const std::uint8_t* s, std::uint8_t v, std::size_t x, std::size_t e);
  // First x in [x, e) with s[x] != v, or e.
  std::size_t (*find_other)(const std::uint8_t* s, std::uint8_t v, std::size_t x, std::size_t e);
  // First x of the run of equal states that holds voxel x of row `s` (searching back from x).
  std::size_t (*run_start)(const std::uint8_t* s, std::size_t x);
  // Runs (maximal stretches of one state along x) in every `every`-th of `rows` consecutive rows
  // of nx states each (nx >= 1).
  std::size_t (*count_runs)(const std::uint8_t* s, std::size_t rows, std::size_t nx, std::size_t every);
  // The sum of v[0, n) in the documented order of a segment's mean occupancy (stages/label.hpp):
  // v[k] is added to lane k % 8 in turn, from 0.0, and the lanes are added as
  // ((l0 + l1) + (l2 + l3)) + ((l4 + l5) + (l6 + l7)), every addition in double.
  double (*run_sum)(const float* v, std::size_t n);
};

// Fills every slot with the fastest kernel at or below `cap` that the processor has.
void select_label(LabelKernels& k, Isa cap);

}  // namespace occseg::kernels
