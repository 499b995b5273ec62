// The labelling's kernels (kernels.hpp): the slots, and how a table fills them. Each slot is a
// whole loop over a row, a block of rows or a run; stages/label.cpp holds the algorithm around
// them.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/isa.hpp"

namespace occseg::kernels {

struct LabelKernels {
  // Sets bit i0 + x of `bits` (bit b at bit b % 8 of byte b / 8) for x = 0 and every x < nx with
  // row[x] != row[x - 1]: the starts of the row's runs (maximal stretches of one state along x).
  // The bits are ORed in, byte by byte: a byte that also holds bits of voxels outside the row is
  // read and written back with those bits unchanged.
  void (*row_starts)(const std::uint8_t* row, std::size_t nx, std::uint8_t* bits, std::size_t i0);
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
