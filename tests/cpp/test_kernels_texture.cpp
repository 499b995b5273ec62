// The texture kernels (kernels/texture.hpp) of every instruction-set level against the scalar
// ones and against texture_unit(): every slot on rows of 0 to 318 voxels (the vector widths'
// tails), values at the edges of [0, 1] (-0.0, subnormals, 0.0, 1.0, 0.5), contrasts on the
// quantiser's step boundaries, ties, random values; and bad values for the kernels that check.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "isa_levels.hpp"
#include "kernels/kernels.hpp"
#include "random_maps.hpp"
#include "stages/texture.hpp"

using namespace occseg;
using kernels::kRecheckStep;

namespace {

class TextureKernels : public testing_isa::IsaTest {
 protected:
  const kernels::TextureKernels& scalar() const { return kernels::table(kernels::Isa::scalar).texture; }
  const kernels::TextureKernels& level() const { return kernels::active().texture; }
};
OCCSEG_INSTANTIATE_ISA_LEVELS(TextureKernels);

const std::size_t kLengths[] = {0, 1, 2, 3, 5, 7, 8, 9, 15, 16, 17, 23, 31, 32, 33, 47, 63, 64, 65, 100, 318};

// A row of n voxels with all six neighbours: a (n + 2) x 3 x 3 block of values, the row at y = 1,
// z = 1, x = 1 .. n.
struct Block3 {
  std::size_t n;
  std::vector<float> v;
  std::ptrdiff_t off[6];
  explicit Block3(std::size_t n_) : n(n_), v((n_ + 2) * 9, 0.5f) {
    const auto sy = static_cast<std::ptrdiff_t>(n + 2), sz = 3 * sy;
    const std::ptrdiff_t o[6] = {-1, 1, -sy, sy, -sz, sz};
    for (int k = 0; k < 6; ++k) off[k] = o[k];
  }
  float* row() { return v.data() + 1 + (n + 2) + 3 * (n + 2); }
};

// Fills the block in one of several ways: 0 random, 1 edge values, 2 multiples of 2^-12 and their
// float neighbours (contrasts on the quantiser's step boundaries), 3 a few values (ties),
// 4 bad values among valid ones (for kernels that check).
void fill(Block3& b, int mode, test::Rng& r) {
  const float edge[] = {-0.0f, 0.0f, 1.0f, 0.5f, 1e-40f, std::nextafter(0.0f, 1.0f), std::nextafter(1.0f, 0.0f),
                        0.25f, 0.75f};
  const float bad[] = {std::nanf(""), INFINITY, -INFINITY, -0.25f, 1.5f, std::nextafter(1.0f, 2.0f), -1e-40f};
  for (float& x : b.v) {
    switch (mode) {
      case 0: x = static_cast<float>(r.uniform()); break;
      case 1: x = edge[r.below(9)]; break;
      case 2: {
        const float base = 0.5f - static_cast<float>(1 + r.below(2000)) / 4096.0f;
        const int nudge = r.below(5);
        x = nudge == 0 ? 0.5f : nudge == 1 ? base : nudge == 2 ? std::nextafter(base, 1.0f)
                                               : nudge == 3 ? std::nextafter(base, 0.0f) : 0.75f;
        break;
      }
      case 3: x = static_cast<float>(r.below(4)) / 3.0f; break;
      default: x = r.below(8) == 0 ? bad[r.below(7)] : static_cast<float>(r.uniform()); break;
    }
  }
}

// texture_unit()'s parked step of voxel x of the row (the meaning every kernel's steps have).
std::uint16_t exact_step(const float* p, const std::ptrdiff_t* off, unsigned present) {
  double nb[6];
  for (int k = 0; k < 6; ++k) nb[k] = p[off[k]];
  const double c = texture_unit(p[0], nb, present).contrast;
  return c <= 1 ? ContrastQuantizer::parked_step(c) : 0;
}
std::uint8_t exact_lbp(const float* p, const std::ptrdiff_t* off, unsigned present) {
  double nb[6];
  for (int k = 0; k < 6; ++k) nb[k] = p[off[k]];
  return texture_unit(p[0], nb, present).lbp;
}

constexpr std::uint16_t kGuard = 0x5A5A;  // past the row: never written
constexpr std::uint8_t kGuard8 = 0xA5;

}  // namespace

// Steps and LBP codes of every level: certified steps are texture_unit()'s, the uncertain ones
// are marked (and maybe_recheck says so), the LBP codes are the scalar kernel's, nothing is
// written past the row, and valid rows (-0.0 and subnormals included) pass the value check.
TEST_P(TextureKernels, ContrastRowGivesTextureUnitsSteps) {
  test::Rng r(1);
  std::size_t sure = 0, uncertain = 0;
  for (int mode = 0; mode < 4; ++mode)
    for (std::size_t n : kLengths)
      for (int round = 0; round < 3; ++round) {
        Block3 b(n);
        fill(b, mode, r);
        const float* p = b.row();
        std::vector<std::uint16_t> steps(n + 8, kGuard), plain(n + 8, kGuard), want_steps(n + 8, kGuard);
        std::vector<std::uint8_t> lbp(n + 8, kGuard8), want_lbp(n + 8, kGuard8);
        bool maybe = false, want_maybe = false;
        const bool ok = level().contrast_row(p, b.off, n, steps.data(), lbp.data(), maybe);
        ASSERT_TRUE(scalar().contrast_row(p, b.off, n, want_steps.data(), want_lbp.data(), want_maybe));
        bool plain_maybe = false;  // without LBP codes: the same steps
        level().contrast_row(p, b.off, n, plain.data(), nullptr, plain_maybe);
        const std::string what = "mode " + std::to_string(mode) + " n " + std::to_string(n);
        EXPECT_TRUE(ok) << what;
        EXPECT_EQ(lbp, want_lbp) << what;
        EXPECT_EQ(plain, steps) << what;
        std::size_t marked = 0;
        for (std::size_t x = 0; x < n; ++x) {
          EXPECT_EQ(want_lbp[x], exact_lbp(p + x, b.off, 63)) << what << " x " << x;
          const std::uint16_t exact = exact_step(p + x, b.off, 63);
          for (const std::uint16_t s : {steps[x], want_steps[x]})
            EXPECT_TRUE(s == kRecheckStep || s == exact) << what << " x " << x << ": " << s << " for " << exact;
          marked += steps[x] == kRecheckStep;
          sure += steps[x] != kRecheckStep && steps[x] != 0;
        }
        uncertain += marked;
        if (marked) {
          EXPECT_TRUE(maybe) << what;
        }
        EXPECT_EQ(steps[n], kGuard) << what;
        EXPECT_EQ(lbp[n], kGuard8) << what;
      }
  EXPECT_GT(sure, 1000u);
  EXPECT_GT(uncertain, 10u);  // the step-boundary rows: the recheck is exercised
}

// Kernels that check values report every row with a centre outside [0, 1] (NaN, infinities,
// -1e-40, one float above 1.0) and no other; the arithmetic on bad values is defined (the steps
// are not checked: such a map is rejected). Only the scalar kernel leaves the values to the stage.
TEST_P(TextureKernels, ContrastRowChecksValues) {
  if (!level().checks_values) {
    EXPECT_EQ(level().contrast_row, scalar().contrast_row) << "a vector kernel must check the values it loads";
    return;
  }
  test::Rng r(2);
  std::size_t rejected = 0;
  for (std::size_t n : kLengths)
    for (int round = 0; round < 20; ++round) {
      Block3 b(n);
      fill(b, 4, r);
      float* p = b.row();
      if (round == 0 && n) p[n - 1] = -0.0f;  // valid: compares equal to 0
      std::vector<std::uint16_t> steps(n + 8);
      std::vector<std::uint8_t> lbp(n + 8);
      bool maybe = false;
      const bool ok = level().contrast_row(p, b.off, n, steps.data(), lbp.data(), maybe);
      EXPECT_EQ(ok, probabilities_in_range(p, n)) << "n " << n << " round " << round;
      rejected += !ok;
    }
  EXPECT_GT(rejected, 100u);
}

// Maps with an axis of size 1 (absent neighbours at offset 0, masked out): every neighbourhood.
TEST_P(TextureKernels, ContrastRowAnyGivesTextureUnitsSteps) {
  test::Rng r(3);
  for (unsigned present : {3u, 12u, 48u, 15u, 51u, 60u, 1u, 63u})
    for (std::size_t n : kLengths) {
      Block3 b(n);
      fill(b, static_cast<int>(n % 4), r);
      std::ptrdiff_t off[6];
      for (int k = 0; k < 6; ++k) off[k] = present & (1u << k) ? b.off[k] : 0;
      std::vector<std::uint16_t> steps(n + 8, kGuard), want(n + 8, kGuard);
      std::vector<std::uint8_t> lbp(n + 8, kGuard8), want_lbp(n + 8, kGuard8);
      level().contrast_row_any(b.row(), off, n, present, steps.data(), lbp.data());
      scalar().contrast_row_any(b.row(), off, n, present, want.data(), want_lbp.data());
      EXPECT_EQ(steps, want) << present << " " << n;
      EXPECT_EQ(lbp, want_lbp) << present << " " << n;
      for (std::size_t x = 0; x < n; ++x) {
        EXPECT_EQ(lbp[x], exact_lbp(b.row() + x, off, present));
        if (steps[x] != kRecheckStep) {
          EXPECT_EQ(steps[x], exact_step(b.row() + x, off, present));
        }
      }
    }
}

TEST_P(TextureKernels, AnyRecheckFindsTheMark) {
  test::Rng r(4);
  for (std::size_t n : kLengths)
    for (std::size_t at = 0; at <= n; ++at) {  // at == n: no mark
      std::vector<std::uint16_t> v(n + 1);
      for (auto& s : v) s = static_cast<std::uint16_t>(r.below(4097));
      v[at] = kRecheckStep;
      EXPECT_EQ(level().any_recheck(v.data(), n), at < n) << n << " " << at;
      EXPECT_EQ(scalar().any_recheck(v.data(), n), at < n) << n << " " << at;
    }
}

// The histograms of the parked steps, summed over the interleaved four (kernels may put a step in
// another of them); entry 0 (flat voxels) is not used.
TEST_P(TextureKernels, CountStepsCountsEveryNonZeroStep) {
  test::Rng r(5);
  const std::size_t stride = kernels::kStepStride, hists = kernels::kStepHistograms;
  for (std::size_t n : kLengths)
    for (int flat_share : {0, 5, 9, 10}) {  // tenths of flat voxels
      std::vector<std::uint16_t> v(n);
      for (auto& s : v) s = r.below(10) < flat_share ? 0 : static_cast<std::uint16_t>(1 + r.below(4096));
      if (n) v[n - 1] = 4096;  // the top step
      std::vector<std::uint64_t> h(hists * stride, 0), want_h(hists * stride, 0);
      std::vector<std::uint16_t> list(n + 32, 0xFFFF);
      level().count_steps(v.data(), n, h.data(), list.data());
      scalar().count_steps(v.data(), n, want_h.data(), list.data());
      std::vector<std::uint64_t> truth(stride, 0);
      for (std::uint16_t s : v) ++truth[s];
      for (std::size_t f = 1; f < stride; ++f) {
        std::uint64_t got = 0, want = 0;
        for (std::size_t k = 0; k < hists; ++k) got += h[k * stride + f], want += want_h[k * stride + f];
        ASSERT_EQ(got, truth[f]) << "n " << n << " step " << f;
        ASSERT_EQ(want, truth[f]) << "n " << n << " step " << f;
      }
    }
}

namespace {

// Rise lists as the quantiser makes them (1 to 16 entries, repeated where cuts tie) and made by
// hand at the ends of the steps (0, 1, 4095, 4096).
std::vector<std::vector<std::uint16_t>> rise_lists(test::Rng& r) {
  std::vector<std::vector<std::uint16_t>> lists = {{}, {0}, {4095}, {1, 1, 4095}, {0, 0, 0, 4096}};
  for (int bins : {2, 3, 8, 17}) {
    std::vector<std::uint64_t> fine(ContrastQuantizer::kFine, 0);
    for (int k = 0; k < 200; ++k) fine[r.below(k % 3 ? 50 : ContrastQuantizer::kFine)] += 1 + r.below(5);
    lists.push_back(ContrastQuantizer(bins, fine).rises());
  }
  std::vector<std::uint16_t> sixteen;
  for (int k = 0; k < 16; ++k) sixteen.push_back(static_cast<std::uint16_t>(r.below(4097)));
  std::sort(sixteen.begin(), sixteen.end());
  lists.push_back(sixteen);
  return lists;
}

std::uint16_t level_of(std::uint16_t v, const std::vector<std::uint16_t>& rises) {
  int l = v != 0;
  for (std::uint16_t t : rises) l += v > t;
  return static_cast<std::uint16_t>(l);
}

}  // namespace

TEST_P(TextureKernels, CodesFromLbpCombineTheLevels) {
  test::Rng r(6);
  for (const auto& rises : rise_lists(r)) {
    ASSERT_LE(rises.size(), 16u);
    for (std::uint16_t bins : {2, 5, 8, 64})
      for (std::size_t n : kLengths) {
        std::vector<std::uint16_t> steps(n + 8, kGuard);
        std::vector<std::uint8_t> lbp(n + 8);
        for (std::size_t x = 0; x < n; ++x) {
          steps[x] = r.below(3) == 0 ? 0 : static_cast<std::uint16_t>(r.below(4097));
          lbp[x] = static_cast<std::uint8_t>(r.below(64));
        }
        std::vector<std::uint16_t> got = steps, want = steps;
        level().codes_from_lbp(got.data(), lbp.data(), n, rises.data(), rises.size(), bins);
        scalar().codes_from_lbp(want.data(), lbp.data(), n, rises.data(), rises.size(), bins);
        EXPECT_EQ(got, want) << "n " << n << " bins " << bins << " rises " << rises.size();
        for (std::size_t x = 0; x < n; ++x)
          ASSERT_EQ(want[x], lbp[x] * bins + level_of(steps[x], rises)) << "n " << n << " x " << x;
        EXPECT_EQ(got[n], kGuard);
      }
  }
}

// The fused pass 2 from the map: whatever prefix a level does in one kernel, finished by the
// slots the stage uses for the rest, gives the scalar path's codes.
TEST_P(TextureKernels, CodesRowGivesTheSameCodes) {
  test::Rng r(7);
  for (const auto& rises : rise_lists(r))
    for (std::uint16_t bins : {3, 8})
      for (std::size_t n : kLengths) {
        Block3 b(n);
        fill(b, static_cast<int>(n % 4), r);
        const float* p = b.row();
        std::vector<std::uint16_t> steps(n + 8, kGuard);
        for (std::size_t x = 0; x < n; ++x) steps[x] = static_cast<std::uint16_t>(r.below(4097));
        const auto finish = [&](const kernels::TextureKernels& k, std::vector<std::uint16_t>& row) {
          const std::size_t done = k.codes_row(p, b.off, n, rises.data(), rises.size(), bins, row.data());
          EXPECT_LE(done, n);
          EXPECT_EQ(done % 8, 0u);
          std::vector<std::uint8_t> lbp(n);
          std::vector<std::uint16_t> lvl(n);
          k.lbp_row(p + done, b.off, n - done, 63, lbp.data());
          k.levels_row(row.data() + done, n - done, rises.data(), rises.size(), lvl.data());
          k.combine_row(lbp.data(), lvl.data(), n - done, bins, row.data() + done);
        };
        std::vector<std::uint16_t> got = steps, want = steps;
        finish(level(), got);
        finish(scalar(), want);
        EXPECT_EQ(got, want) << "n " << n << " bins " << bins;
        for (std::size_t x = 0; x < n; ++x)
          ASSERT_EQ(want[x], exact_lbp(p + x, b.off, 63) * bins + level_of(steps[x], rises)) << "n " << n;
      }
}

TEST_P(TextureKernels, LbpRowLevelsRowCombineRow) {
  test::Rng r(8);
  for (unsigned present : {63u, 15u, 48u})
    for (std::size_t n : kLengths) {
      Block3 b(n);
      fill(b, static_cast<int>(n % 4), r);
      std::ptrdiff_t off[6];
      for (int k = 0; k < 6; ++k) off[k] = present & (1u << k) ? b.off[k] : 0;
      std::vector<std::uint8_t> lbp(n + 8, kGuard8), want(n + 8, kGuard8);
      level().lbp_row(b.row(), off, n, present, lbp.data());
      scalar().lbp_row(b.row(), off, n, present, want.data());
      EXPECT_EQ(lbp, want) << present << " " << n;
      for (std::size_t x = 0; x < n; ++x) ASSERT_EQ(want[x], exact_lbp(b.row() + x, off, present));
    }
  for (const auto& rises : rise_lists(r))
    for (std::size_t n : kLengths) {
      std::vector<std::uint16_t> v(n), lvl(n + 8, kGuard), want(n + 8, kGuard);
      for (auto& s : v) s = static_cast<std::uint16_t>(r.below(4097));
      level().levels_row(v.data(), n, rises.data(), rises.size(), lvl.data());
      scalar().levels_row(v.data(), n, rises.data(), rises.size(), want.data());
      EXPECT_EQ(lvl, want) << n;
      for (std::size_t x = 0; x < n; ++x) ASSERT_EQ(want[x], level_of(v[x], rises));
      std::vector<std::uint8_t> lbp(n);
      for (auto& l : lbp) l = static_cast<std::uint8_t>(r.below(64));
      for (std::uint16_t bins : {2, 7, 64}) {
        std::vector<std::uint16_t> code(n + 8, kGuard), want_code(n + 8, kGuard);
        level().combine_row(lbp.data(), want.data(), n, bins, code.data());
        scalar().combine_row(lbp.data(), want.data(), n, bins, want_code.data());
        EXPECT_EQ(code, want_code) << n;
        for (std::size_t x = 0; x < n; ++x) ASSERT_EQ(want_code[x], lbp[x] * bins + want[x]);
      }
    }
}
