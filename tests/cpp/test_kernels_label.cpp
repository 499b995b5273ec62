// The labelling's kernels (kernels/label.hpp) at every level against the scalar ones, on edge
// inputs: rows of 1 to 80 voxels (around the vector widths) at every bit offset, runs ending on
// and off a vector's edge, and run sums of 0 to 40 values of -0.0, subnormals, 0.5, 1.0, 0.0 and
// random values.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "isa_levels.hpp"
#include "kernels/kernels.hpp"
#include "random_maps.hpp"

using namespace occseg;
using kernels::Isa;
using testing_isa::IsaTest;

namespace {

const kernels::LabelKernels& scalar() { return kernels::table(Isa::scalar).label; }
const kernels::LabelKernels& level() { return kernels::active().label; }

// Rows of states: random runs of 1 to `longest` voxels of the states 0..2, in rows of every
// length up to 80.
std::vector<std::vector<std::uint8_t>> rows_of_runs(std::uint64_t seed, int longest) {
  test::Rng r(seed);
  std::vector<std::vector<std::uint8_t>> rows;
  for (std::size_t n = 1; n <= 80; ++n) {
    std::vector<std::uint8_t> row(n);
    for (std::size_t i = 0; i < n;) {
      const auto s = static_cast<std::uint8_t>(r.below(3));
      for (int k = 1 + r.below(longest); k > 0 && i < n; --k) row[i++] = s;
    }
    rows.push_back(row);
  }
  return rows;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

}  // namespace

class KernelsLabel : public IsaTest {};
OCCSEG_INSTANTIATE_ISA_LEVELS(KernelsLabel);

// Every row at every bit offset of a byte and more, into bits whose other voxels' bits are set
// at random (they must stay as they are); each row's own bits clear before, as the labelling
// has them.
TEST_P(KernelsLabel, RowStartsMatchesScalar) {
  test::Rng r(13);
  int checked = 0;
  for (int longest : {1, 3, 16, 17, 40, 100})
    for (const auto& row : rows_of_runs(11 + longest, longest))
      for (std::size_t i0 = 0; i0 < 24; ++i0) {
        std::vector<std::uint8_t> want((i0 + row.size()) / 8 + 3);
        for (auto& b : want) b = static_cast<std::uint8_t>(r.next());
        for (std::size_t x = 0; x < row.size(); ++x)
          want[(i0 + x) / 8] = static_cast<std::uint8_t>(want[(i0 + x) / 8] & ~(1u << ((i0 + x) % 8)));
        std::vector<std::uint8_t> got = want;
        scalar().row_starts(row.data(), row.size(), want.data(), i0);
        level().row_starts(row.data(), row.size(), got.data(), i0);
        ASSERT_EQ(got, want) << "row of " << row.size() << " at bit " << i0;
        ++checked;
      }
  EXPECT_EQ(checked, 6 * 80 * 24);
}

// Blocks of 1 to 6 rows of 1 to 80 states, every 1st to 4th row.
TEST_P(KernelsLabel, CountRunsMatchesScalar) {
  for (int longest : {1, 2, 16, 40}) {
    test::Rng r(31 + longest);
    for (std::size_t nx = 1; nx <= 80; ++nx)
      for (std::size_t rows = 1; rows <= 6; ++rows) {
        std::vector<std::uint8_t> s(nx * rows);
        for (std::size_t i = 0; i < s.size();) {
          const auto v = static_cast<std::uint8_t>(r.below(3));
          for (int k = 1 + r.below(longest); k > 0 && i < s.size(); --k) s[i++] = v;
        }
        for (std::size_t every = 1; every <= 4; ++every)
          ASSERT_EQ(level().count_runs(s.data(), rows, nx, every), scalar().count_runs(s.data(), rows, nx, every))
              << nx << " x " << rows << " rows, every " << every;
      }
  }
}

// Runs of 0 to 40 values (the vector loops and their tails) of each kind, and mixed, bit for bit
// (a sum of -0.0 values is +0.0: the lanes start at 0.0).
TEST_P(KernelsLabel, RunSumMatchesScalarBitForBit) {
  const float sub = std::numeric_limits<float>::denorm_min();
  const std::vector<float> kinds = {-0.0f, 0.0f, sub, 3 * sub, std::numeric_limits<float>::min(), 0.5f, 1.0f,
                                    std::nextafter(0.5f, 1.0f), std::nextafter(1.0f, 0.0f)};
  test::Rng r(41);
  std::vector<std::vector<float>> runs;
  for (std::size_t n = 0; n <= 40; ++n) {
    for (float v : kinds) runs.emplace_back(n, v);
    std::vector<float> mixed(n), spread(n), pick(n);
    for (std::size_t k = 0; k < n; ++k) {
      mixed[k] = static_cast<float>(r.uniform());
      spread[k] = static_cast<float>(std::pow(r.uniform(), 12));  // many binades: rounded sums
      pick[k] = kinds[static_cast<std::size_t>(r.below(static_cast<int>(kinds.size())))];
    }
    if (n) spread[0] = 1.0f;  // then the small values are below half an ulp of a serial sum
    runs.push_back(mixed);
    runs.push_back(spread);
    runs.push_back(pick);
  }
  for (const auto& v : runs) {
    const double want = scalar().run_sum(v.data(), v.size()), got = level().run_sum(v.data(), v.size());
    ASSERT_TRUE(same_bits(got, want)) << v.size() << " values from " << (v.empty() ? 0.0f : v[0]) << ": " << got
                                      << " != " << want;
  }
}
