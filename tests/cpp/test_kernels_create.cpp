// The create kernels (kernels/create.hpp) of every instruction-set level against the scalar ones
// and against the rules they compute: rows of 0 to 318 voxels (the vector widths' tails), values
// at the band's float limits and one step either side, -0.0, subnormals, 0.0, 0.5, 1.0, NaN, and
// cell sums whose value depends on the order of their additions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "isa_levels.hpp"
#include "kernels/kernels.hpp"
#include "random_maps.hpp"
#include "stages/own_states.hpp"

using namespace occseg;

namespace {

class CreateKernels : public testing_isa::IsaTest {
 protected:
  const kernels::CreateKernels& scalar() const { return kernels::table(kernels::Isa::scalar).create; }
  const kernels::CreateKernels& level() const { return kernels::active().create; }
};
OCCSEG_INSTANTIATE_ISA_LEVELS(CreateKernels);

const std::size_t kLengths[] = {0, 1, 2, 7, 8, 9, 15, 16, 17, 31, 32, 33, 63, 64, 65, 100, 127, 128, 129, 318};

// Values at and around the band's float limits (float_bounds of the default band), the edges of
// [0, 1], NaN (unknown, as in own_state_of), and random ones.
std::vector<float> band_values(std::size_t n, test::Rng& r, float& lo, float& hi) {
  detail::float_bounds(Params().free_below, Params().occupied_above, lo, hi);
  const float v[] = {lo, std::nextafter(lo, 0.0f), std::nextafter(lo, 1.0f), hi, std::nextafter(hi, 0.0f),
                     std::nextafter(hi, 1.0f), 0.5f, -0.0f, 0.0f, 1.0f, 1e-40f, std::nanf("")};
  std::vector<float> p(n);
  for (float& x : p) x = r.below(3) == 0 ? static_cast<float>(r.uniform()) : v[r.below(12)];
  return p;
}

}  // namespace

TEST_P(CreateKernels, OwnStatesAreOwnStateOf) {
  test::Rng r(1);
  for (std::size_t n : kLengths)
    for (int round = 0; round < 4; ++round) {
      float lo = 0, hi = 0;
      const std::vector<float> p = band_values(n, r, lo, hi);
      std::vector<std::uint8_t> got(n + 8, 0xEE), want(n + 8, 0xEE);
      level().own_states(p.data(), n, lo, hi, got.data());
      scalar().own_states(p.data(), n, lo, hi, want.data());
      EXPECT_EQ(got, want) << "n " << n;
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(want[i], detail::own_state_of(p[i], lo, hi)) << p[i];
    }
}

// The bits of own_state_of (unknown, occupied), every word written whole (dirty words given),
// the bits past n 0.
TEST_P(CreateKernels, OwnBitsAreOwnStateOf) {
  test::Rng r(2);
  for (std::size_t n : kLengths)
    for (int round = 0; round < 4; ++round) {
      float lo = 0, hi = 0;
      const std::vector<float> p = band_values(n, r, lo, hi);
      const std::size_t words = (n + 63) / 64;
      std::vector<std::uint64_t> u(words + 1, ~0ull), o(words + 1, ~0ull), wu(words + 1, ~0ull), wo(words + 1, ~0ull);
      level().own_bits(p.data(), n, lo, hi, reinterpret_cast<detail::word_t*>(u.data()),
                       reinterpret_cast<detail::word_t*>(o.data()));
      scalar().own_bits(p.data(), n, lo, hi, reinterpret_cast<detail::word_t*>(wu.data()),
                        reinterpret_cast<detail::word_t*>(wo.data()));
      EXPECT_EQ(u, wu) << "n " << n;
      EXPECT_EQ(o, wo) << "n " << n;
      EXPECT_EQ(u[words], ~0ull);  // past the row: not written
      for (std::size_t x = 0; x < 64 * words; ++x) {
        const std::uint8_t s = x < n ? detail::own_state_of(p[x], lo, hi) : 0;
        ASSERT_EQ((wu[x / 64] >> (x % 64)) & 1, s == 1u) << "n " << n << " x " << x;
        ASSERT_EQ((wo[x / 64] >> (x % 64)) & 1, s == 2u) << "n " << n << " x " << x;
      }
    }
}

TEST_P(CreateKernels, PackEqualIsTheBitRowOfEqualBytes) {
  test::Rng r(3);
  for (std::size_t n : kLengths)
    for (std::uint8_t v : {0, 1, 2}) {
      std::vector<std::uint8_t> bytes(n);
      for (auto& b : bytes) b = static_cast<std::uint8_t>(r.below(3));
      const std::size_t words = (n + 63) / 64;
      std::vector<std::uint64_t> got(words + 1, ~0ull), want(words + 1, ~0ull);
      level().pack_equal(bytes.data(), n, v, reinterpret_cast<detail::word_t*>(got.data()));
      scalar().pack_equal(bytes.data(), n, v, reinterpret_cast<detail::word_t*>(want.data()));
      EXPECT_EQ(got, want) << "n " << n;
      for (std::size_t x = 0; x < 64 * words; ++x)
        ASSERT_EQ((want[x / 64] >> (x % 64)) & 1, x < n && bytes[x] == v) << "n " << n << " x " << x;
      EXPECT_EQ(want[words], ~0ull);
    }
}

// Cell sums bit for bit: each cell starts from a running sum near 1.0 and adds half-ulps of 1.0
// (2^-53, slightly more, a quarter, zero, -0.0, subnormals), so an addition out of order, to the
// wrong cell or twice changes the sum; 0 to 40 cells (groups of eight and the rest).
TEST_P(CreateKernels, AddCellsAddsInOrder) {
  test::Rng r(4);
  const float half = std::ldexp(1.0f, -53);
  const float values[] = {half, half * (1.0f + std::ldexp(1.0f, -7)), half / 2, 0.0f, -0.0f, 1e-40f, 1.0f, 0.5f};
  std::size_t order_matters = 0;
  for (std::size_t cells = 0; cells <= 40; ++cells)
    for (int round = 0; round < 4; ++round) {
      std::vector<float> v(8 * cells + 8);
      for (float& x : v) x = values[r.below(r.below(4) == 0 ? 8 : 6)];
      std::vector<double> start(cells + 1);
      for (double& s : start) s = r.below(2) ? 1.0 : 1.0 + std::ldexp(1.0, -52) * r.below(4);
      std::vector<double> got = start, want = start;
      level().add_cells(v.data(), got.data(), cells);
      scalar().add_cells(v.data(), want.data(), cells);
      for (std::size_t k = 0; k <= cells; ++k) {
        ASSERT_EQ(std::memcmp(&got[k], &want[k], sizeof(double)), 0) << "cells " << cells << " cell " << k;
        double acc = start[k];
        for (int i = 0; i < 8 && k < cells; ++i) acc += v[8 * k + i];
        ASSERT_EQ(want[k], acc) << "cells " << cells << " cell " << k;
        if (k < cells) {
          double backwards = start[k];
          for (int i = 8; i-- > 0;) backwards += v[8 * k + i];
          order_matters += backwards != acc;
        }
      }
    }
  EXPECT_GT(order_matters, 100u);  // the values tell orders apart
}
