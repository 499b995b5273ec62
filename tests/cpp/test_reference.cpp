// The fast pipeline (vectorised, multi-threaded, restructured scans) against the scalar reference
// in tests/cpp/reference/: every stage output must be identical, bit for bit, for both presets,
// any thread count and map shapes that are not multiples of the block sizes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "isa_levels.hpp"
#include "rules/departures.hpp"
#include "stages/divide.hpp"
#include "stages/histogram.hpp"
#include "stages/label.hpp"
#include "stages/refine.hpp"
#include "occseg/segment.hpp"
#include "stages/texture.hpp"
#include "stages/codes.hpp"
#include "stages/own_states.hpp"
#include "isa_levels.hpp"
#include "random_maps.hpp"
#include "reference/reference.hpp"
#include "isa_levels.hpp"

using namespace occseg;
using occseg::testing_isa::for_each_isa;

// The reference sums segment statistics in the library's documented slabs.
static_assert(reference::kSlab == kLabelSlab);

// The reference ends at the labelling; the object rules that follow it in the default preset
// (rules/objects.hpp, rules/structure.hpp) are tested on their own (test_objects.cpp,
// test_structure.cpp), so whole runs are compared with them off.
static Params labelled_defaults() {
  Params p = Params::defaults();
  p.object_gap = p.min_object_voxels = p.min_pocket_voxels = 0;
  p.structure_planes = 0;
  return p;
}

namespace {

void expect_same_segments(const std::vector<Segment>& a, const std::vector<Segment>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, b[i].id) << what << " segment " << i;
    EXPECT_EQ(a[i].state, b[i].state) << what << " segment " << i;
    EXPECT_EQ(a[i].voxels, b[i].voxels) << what << " segment " << i;
    EXPECT_EQ(a[i].bbox_min, b[i].bbox_min) << what << " segment " << i;
    EXPECT_EQ(a[i].bbox_max, b[i].bbox_max) << what << " segment " << i;
    // Exact: the statistics are sums in a fixed order whatever the thread count.
    EXPECT_EQ(a[i].mop, b[i].mop) << what << " segment " << i;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a[i].centroid[k], b[i].centroid[k]) << what << " segment " << i;
  }
}

// The own states as bits, as segment()'s fused map pass writes them (detail::CellRows, straight
// from the values): every level of the row kernels the processor has must give the bits packed
// from own_states()' bytes.
detail::OwnBitsStore own_bits(const Grid& g) {
  const Dims& d = g.dims;
  detail::OwnBitsStore want = detail::pack_own_bits(own_states(g, Params()).data(), d, 1);
  for_each_isa([&](kernels::Isa) {
    std::vector<std::uint64_t> u(want.unknown.size(), ~std::uint64_t(0)), o(want.occupied.size(), ~std::uint64_t(0));
    float lo = 0, hi = 0;
    detail::float_bounds(Params().free_below, Params().occupied_above, lo, hi);
    detail::CellRows rows(g, nullptr, lo, hi, u.data(), o.data());
    for (std::size_t z = 0; z < d.nz; ++z)
      for (std::size_t y = 0; y < d.ny; ++y) rows.add_row(y, z, g.values() + g.index(0, y, z));
    EXPECT_EQ(u, want.unknown);
    EXPECT_EQ(o, want.occupied);
  });
  return want;
}

// The own states' unknown voxels as bits (own_bits()).
std::vector<std::uint64_t> unknown_bits(const Grid& g) { return own_bits(g).unknown; }

bool same_blocks(const std::vector<Block>& a, const std::vector<Block>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(a[i].lo, b[i].lo, sizeof a[i].lo) || std::memcmp(a[i].hi, b[i].hi, sizeof a[i].hi)) return false;
  return true;
}

struct Case {
  Dims dims;
  std::uint64_t seed;
  double noise;
};

const Case kCases[] = {
    {{37, 29, 23}, 1, 1.0},  {{70, 45, 33}, 2, 0.3},  {{65, 66, 17}, 3, 1.0}, {{90, 77, 1}, 4, 0.6},
    {{1, 1, 50}, 5, 1.0},    {{100, 3, 40}, 6, 0.5},  {{130, 67, 70}, 7, 0.05}, {{9, 1, 70}, 8, 1.0},
};

}  // namespace

TEST(Reference, TextureCodesMatch) {
  // Every level of the kernels the processor has: the compiler-vectorised contrast kernel and
  // the hand-written AVX2 and AVX-512 ones.
  for_each_isa([&](kernels::Isa level) {
    const std::string vector_kernel = kernels::isa_name(level);
    for (const Case& c : kCases) {
      const Grid g = test::random_map(c.dims, c.seed, c.noise);
      const TextureMap ref = reference::texture(g, 8);
      for (int t : {1, 2, 3})
        EXPECT_EQ(compute_texture(g, 8, t).codes, ref.codes) << "seed " << c.seed << " kernel " << vector_kernel;
      // The pipeline's way: codes into caller storage, the LBP codes parked in scratch between
      // the passes (dirty storage: every interior voxel's entries must be written).
      std::vector<std::uint16_t> codes(g.p.size(), 0x1234);
      std::vector<std::uint8_t> scratch(g.p.size(), 0xA5);
      detail::compute_texture_into(g, 8, 2, codes.data(), scratch.data());
      EXPECT_EQ(codes, ref.codes) << "seed " << c.seed << " kernel " << vector_kernel << " with scratch";
      EXPECT_EQ(compute_texture(g, 5, 2).codes, reference::texture(g, 5).codes) << "seed " << c.seed;
    }
  });
}

TEST(Reference, WholePipelineMatchesForBothPresets) {
  for (const Case& c : kCases) {
    const Grid g = test::random_map(c.dims, c.seed, c.noise);
    for (Params p : {Params::paper(), labelled_defaults()}) {
      p.texture = "lbp6";  // the reference's operator, also for the 2D case (whose default is lbp8)
      const reference::Output ref = reference::segment(g, p);
      for (int t : {1, 2, 3}) {
        p.threads = t;
        const std::string what = std::string(preset_name(p.preset)) + " seed " + std::to_string(c.seed) +
                                 " threads " + std::to_string(t);
        const Result r = segment(g, p, true);
        EXPECT_TRUE(same_blocks(r.blocks, ref.blocks)) << what;
        EXPECT_EQ(r.created_states, ref.created) << what;
        EXPECT_EQ(r.labels, ref.labels) << what;
        expect_same_segments(r.segments, ref.segments, what);
      }
      // Without the stages kept, the creation leaves the states to the unknown growth, which
      // writes each row once (every level of the row kernels).
      p.threads = 2;
      const int levels = for_each_isa([&](kernels::Isa level) {
        const Result r = segment(g, p);
        const std::string what = std::string(preset_name(p.preset)) + " seed " + std::to_string(c.seed) +
                                 " kernels " + kernels::isa_name(level) + " without the stages";
        EXPECT_EQ(r.labels, ref.labels) << what;
        expect_same_segments(r.segments, ref.segments, what);
      });
      EXPECT_GE(levels, 2);
    }
  }
}

// Rows whose only occupied voxels lie in their last cell of 8 (a map 45 voxels wide: cells 40..44
// hold the object) must still be swept: the boundary at x = 40 into the object has low values
// behind it, which the x sweep gives back to the free side. (The creation flags the rows with an
// occupied voxel for the sweeps from its cells' states.) Blocks of one cell (Smax = 8), so that
// the object's cells are created occupied; the paper preset, whose only change there is the sweep.
TEST(Reference, RowsOccupiedOnlyInTheirLastCellAreSwept) {
  Grid g(Dims{45, 16, 16}, 0.15f);
  test::Rng r(11);
  for (std::size_t z = 0; z < 16; ++z)
    for (std::size_t y = 0; y < 16; ++y)
      for (std::size_t x = 0; x < 45; ++x) {
        float& v = g.at(x, y, z);
        v = static_cast<float>(0.1 + 0.1 * r.uniform());
        if (x >= 40) v = x <= 41 && (y + z) % 3 == 0 ? 0.1f : 0.9f;  // the object, low at its face
      }
  for (Params p : {Params::paper(), labelled_defaults()}) {
    p.smax = 8;
    const reference::Output ref = reference::segment(g, p);
    const Result got = segment(g, p, true);
    EXPECT_EQ(got.labels, ref.labels) << preset_name(p.preset);
    EXPECT_EQ(got.created_states, ref.created) << preset_name(p.preset);
    if (p.preset != Preset::paper) continue;
    // The sweep did something: voxels created occupied at the object's face end up free.
    const std::vector<std::uint8_t> states = voxel_states(got);
    std::size_t given_back = 0;
    for (std::size_t z = 0; z < 16; ++z)
      for (std::size_t y = 0; y < 16; ++y)
        given_back += states[g.index(40, y, z)] == static_cast<std::uint8_t>(State::free) &&
                      got.created_states[g.index(40, y, z)] == static_cast<std::uint8_t>(State::occupied);
    EXPECT_GT(given_back, 40u);
  }
}

// The built-in operator's codes through the division as segment() runs it (faces_only: blocks
// inside the map counted without the kNoTexture test, the flat code as the common one), with
// the division's kernels of every level the processor has.
TEST(Reference, DivisionMatchesWithEveryCountingKernel) {
  std::size_t with_flat = 0, without_flat = 0;
  for (const Case& c : kCases) {
    const Grid g = test::random_map(c.dims, c.seed, c.noise);
    const TextureMap t = reference::texture(g, 8);
    const auto flat = static_cast<std::size_t>(std::count(t.codes.begin(), t.codes.end(), 63 * 8));
    with_flat += 10 * flat >= t.codes.size();
    without_flat += flat == 0;
    for (Params p : {Params::paper(), labelled_defaults()}) {
      const std::vector<Block> want = reference::divide(g, t, p);
      const int levels = testing_isa::for_each_isa([&](kernels::Isa level) {
        for (int threads : {1, 2}) {
          p.threads = threads;
          const auto got = detail::divide_codes(g, reinterpret_cast<const detail::code_t*>(t.codes.data()),
                                                t.code_count(), p, /*faces_only=*/true, kernels::table(level));
          EXPECT_TRUE(same_blocks(got, want)) << "seed " << c.seed << " threads " << threads;
        }
      });
      EXPECT_GE(levels, 2);
    }
  }
  // Maps where the flat (common) code is a tenth of the voxels or more (unknown boxes at exactly
  // 0.5), and maps without it.
  EXPECT_GE(with_flat, 3u);
  EXPECT_GE(without_flat, 1u);
}

// The division's G-statistics (and the public g_statistic()) bit for bit, and every pair of
// siblings taken: one 16^3 block of eight 8^3 octants with random histograms over 40 codes spread
// over the 512 bins (each sum fills its eight lanes several times), X set to the reference's
// Gmax / Gmin over the 28 pairs and to the next double below it. The block must stay whole at X
// and split below it, with the kernels of every level: a G one rounding off, or a pair left out (each of
// the 28 pairs is the largest or the smallest in some of the blocks), moves the ratio across one
// of the two.
TEST(Reference, DivisionRatioIsExactAtTheThreshold) {
  const Dims d{16, 16, 16};
  const Grid g(d, 0.5f);
  std::vector<std::uint16_t> codes(d.count());
  std::vector<std::vector<bool>> extreme(8, std::vector<bool>(8, false));
  Params p = Params::defaults();
  p.smax = 16;
  p.smin = 8;
  for (int trial = 0; trial < 56; ++trial) {
    test::Rng r(500 + static_cast<std::uint64_t>(trial));
    std::vector<std::vector<std::uint32_t>> h(8, std::vector<std::uint32_t>(512, 0));
    // Octants `close` and `twin` (pair number trial % 28) draw from nearly the same weights: their
    // pair is most likely the smallest.
    int twin = 1, close = trial % 28;
    while (close >= twin) close -= twin++;
    double w[8][40];
    for (int k = 0; k < 8; ++k)
      for (double& x : w[k]) x = r.uniform() * r.uniform();
    for (int c = 0; c < 40; ++c) w[twin][c] = w[close][c] * (0.9 + 0.2 * r.uniform());
    for (int k = 0; k < 8; ++k) {
      double sum = 0;
      for (double x : w[k]) sum += x;
      for (std::size_t z = 0; z < 8; ++z)
        for (std::size_t y = 0; y < 8; ++y)
          for (std::size_t x = 0; x < 8; ++x) {
            double u = r.uniform() * sum;
            int c = 0;
            while (c < 39 && (u -= w[k][c]) > 0) ++c;
            const auto code = static_cast<std::uint16_t>(c * 13 % 512);  // 40 bins spread over 0..507
            const std::size_t i = g.index(x + 8 * (k & 1), y + 8 * (k >> 1 & 1), z + 8 * (k >> 2));
            codes[i] = code;
            ++h[static_cast<std::size_t>(k)][code];
          }
    }
    double gmax = 0, gmin = HUGE_VAL;
    int max_pair[2] = {0, 0}, min_pair[2] = {0, 0};
    for (int b = 1; b < 8; ++b)
      for (int a = 0; a < b; ++a) {
        const double v = reference::g_statistic(h[a].data(), h[b].data(), 512);
        EXPECT_EQ(g_statistic(h[a].data(), h[b].data(), 512), v) << "the public G-statistic, trial " << trial;
        if (v > gmax) gmax = v, max_pair[0] = a, max_pair[1] = b;
        if (v < gmin) gmin = v, min_pair[0] = a, min_pair[1] = b;
      }
    ASSERT_GT(gmin, 0.0);
    extreme[max_pair[0]][max_pair[1]] = extreme[min_pair[0]][min_pair[1]] = true;
    const double ratio = gmax / gmin;
    // The rule itself (should_split over g_statistic), then the division on every level.
    const std::vector<const std::uint32_t*> octants = {h[0].data(), h[1].data(), h[2].data(), h[3].data(),
                                                       h[4].data(), h[5].data(), h[6].data(), h[7].data()};
    EXPECT_FALSE(should_split(octants, 512, ratio)) << "trial " << trial;
    EXPECT_TRUE(should_split(octants, 512, std::nextafter(ratio, 0.0))) << "trial " << trial;
    testing_isa::for_each_isa([&](kernels::Isa level) {
      for (const double x : {ratio, std::nextafter(ratio, 0.0)}) {
        p.split_ratio = x;
        const auto got = detail::divide_codes(g, codes.data(), 512, p, /*faces_only=*/false, kernels::table(level));
        EXPECT_EQ(got.size(), x == ratio ? 1u : 8u) << "trial " << trial << " X " << x;
      }
    });
  }
  for (int b = 1; b < 8; ++b)
    for (int a = 0; a < b; ++a) EXPECT_TRUE(extreme[a][b]) << "pair " << a << ", " << b << " never decided the ratio";
}

// A plugin's codes may leave any voxel without texture (kNoTexture), inside the map too: there
// the division tests every voxel (only the built-in operator's codes, whose kNoTexture voxels lie
// on the outer faces, are counted without the test in blocks inside the map).
TEST(Reference, DivisionOfCodesWithoutTextureInside) {
  const Grid g = test::random_map(Dims{70, 45, 33}, 2, 0.3);
  TextureMap t = reference::texture(g, 8);
  test::Rng r(5);
  std::size_t inside = 0;
  for (std::size_t i = 0; i < t.codes.size(); ++i)
    if (r.below(10) == 0) {
      t.codes[i] = kNoTexture;
      const std::size_t x = i % 70, y = (i / 70) % 45, z = i / (70 * 45);
      inside += x > 8 && x < 60 && y > 8 && y < 40 && z > 8 && z < 30;
    }
  ASSERT_GT(inside, 1000u);
  for (int threads : {1, 2}) {
    Params p;
    p.threads = threads;
    EXPECT_TRUE(same_blocks(divide(g, t, p), reference::divide(g, t, p))) << threads;
  }
}

TEST(Reference, OtherParametersMatch) {
  const Grid g = test::random_map(Dims{53, 41, 37}, 11, 0.7);
  Params variants[4] = {labelled_defaults(), Params::paper(), labelled_defaults(), Params::paper()};
  variants[0].smin = 4;
  variants[0].smax = 16;
  variants[0].lookahead = 5;
  variants[1].refine_passes = 3;
  variants[1].contrast_bins = 3;
  variants[2].gap_radius = 2;
  variants[2].split_ratio = 2.5;
  variants[3].smin = 2;
  variants[3].smax = 32;
  variants[3].lookahead = 1;
  for (Params& p : variants) {
    const reference::Output ref = reference::segment(g, p);
    p.threads = 2;
    const Result r = segment(g, p, true);
    EXPECT_TRUE(same_blocks(r.blocks, ref.blocks));
    EXPECT_EQ(r.labels, ref.labels);
    expect_same_segments(r.segments, ref.segments, "variant");
  }
}

// Contrasts exactly on (and one float step either side of) the quantiser's 1/4096 grid: where the
// vectorised float kernel must hand over to the double arithmetic of texture_unit().
TEST(Reference, ContrastsOnStepBoundariesMatch) {
  Grid g(Dims{41, 37, 29}, 0.5f);
  test::Rng r(99);
  for (auto& v : g.p) {
    const int k = 1 + r.below(2000);
    const float base = 0.5f - static_cast<float>(k) / 4096.0f;  // exact: a multiple of 2^-12
    const int nudge = r.below(5);
    v = nudge == 0 ? 0.5f : (nudge == 1 ? base : (nudge == 2 ? std::nextafter(base, 1.0f) : (nudge == 3 ? std::nextafter(base, 0.0f) : 0.75f)));
  }
  for_each_isa([&](kernels::Isa level) {
    for (int bins : {8, 64})
      EXPECT_EQ(compute_texture(g, bins, 2).codes, reference::texture(g, bins).codes)
          << bins << " " << kernels::isa_name(level);
  });
}

// The unknown growth on bit masks against the reference's six byte scans, on random per-voxel
// states (runs of candidates start and end anywhere, also across 64-voxel words and at the row
// ends), rows of 1 to 200 voxels, any thread count, masks in dirty caller storage or their own,
// at every kernel level.
namespace {
// A map value: 0.5 for a share `half` of the voxels, else 0.2 or 0.9 evenly.
float band_value(test::Rng& r, double half) {
  const double u = r.uniform();
  return u < half ? 0.5f : (u < (1 + half) / 2 ? 0.2f : 0.9f);
}
}  // namespace

// The own states as bits from every row kernel (own_bits() checks them against the bytes), on
// values at the band's float edges and one step either side of them, rows of 1 to 200 voxels
// (the kernels' 64-voxel steps and their tails); the bytes themselves against the double
// thresholds of Params.
TEST(Reference, OwnBitsMatchAtTheBandEdges) {
  float lo = 0, hi = 0;
  detail::float_bounds(Params().free_below, Params().occupied_above, lo, hi);
  const float values[] = {0.0f, std::nextafter(lo, 0.0f), lo, std::nextafter(lo, 1.0f), 0.5f,
                          std::nextafter(hi, 0.0f), hi, std::nextafter(hi, 1.0f), 1.0f, 0.2f, 0.9f};
  const Dims dims[] = {{1, 3, 2}, {7, 2, 3}, {63, 2, 2}, {64, 3, 2}, {65, 2, 3}, {130, 2, 2}, {200, 3, 3}};
  test::Rng r(77);
  int edges = 0;
  for (const Dims& d : dims) {
    Grid g(d, 0.5f);
    for (float& v : g.p) v = values[r.below(11)];
    const std::vector<std::uint8_t> own = own_states(g, Params());
    for (std::size_t i = 0; i < own.size(); ++i) {
      const double v = g.p[i];
      ASSERT_EQ(own[i], v < Params().free_below ? 0 : (v > Params().occupied_above ? 2 : 1)) << v;
      edges += g.p[i] == lo || g.p[i] == hi;
    }
    own_bits(g);
  }
  EXPECT_GT(edges, 100);
}

TEST(Reference, UnknownGrowthMatchesOnRandomStates) {
  const Dims dims[] = {{1, 1, 50}, {63, 3, 4}, {64, 5, 3}, {65, 4, 6}, {130, 3, 3}, {200, 7, 5}, {129, 1, 1}};
  std::uint64_t seed = 1;
  for (const Dims& d : dims)
    for (int round = 0; round < 4; ++round) {
      test::Rng r(seed++);
      Grid g(d, 0.5f);
      std::vector<std::uint8_t> st(d.count());
      const double half = 0.3 + 0.2 * round;  // share of voxels at 0.5
      for (std::size_t i = 0; i < st.size(); ++i) {
        g.p[i] = band_value(r, half);
        const double v = r.uniform();
        st[i] = v < 0.55 ? 0 : (v < 0.85 ? 1 : 2);
      }
      if (round == 3 && d.nx == 200) {  // one run of candidates through four words, each way
        std::fill(g.p.begin(), g.p.end(), 0.5f);
        std::fill(st.begin(), st.end(), 2);          // occupied: no growth along y or z
        std::fill(st.begin(), st.begin() + 200, 0);  // rows 0 and 2: candidates
        std::fill(st.begin() + 400, st.begin() + 600, 0);
        st[0] = 1;    // row 0: grows up from x = 0 to 199
        st[599] = 1;  // row 2: grows down from x = 199 to 0
      }
      std::vector<std::uint8_t> want = st;
      reference::refine_unknown(want, g, Params());
      for_each_isa([&](kernels::Isa) {
        for (int threads : {1, 3}) {
          Params p;
          p.threads = threads;
          std::vector<std::uint8_t> got = st;
          refine_unknown(got, g, p);
          EXPECT_EQ(got, want) << d.nx << "x" << d.ny << "x" << d.nz << " round " << round << " threads " << threads;
          if (round == 3 && d.nx == 200) {  // both rows wholly unknown
            EXPECT_EQ(std::count(got.begin(), got.begin() + 200, 1) +
                          std::count(got.begin() + 400, got.begin() + 600, 1),
                      400);
          }
          std::vector<std::uint64_t> scratch(detail::grow_unknown_scratch_bytes(d) / 8 + 1, 0xA5A5A5A5A5A5A5A5ull);
          got = st;
          const std::vector<std::uint8_t> own = own_states(g, p);
          detail::grow_unknown(got.data(), own.data(), d, threads, reinterpret_cast<std::uint8_t*>(scratch.data()),
                               scratch.size() * 8);
          EXPECT_EQ(got, want) << d.nx << "x" << d.ny << "x" << d.nz << " round " << round << " in scratch";
          got = st;  // from the unknown bits segment() has, not reading `own`
          const std::vector<std::uint8_t> no_own(own.size(), 0xEE);
          detail::grow_unknown(got.data(), no_own.data(), d, threads, nullptr, 0, unknown_bits(g).data());
          EXPECT_EQ(got, want) << d.nx << "x" << d.ny << "x" << d.nz << " round " << round << " from bits";
        }
      });
    }
}

// The default rules on random own and created states, at every kernel level (the AVX-512 and
// AVX2 row kernels where the processor has them, the AVX2 one for rows of 32 voxels or more, its
// last step overlapping the one before; the scalar one) on the own states as bits (from the map,
// as segment() has them) and as bytes (the public stage) against the reference: rows of 31 to 200 voxels, regions of
// 0.5 voxels, gaps touching occupied voxels (the flood's seeds) on both row ends.
TEST(Reference, VoxelRulesMatchOnRandomStates) {
  const Dims dims[] = {{31, 5, 4}, {32, 4, 5}, {33, 6, 5}, {34, 5, 4}, {35, 6, 5},
                       {64, 7, 3}, {65, 9, 4}, {97, 4, 6}, {200, 5, 5}};
  std::uint64_t seed = 40;
  std::size_t seeded_rows = 0;
  for (const Dims& d : dims)
    for (int round = 0; round < 3; ++round) {
      test::Rng r(seed++);
      Grid g(d, 0.5f);
      std::vector<std::uint8_t> st(d.count());
      const double half = 0.4 + 0.2 * round;  // share of voxels at 0.5
      for (std::size_t i = 0; i < st.size(); ++i) {
        g.p[i] = band_value(r, half);
        st[i] = static_cast<std::uint8_t>(r.below(3));
      }
      std::vector<std::uint8_t> want = st;
      reference::apply_voxel_rules(want, g, Params());
      const std::vector<std::uint8_t> own = own_states(g, Params());
      for (std::size_t i = 0; i < st.size(); i += d.nx)  // a candidate seed at a row end
        seeded_rows += own[i] == 1 && st[i] == 0 && want[i] == 1;
      for_each_isa([&](kernels::Isa level) {
        for (int threads : {1, 2}) {
          Params p;
          p.threads = threads;
          const detail::OwnBitsStore bits = own_bits(g);
          std::vector<std::uint8_t> got = st;
          detail::apply_voxel_rules(got.data(), bits.bits, d, p, nullptr, 0, kernels::active());
          EXPECT_EQ(got, want) << d.nx << "x" << d.ny << "x" << d.nz << " round " << round << " kernels "
                               << kernels::isa_name(level) << " threads " << threads;
          {  // the same with the resulting states' bits for the surface band (over garbage)
            const std::size_t W = (d.nx + 63) / 64, rows = d.ny * d.nz;
            std::vector<std::uint64_t> storage(3 * rows * W, 0xA5A5A5A5A5A5A5A5ull);
            std::vector<std::uint8_t> kinds(rows, 0);
            detail::StateBits sb;
            got = st;
            detail::apply_voxel_rules(got.data(), bits.bits, d, p, nullptr, 0, kernels::active(), &sb, storage.data(),
                                      kinds.data());
            ASSERT_EQ(got, want) << d.nx << "x" << d.ny << "x" << d.nz << " with bits";
            for (std::size_t row = 0; row < rows; ++row)
              for (std::size_t x = 0; x < 64 * W; ++x) {
                const std::size_t w = row * W + x / 64;
                const bool in = x < d.nx;
                const std::uint8_t s = in ? got[row * d.nx + x] : 3;
                ASSERT_EQ((sb.free[w] >> (x % 64)) & 1u, s == 0 ? 1u : 0u) << row << " " << x;
                ASSERT_EQ((sb.unknown[w] >> (x % 64)) & 1u, s == 1 ? 1u : 0u) << row << " " << x;
                ASSERT_EQ((sb.occupied[w] >> (x % 64)) & 1u, s == 2 ? 1u : 0u) << row << " " << x;
                if (in) {
                  ASSERT_TRUE(sb.rows[row] & (1u << s)) << row << " " << x;  // (kinds: a superset)
                }
              }
          }
          got = st;  // the public stage: own states as bytes
          apply_voxel_rules(got, own, d, p);
          EXPECT_EQ(got, want) << d.nx << "x" << d.ny << "x" << d.nz << " round " << round << " from bytes";
          p.gap_radius = 0;  // no opening: the regions are the 0.5 bits themselves
          Params p0;
          p0.gap_radius = 0;
          std::vector<std::uint8_t> want0 = st;
          reference::apply_voxel_rules(want0, g, p0);
          got = st;
          detail::apply_voxel_rules(got.data(), bits.bits, d, p, nullptr, 0, kernels::active());
          EXPECT_EQ(got, want0) << d.nx << "x" << d.ny << "x" << d.nz << " round " << round << " radius 0";
        }
      });
    }
  EXPECT_GT(seeded_rows, 10u);
}

// The labelling on random states against the reference union-find: maps of many 8-plane slabs
// (their first planes are joined on several threads at once), runs of 1 to 120 voxels of one
// state (slabs labelled with a table of their runs, which keeps their local numbers until the
// statistics), of 1 to 40 (tables and the label array, slab by slab) and of 1 to 6 (slabs labelled
// through the label array), 6- and 26-connectivity, 1 to 4 threads, every level of the kernels.
// Labels and the whole segment table must match.
TEST(Reference, LabellingMatchesOnRandomStatesAcrossManySlabs) {
  const Dims dims[] = {{41, 29, 70}, {70, 3, 129}, {5, 60, 41}, {130, 17, 33}};
  std::uint64_t seed = 7;
  for (const Dims& d : dims)
    for (double longest : {120.0, 40.0, 6.0}) {
      test::Rng r(seed++);
      Grid g(d, 0.5f);
      std::vector<std::uint8_t> st(d.count());
      for (std::size_t i = 0; i < st.size();) {
        const std::size_t run = 1 + static_cast<std::size_t>(r.uniform() * longest);
        const double v = r.uniform();
        const auto s = static_cast<std::uint8_t>(v < 0.4 ? 0 : (v < 0.7 ? 1 : 2));
        for (std::size_t k = 0; k < run && i < st.size(); ++k, ++i) st[i] = s;
      }
      // A run of its own in the last voxel: its start bit lies in the last, partly used byte of the
      // run-start bits (none of these voxel counts is a multiple of 8).
      st.back() = static_cast<std::uint8_t>((st[st.size() - 2] + 1) % 3);
      for (std::size_t i = 0; i < g.p.size(); ++i) g.p[i] = static_cast<float>(r.uniform());
      for (bool occupied26 : {false, true}) {
        LabelArray want;
        std::vector<Segment> want_segs;
        reference::label(st, g, want, want_segs, occupied26);
        testing_isa::for_each_isa([&](kernels::Isa level) {
          for (int threads : {1, 2, 3, 4}) {
            LabelArray got;
            std::vector<Segment> got_segs;
            label_components(st, g, got, got_segs, threads, occupied26);
            const std::string what = std::to_string(d.nx) + "x" + std::to_string(d.ny) + "x" +
                                     std::to_string(d.nz) + (occupied26 ? " 26" : " 6") + " threads " +
                                     std::to_string(threads) + " runs up to " +
                                     std::to_string(static_cast<int>(longest)) + " " + kernels::isa_name(level);
            EXPECT_TRUE(std::equal(got.begin(), got.end(), want.begin(), want.end())) << what;
            expect_same_segments(got_segs, want_segs, what);
          }
        });
      }
    }
}
