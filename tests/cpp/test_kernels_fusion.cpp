// The scan fusion's walk kernel (kernels/fusion.hpp) at every level against the scalar one, on
// walks built by hand: 0 to 333 walks per block (fewer than, and not a multiple of, the lanes),
// walks of one voxel, walks stopped by their budget, by the grid's faces or on their end voxel,
// exact ties between axes, tmax of -0.0 and 0.0, subnormal and 0.5 / 1.0 steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "isa_levels.hpp"
#include "kernels/kernels.hpp"
#include "random_maps.hpp"

using namespace occseg;
using kernels::Isa;
using kernels::Walk;
using testing_isa::IsaTest;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The voxel index a walk is on after `steps` steps by the rule of kernels/fusion.hpp, or ~0 when
// it is over before (for choosing end voxels the walks do reach).
std::uint64_t voxel_after(Walk w, long steps) {
  for (long s = 0; s < steps; ++s) {
    const int axis = w.tx[0] < w.ty[0] ? (w.tx[0] < w.tz[0] ? 0 : 2) : (w.ty[0] < w.tz[0] ? 1 : 2);
    double* t[3] = {w.tx, w.ty, w.tz};
    const double d[3] = {w.dx[0], w.dy[0], w.dz[0]};
    const std::uint64_t stride[3] = {w.sx, w.sy, w.sz};
    long* room[3] = {&w.rx, &w.ry, &w.rz};
    t[axis][0] += d[axis];
    w.i += stride[axis];
    if (--*room[axis] < 0 || --w.budget <= 0) return ~std::uint64_t(0);
  }
  return w.i;
}

struct RayBlock {
  Dims dims;
  std::vector<Walk> walks;
};

// `count` random walks in a grid of `dims`.
RayBlock random_block(const Dims& dims, std::size_t count, test::Rng& r) {
  const double sub = std::numeric_limits<double>::denorm_min();
  const double firsts[] = {-0.0, 0.0, sub, 0.5, 1.0, 0.25, 0.75};
  const double deltas[] = {0.5, 1.0, 0.25, 2.0, sub, 1e300};
  RayBlock b{dims, {}};
  const long n[3] = {long(dims.nx), long(dims.ny), long(dims.nz)};
  for (std::size_t k = 0; k < count; ++k) {
    Walk w{};
    double* t[3] = {w.tx, w.ty, w.tz};
    double* d[3] = {w.dx, w.dy, w.dz};
    const bool ties = r.below(3) == 0;  // the same first tmax and tdelta on every axis
    const double tie_t = firsts[r.below(7)], tie_d = deltas[r.below(4)];
    for (int a = 0; a < 3; ++a) {
      w.c0[a] = r.below(static_cast<int>(n[a]));
      w.step[a] = r.below(5) == 0 ? 0 : (r.below(2) ? 1 : -1);
      if (w.step[a] == 0) {
        t[a][0] = d[a][0] = kInf;
      } else if (ties) {
        t[a][0] = tie_t, d[a][0] = tie_d;
      } else {
        t[a][0] = r.below(2) ? firsts[r.below(7)] : r.uniform();
        d[a][0] = r.below(2) ? deltas[r.below(6)] : 0.01 + r.uniform();
      }
      w.room[a] = w.step[a] > 0 ? n[a] - 1 - w.c0[a] : (w.step[a] < 0 ? w.c0[a] : std::numeric_limits<long>::max());
    }
    const std::uint64_t nx = dims.nx, nxy = nx * dims.ny;
    w.i = std::uint64_t(w.c0[0]) + nx * std::uint64_t(w.c0[1]) + nxy * std::uint64_t(w.c0[2]);
    w.sx = std::uint64_t(w.step[0]), w.sy = std::uint64_t(w.step[1]) * nx, w.sz = std::uint64_t(w.step[2]) * nxy;
    w.rx = w.room[0], w.ry = w.room[1], w.rz = w.room[2];
    w.budget = 1 + r.below(r.below(4) == 0 ? 2 : 60);
    w.hit = r.below(2);
    // The end: a voxel the walk reaches (at its start, or later), or one it misses.
    const long at = r.below(3) == 0 ? 0 : r.below(static_cast<int>(w.budget) + 3);
    w.end = voxel_after(w, at);
    if (w.end == ~std::uint64_t(0) || r.below(4) == 0) w.end = std::uint64_t(r.below(static_cast<int>(dims.count())));
    b.walks.push_back(w);
  }
  return b;
}

struct Outcome {
  std::vector<std::uint8_t> marks;
  kernels::TouchBox box;
  std::vector<std::uint64_t> hits;
};

Outcome walk(const kernels::FusionKernels& k, const RayBlock& b) {
  Outcome o;
  o.marks.assign(b.dims.count(), 0);
  std::size_t next = 0;
  auto give = [&](Walk& w) {
    if (next == b.walks.size()) return false;
    w = b.walks[next++];
    return true;
  };
  k.walk_rays(kernels::NextRay(give), o.marks.data(), b.dims, o.box, o.hits);
  EXPECT_EQ(next, b.walks.size()) << "every walk taken";
  std::sort(o.hits.begin(), o.hits.end());
  return o;
}

}  // namespace

class KernelsFusion : public IsaTest {};
OCCSEG_INSTANTIATE_ISA_LEVELS(KernelsFusion);

TEST_P(KernelsFusion, WalkRaysMatchesScalar) {
  test::Rng r(17);
  std::size_t marked = 0, hits = 0;
  for (const Dims& d : {Dims{1, 1, 1}, Dims{13, 11, 7}, Dims{40, 3, 2}, Dims{2, 2, 64}})
    for (std::size_t count : {0, 1, 2, 3, 4, 5, 7, 8, 9, 50, 333}) {
      const RayBlock b = random_block(d, count, r);
      const Outcome want = walk(kernels::table(Isa::scalar).fusion, b);
      const Outcome got = walk(kernels::active().fusion, b);
      ASSERT_EQ(got.marks, want.marks) << count << " walks in " << d.nx << " x " << d.ny << " x " << d.nz;
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(got.box.lo[a], want.box.lo[a]) << count << " walks, axis " << a;
        ASSERT_EQ(got.box.hi[a], want.box.hi[a]) << count << " walks, axis " << a;
      }
      ASSERT_EQ(got.hits, want.hits) << count << " walks in " << d.nx << " x " << d.ny << " x " << d.nz;
      for (std::uint8_t m : want.marks) marked += m;
      hits += want.hits.size();
    }
  EXPECT_GT(marked, 1000u);
  EXPECT_GT(hits, 50u);
}
