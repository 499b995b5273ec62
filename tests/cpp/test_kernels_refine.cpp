// The refinement's kernels (kernels/refine.hpp) at every level against the scalar ones. They take
// voxel states (0, 1, 2) and bit rows only, no values: the edge inputs are the lengths (0, 1, the
// tails of the 16- and 32-voxel steps, the 64-voxel words), the positions of what is found (first,
// last, none), every state, dense and sparse rows, and dirty output storage.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "isa_levels.hpp"
#include "kernels/kernels.hpp"
#include "random_maps.hpp"

using namespace occseg;
using occseg::testing_isa::for_each_isa;

namespace {

const kernels::RefineKernels& scalar_kernels() { return kernels::table(kernels::Isa::scalar).refine; }

std::vector<std::size_t> lengths() {
  std::vector<std::size_t> n;
  for (std::size_t i = 0; i <= 70; ++i) n.push_back(i);
  for (std::size_t i : {95u, 96u, 97u, 127u, 128u, 129u, 200u}) n.push_back(i);
  return n;
}

// States 0..2; `other` the share of voxels not `base`.
std::vector<std::uint8_t> states(test::Rng& r, std::size_t n, std::uint8_t base, double other) {
  std::vector<std::uint8_t> s(n, base);
  for (auto& v : s)
    if (r.uniform() < other) v = static_cast<std::uint8_t>(r.below(3));
  return s;
}

// A bit row of n voxels, each bit set with probability `density`, bits past n 0.
std::vector<std::uint64_t> bits(test::Rng& r, std::size_t n, double density) {
  std::vector<std::uint64_t> w((n + 63) / 64, 0);
  for (std::size_t x = 0; x < n; ++x)
    if (r.uniform() < density) w[x / 64] |= std::uint64_t(1) << (x % 64);
  return w;
}

const detail::word_t* words(const std::vector<std::uint64_t>& v) {
  return reinterpret_cast<const detail::word_t*>(v.data());
}
detail::word_t* words(std::vector<std::uint64_t>& v) { return reinterpret_cast<detail::word_t*>(v.data()); }

}  // namespace

TEST(KernelsRefine, AnyBoundaryAndAnyOccupied) {
  test::Rng r(1);
  const int levels = for_each_isa([&](kernels::Isa) {
    const kernels::RefineKernels& k = kernels::active().refine;
    for (std::size_t n : lengths()) {
      // No boundary (free and unknown only, or occupied and unknown only), then one at each position.
      for (std::uint8_t base : {std::uint8_t(0), std::uint8_t(2)}) {
        std::vector<std::uint8_t> a(n), b(n);
        for (std::size_t x = 0; x < n; ++x) {
          a[x] = r.uniform() < 0.5 ? base : 1;
          b[x] = r.uniform() < 0.5 ? base : 1;
        }
        EXPECT_FALSE(k.any_boundary(a.data(), b.data(), n)) << n;
        EXPECT_EQ(k.any_occupied(a.data(), n), scalar_kernels().any_occupied(a.data(), n)) << n;
        for (std::size_t p = 0; p < n; ++p) {
          auto a2 = a, b2 = b;
          a2[p] = base;
          b2[p] = static_cast<std::uint8_t>(2 - base);
          EXPECT_TRUE(k.any_boundary(a2.data(), b2.data(), n)) << n << " at " << p;
          EXPECT_TRUE(k.any_boundary(b2.data(), a2.data(), n)) << n << " at " << p;
          std::vector<std::uint8_t> s(n, 0);
          s[p] = 2;
          EXPECT_TRUE(k.any_occupied(s.data(), n)) << n << " at " << p;
          s[p] = 1;
          EXPECT_FALSE(k.any_occupied(s.data(), n)) << n << " at " << p;
        }
      }
      for (double other : {0.01, 0.1, 1.0}) {
        const auto a = states(r, n, 0, other), b = states(r, n, 0, other);
        EXPECT_EQ(k.any_boundary(a.data(), b.data(), n), scalar_kernels().any_boundary(a.data(), b.data(), n)) << n;
        EXPECT_EQ(k.any_occupied(a.data(), n), scalar_kernels().any_occupied(a.data(), n)) << n;
      }
    }
  });
  EXPECT_GE(levels, 2);
}

TEST(KernelsRefine, NextBoundaryForwardAndBackward) {
  test::Rng r(2);
  std::size_t found = 0;
  for_each_isa([&](kernels::Isa) {
    const kernels::RefineKernels& k = kernels::active().refine;
    for (std::size_t len : lengths()) {
      if (len == 0) continue;  // (a line holds a voxel)
      for (double other : {0.0, 0.02, 0.2, 1.0}) {
        // runs of one state, so that boundaries are sparse
        std::vector<std::uint8_t> st(len);
        std::uint8_t s = static_cast<std::uint8_t>(r.below(3));
        for (auto& v : st) {
          if (r.uniform() < other) s = static_cast<std::uint8_t>(r.below(3));
          v = s;
        }
        for (int step : {+1, -1})
          for (std::size_t q = 1; q <= len; ++q) {
            const std::size_t got = k.next_boundary(st.data(), q, len, step);
            ASSERT_EQ(got, scalar_kernels().next_boundary(st.data(), q, len, step))
                << len << " from " << q << " step " << step;
            found += got < len;
          }
      }
    }
  });
  EXPECT_GT(found, 1000u);
}

TEST(KernelsRefine, WindowStarts) {
  test::Rng r(3);
  std::size_t started = 0;
  for_each_isa([&](kernels::Isa) {
    const kernels::RefineKernels& k = kernels::active().refine;
    for (std::size_t nx : lengths())
      for (double other : {0.0, 0.1, 1.0})
        for (int max_skip : {0, 1, 3, 63}) {
          const auto prev = states(r, nx, 0, other), cur = states(r, nx, 2, other);
          std::vector<std::uint8_t> skip(nx);
          for (auto& v : skip) v = static_cast<std::uint8_t>(r.below(max_skip + 1));
          auto want_skip = skip;
          std::vector<std::uint32_t> lanes(nx + 1, 0xDEADBEEF), want(nx + 1, 0xDEADBEEF);
          const std::size_t n = k.window_starts(prev.data(), cur.data(), skip.data(), nx, lanes.data());
          const std::size_t m =
              scalar_kernels().window_starts(prev.data(), cur.data(), want_skip.data(), nx, want.data());
          ASSERT_EQ(n, m) << nx;
          ASSERT_EQ(lanes, want) << nx;
          ASSERT_EQ(skip, want_skip) << nx;
          started += n;
        }
  });
  EXPECT_GT(started, 1000u);
}

TEST(KernelsRefine, PlaneRow) {
  // A plane of `rows` window rows after the row before, laid out forward (rs = +nx) or backward
  // (rs = -nx: window row w above row 0 in memory): lanes boundary-heavy or not, running windows,
  // window rows of the boundary voxel's state or not, own states of every kind.
  test::Rng r(7);
  std::size_t started = 0, moved = 0;
  for_each_isa([&](kernels::Isa) {
    const kernels::RefineKernels& k = kernels::active().refine;
    for (std::size_t nx : lengths())
      for (int rows : {1, 2, 3, 4, 8, 63, 64})
        for (int step : {+1, -1})
          for (double other : {0.0, 0.2, 1.0}) {
            const std::size_t W = (nx + 63) / 64;
            const std::size_t total = (static_cast<std::size_t>(rows) + 1) * nx;
            std::vector<std::uint8_t> plane(total + 1);
            const std::uint8_t base = r.uniform() < 0.5 ? 0 : 2;
            for (std::size_t i = 0; i < total; ++i)
              plane[i] = r.uniform() < other ? static_cast<std::uint8_t>(r.below(3)) : base;
            // the row before first in scan order; the window rows follow it in scan order
            const std::ptrdiff_t rs = step > 0 ? static_cast<std::ptrdiff_t>(nx) : -static_cast<std::ptrdiff_t>(nx);
            const std::size_t prev_at = step > 0 ? 0 : static_cast<std::size_t>(rows) * nx;
            for (std::size_t x = 0; x < nx; ++x)  // the row before: mostly the other state
              if (r.uniform() < 0.7) plane[prev_at + x] = static_cast<std::uint8_t>(2 - plane[prev_at + x]);
            std::vector<std::uint8_t> skip(nx);
            for (auto& v : skip) v = r.uniform() < 0.7 ? 0 : static_cast<std::uint8_t>(r.below(5));
            std::vector<std::vector<std::uint64_t>> o(static_cast<std::size_t>(rows)), u(o);
            const detail::word_t* occ[64];
            const detail::word_t* unk[64];
            for (int w = 0; w < rows; ++w) {
              o[std::size_t(w)] = bits(r, nx, r.uniform());
              u[std::size_t(w)] = bits(r, nx, r.uniform());
              for (std::size_t i = 0; i < W; ++i) u[std::size_t(w)][i] &= ~o[std::size_t(w)][i];  // one state each
            }
            for (int w = 0; w < rows; ++w) {
              occ[w] = words(o[std::size_t(w)]);
              unk[w] = words(u[std::size_t(w)]);
            }
            const auto before = plane;
            auto want_plane = plane;
            auto want_skip = skip;
            const std::ptrdiff_t cur_at = static_cast<std::ptrdiff_t>(prev_at) + rs;
            const kernels::PlaneRow got = k.plane_row(plane.data() + prev_at, plane.data() + cur_at, rs, rows,
                                                      skip.data(), nx, occ, unk);
            const kernels::PlaneRow want =
                scalar_kernels().plane_row(want_plane.data() + prev_at, want_plane.data() + cur_at, rs, rows,
                                           want_skip.data(), nx, occ, unk);
            ASSERT_EQ(got.started, want.started) << nx << " rows " << rows << " step " << step;
            ASSERT_EQ(got.occupied_rows, want.occupied_rows) << nx << " rows " << rows << " step " << step;
            ASSERT_EQ(plane, want_plane) << nx << " rows " << rows << " step " << step;
            ASSERT_EQ(skip, want_skip) << nx << " rows " << rows << " step " << step;
            started += want.started;
            for (std::size_t i = 0; i < total; ++i) moved += want_plane[i] != before[i];
          }
  });
  EXPECT_GT(started, 1000u);
  EXPECT_GT(moved, 1000u);
}

TEST(KernelsRefine, PackStatesAndPackEqual) {
  test::Rng r(4);
  for_each_isa([&](kernels::Isa) {
    const kernels::RefineKernels& k = kernels::active().refine;
    for (std::size_t nx : lengths())
      for (double other : {0.0, 0.3, 1.0})
        for (std::uint8_t base : {std::uint8_t(0), std::uint8_t(1), std::uint8_t(2)}) {
          const auto st = states(r, nx, base, other);
          const std::size_t W = (nx + 63) / 64;
          std::vector<std::uint64_t> u(W, ~0ull), f(W, ~0ull), wu(W, 0x5555), wf(W, 0xAAAA);
          k.pack_states(st.data(), nx, words(u), words(f));
          scalar_kernels().pack_states(st.data(), nx, words(wu), words(wf));
          ASSERT_EQ(u, wu) << nx;
          ASSERT_EQ(f, wf) << nx;
          for (std::uint8_t v : {std::uint8_t(0), std::uint8_t(1), std::uint8_t(2)}) {
            std::vector<std::uint64_t> got(W, ~0ull), want(W, 0x1234);
            k.pack_equal(st.data(), nx, v, words(got));
            scalar_kernels().pack_equal(st.data(), nx, v, words(want));
            ASSERT_EQ(got, want) << nx << " value " << int(v);
          }
          // the meaning, once: bit x is st[x] == v, bits past nx 0
          for (std::size_t x = 0; x < 64 * W; ++x) {
            const bool bit = (wu[x / 64] >> (x % 64)) & 1u;
            ASSERT_EQ(bit, x < nx && st[x] == 1) << nx << " bit " << x;
          }
        }
  });
}

TEST(KernelsRefine, UnpackUnknownAndWriteCellsRow) {
  test::Rng r(5);
  for_each_isa([&](kernels::Isa) {
    const kernels::RefineKernels& k = kernels::active().refine;
    for (std::size_t nx : lengths())
      for (double density : {0.0, 0.05, 0.5, 1.0}) {
        const auto w = bits(r, nx, density);
        const auto st = states(r, nx, 0, 1.0);
        auto got = st, want = st;
        k.unpack_unknown(words(w), nx, got.data());
        scalar_kernels().unpack_unknown(words(w), nx, want.data());
        ASSERT_EQ(got, want) << nx;
        std::vector<std::uint8_t> cs((nx + 7) / 8);
        for (auto& c : cs) c = static_cast<std::uint8_t>(r.below(3));
        std::vector<std::uint8_t> out(nx, 0xEE), out_want(nx, 0x77);
        k.write_cells_row(cs.data(), words(w), nx, out.data());
        scalar_kernels().write_cells_row(cs.data(), words(w), nx, out_want.data());
        ASSERT_EQ(out, out_want) << nx;
        for (std::size_t x = 0; x < nx; ++x)  // the meaning, once
          ASSERT_EQ(out_want[x], ((w[x / 64] >> (x % 64)) & 1u) ? 1 : cs[x / 8]) << nx << " voxel " << x;
      }
  });
}
