// The support planes' kernels (kernels/planes.hpp) at every level against the scalar ones, on
// edge inputs: 0 to 600 points (the vector loop, its tail, the looks at the bound every
// kMsacChunk points), coordinates of -0.0, subnormals, 0.5, 1.0 and 0.0, distances exactly at the
// cap, bounds that cut a cost short; rows of labels of every length and offset up to three words.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "isa_levels.hpp"
#include "kernels/kernels.hpp"
#include "random_maps.hpp"
#include "rules/planes.hpp"

using namespace occseg;
using kernels::Isa;
using testing_isa::IsaTest;

namespace {

const kernels::PlanesKernels& scalar() { return kernels::table(Isa::scalar).planes; }
const kernels::PlanesKernels& level() { return kernels::active().planes; }

constexpr double kCap = kPlaneInlierDistance * kPlaneInlierDistance;

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

struct Sample {
  std::vector<double> x, y, z;
  kernels::PlanePoints points() const { return {x.data(), y.data(), z.data(), x.size()}; }
};

// n points of one kind: 0 random, 1 special values only, 2 on the plane z = 0.5 or at exactly
// the cap's distance from it (the min's tie), 3 random with every 5th point special.
Sample sample(std::size_t n, int kind, test::Rng& r) {
  const double sub = std::numeric_limits<double>::denorm_min();
  const double special[] = {-0.0, 0.0, sub, -5 * sub, std::numeric_limits<double>::min(), 0.5, 1.0, -1.0, 30.0};
  auto any_special = [&] { return special[r.below(9)]; };
  Sample s;
  for (std::size_t i = 0; i < n; ++i) {
    double x = 30 * r.uniform(), y = 30 * r.uniform(), z = 30 * r.uniform();
    if (kind == 1 || (kind == 3 && i % 5 == 0)) x = any_special(), y = any_special(), z = any_special();
    if (kind == 2) z = 0.5 + (i % 3 == 0 ? 0.0 : (i % 3 == 1 ? kPlaneInlierDistance : -kPlaneInlierDistance));
    s.x.push_back(x), s.y.push_back(y), s.z.push_back(z);
  }
  return s;
}

kernels::MsacPlane random_plane(test::Rng& r) {
  const double a = 6.28 * r.uniform(), b = 3.14 * r.uniform();
  return {std::cos(a) * std::sin(b), std::sin(a) * std::sin(b), std::cos(b), 15 * r.uniform()};
}

const std::size_t kCounts[] = {0, 1, 2, 3, 4, 5, 7, 8, 9, 255, 256, 257, 259, 511, 512, 513, 600};

}  // namespace

class KernelsPlanes : public IsaTest {};
OCCSEG_INSTANTIATE_ISA_LEVELS(KernelsPlanes);

// The scalar cost, bit for bit, below the bound; at or above it, a sum at or above it (the levels
// may cut a cost short after different points). Without a bound, and with bounds a quarter, half
// and all of the way to the full cost.
TEST_P(KernelsPlanes, CostMatchesScalarBitForBit) {
  test::Rng r(3);
  int cut_short = 0;
  for (std::size_t n : kCounts)
    for (int kind = 0; kind < 4; ++kind) {
      const Sample s = sample(n, kind, r);
      for (int p = 0; p < 4; ++p) {
        const kernels::MsacPlane pl = kind == 2 && p == 0 ? kernels::MsacPlane{0.0, -0.0, 1.0, 0.5} : random_plane(r);
        const double full = scalar().cost(s.points(), pl, kCap, std::numeric_limits<double>::infinity());
        for (double stop : {std::numeric_limits<double>::infinity(), 0.25 * full, 0.5 * full, full, 0.0}) {
          const double want = scalar().cost(s.points(), pl, kCap, stop);
          const double got = level().cost(s.points(), pl, kCap, stop);
          if (full < stop)
            ASSERT_TRUE(same_bits(got, full) && same_bits(want, full))
                << n << " points of kind " << kind << ", stop " << stop << ": " << got << " != " << full;
          else
            ASSERT_TRUE(got >= stop && want >= stop) << n << " points of kind " << kind << ", stop " << stop;
          cut_short += want != full;
        }
      }
    }
  EXPECT_GT(cut_short, 50);
}

// Each of the pair is the scalar cost() alone, bit for bit below the bound (at or above it, a sum
// at or above it), whichever of them stops first.
TEST_P(KernelsPlanes, CostPairMatchesScalarCostBitForBit) {
  test::Rng r(5);
  for (std::size_t n : kCounts)
    for (int kind = 0; kind < 4; ++kind) {
      const Sample s = sample(n, kind, r);
      for (int p = 0; p < 4; ++p) {
        const kernels::MsacPlane a = random_plane(r);
        kernels::MsacPlane b = p == 0 ? a : random_plane(r);
        if (p == 1) b.d = a.d + 0.5;
        const double inf = std::numeric_limits<double>::infinity();
        const double fa = scalar().cost(s.points(), a, kCap, inf), fb = scalar().cost(s.points(), b, kCap, inf);
        for (double stop : {inf, 0.5 * (fa + fb), 0.5 * fa, fb, 0.0}) {
          double ga = -1, gb = -1;
          level().cost_pair(s.points(), a, b, kCap, stop, ga, gb);
          EXPECT_TRUE(fa < stop ? same_bits(ga, fa) : ga >= stop) << n << " points, stop " << stop << ": " << ga;
          EXPECT_TRUE(fb < stop ? same_bits(gb, fb) : gb >= stop) << n << " points, stop " << stop << ": " << gb;
          // The pair's results are the level's cost() alone, bit for bit.
          ASSERT_TRUE(same_bits(ga, level().cost(s.points(), a, kCap, stop))) << n << " points, stop " << stop;
          ASSERT_TRUE(same_bits(gb, level().cost(s.points(), b, kCap, stop))) << n << " points, stop " << stop;
        }
      }
    }
}

// cost_inliers(): the cost is cost()'s bit for bit (at or above the bound, a sum at or above
// it), and below the bound the list is exactly the points with |distance| <= the inlier distance,
// computed here one point at a time (kind 2 puts points on the plane and about that distance off).
TEST_P(KernelsPlanes, CostInliersMatchesCostAndListsTheInliers) {
  test::Rng r(9);
  for (std::size_t n : kCounts)
    for (int kind = 0; kind < 4; ++kind) {
      const Sample s = sample(n, kind, r);
      for (int p = 0; p < 4; ++p) {
        const kernels::MsacPlane pl = kind == 2 && p == 0 ? kernels::MsacPlane{0.0, -0.0, 1.0, 0.5} : random_plane(r);
        const double inf = std::numeric_limits<double>::infinity();
        const double full = scalar().cost(s.points(), pl, kCap, inf);
        std::vector<std::uint32_t> want;
        for (std::size_t i = 0; i < n; ++i) {
          const double e = pl.n0 * s.x[i] + pl.n1 * s.y[i] + pl.n2 * s.z[i] - pl.d;
          if (std::fabs(e) <= kPlaneInlierDistance) want.push_back(static_cast<std::uint32_t>(i));
        }
        for (double stop : {inf, 0.5 * full, full, 0.0}) {
          for (const kernels::PlanesKernels* k : {&scalar(), &level()}) {
            std::vector<std::uint32_t> out(n + 1, 0xFFFFFFFFu);
            std::size_t count = ~std::size_t(0);
            const double got = k->cost_inliers(s.points(), pl, kCap, stop, kPlaneInlierDistance, out.data(), count);
            EXPECT_EQ(out[n], 0xFFFFFFFFu) << "written past the room for n positions";
            if (full < stop) {
              ASSERT_TRUE(same_bits(got, full)) << n << " points of kind " << kind << ", stop " << stop;
              ASSERT_EQ(count, want.size()) << n << " points of kind " << kind;
              ASSERT_TRUE(std::equal(want.begin(), want.end(), out.begin())) << n << " points of kind " << kind;
            } else {
              ASSERT_GE(got, stop) << n << " points of kind " << kind << ", stop " << stop;
            }
          }
        }
      }
    }
}

// Rows of labels holding s at random (sparse, dense, all, none), x0 0..70, lengths 1..130; the
// words past the row's last one must stay untouched.
TEST_P(KernelsPlanes, RowMembersMatchesScalar) {
  test::Rng r(7);
  constexpr std::uint32_t s = 12345;
  for (double density : {0.0, 0.1, 0.5, 0.9, 1.0}) {
    std::vector<std::uint32_t> row(220);
    for (auto& l : row) l = r.uniform() < density ? s : (r.uniform() < 0.5 ? s + 1 : s ^ 0x80000000u);
    for (std::size_t x0 = 0; x0 <= 70; ++x0)
      for (std::size_t len = 1; len <= 130; ++len) {
        const std::size_t x1 = x0 + len, words = (len + 63) / 64;
        std::vector<std::uint64_t> want(words + 2, 0xA5A5A5A5A5A5A5A5ull), got = want;
        const std::size_t nw = scalar().row_members(row.data(), x0, x1, s, want.data());
        const std::size_t ng = level().row_members(row.data(), x0, x1, s, got.data());
        ASSERT_EQ(ng, nw) << "[" << x0 << ", " << x1 << ") density " << density;
        ASSERT_EQ(got, want) << "[" << x0 << ", " << x1 << ") density " << density;
        EXPECT_EQ(want[words], 0xA5A5A5A5A5A5A5A5ull);
      }
  }
}
