// The division's kernels (kernels/divide.hpp), every slot at every level against the scalar one
// (the scalar one against a count written out here): tails of every length around the vector
// widths, empty inputs, codes 0 and bins - 1, kNoTexture, hints that are right, wrong or absent,
// counts that need more than 32 bits once summed, and random data.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "isa_levels.hpp"
#include "kernels/kernels.hpp"
#include "occseg/texture_codes.hpp"
#include "random_maps.hpp"

using namespace occseg;
using testing_isa::IsaTest;

namespace {

const kernels::DivideKernels& here() { return kernels::active().divide; }
const kernels::DivideKernels& scalar() { return kernels::table(kernels::Isa::scalar).divide; }

// Codes in runs (whole rows of one code, single voxels that differ), over `bins` codes, with
// kNoTexture voxels in runs and alone unless `textured`.
std::vector<std::uint16_t> random_codes(const Dims& d, std::uint64_t seed, std::size_t bins, bool textured) {
  test::Rng r(seed);
  std::vector<std::uint16_t> c(d.count());
  const auto code = [&] { return static_cast<std::uint16_t>(r.below(static_cast<int>(bins))); };
  for (std::size_t i = 0; i < c.size();) {
    const std::size_t run = 1 + static_cast<std::size_t>(r.below(24));
    const std::uint16_t v = !textured && r.below(5) == 0 ? kNoTexture : r.below(4) == 0 ? 0 : code();
    for (std::size_t k = 0; k < run && i < c.size(); ++k, ++i) c[i] = v;
    if (r.below(3) == 0 && i < c.size()) c[i++] = r.below(3) == 0 ? static_cast<std::uint16_t>(bins - 1) : code();
  }
  return c;
}

std::vector<std::uint32_t> count_by_hand(const std::vector<std::uint16_t>& codes, const Dims& d, const Block& b,
                                         std::size_t bins) {
  std::vector<std::uint32_t> h(bins, 0);
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
    for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y)
      for (std::uint32_t x = b.lo[0]; x < b.hi[0]; ++x) {
        const std::uint16_t c = codes[x + d.nx * (y + d.ny * z)];
        if (c != kNoTexture) ++h[c];
      }
  return h;
}

// Blocks at every x offset of the first 12 voxels and every width (rows of 8 starting anywhere,
// tails of 0 to 7, exactly 8 wide: the four-row path), 1 to 9 rows, 1 to 3 planes.
template <class Body>
std::size_t for_each_block(const Dims& d, Body&& body) {
  std::size_t n = 0;
  for (std::uint32_t x0 = 0; x0 < 12; ++x0)
    for (std::uint32_t w = 1; x0 + w <= d.nx; w += w < 17 ? 1 : 7)
      for (std::uint32_t rows = 1; rows <= 9 && 1 + rows <= d.ny; ++rows)
        for (std::uint32_t planes : {1u, 3u}) {
          body(Block{{x0, 1, 1}, {x0 + w, 1 + rows, 1 + planes}});
          ++n;
        }
  return n;
}

class DivideKernels : public IsaTest {};

TEST_P(DivideKernels, CountMatchesScalarAndTheCodes) {
  const Dims d{45, 11, 5};
  for (const std::size_t bins : {std::size_t(512), std::size_t(24)}) {
    for (const bool textured : {false, true}) {
      std::vector<std::uint16_t> codes = random_codes(d, 7 + bins + textured, bins, textured);
      if (!textured)  // blocks whose first voxel has no texture (the first guess of the packing kernels)
        for (std::size_t x = 0; x < 12; x += 3) codes[x + d.nx * (1 + d.ny)] = kNoTexture;
      const auto* c = reinterpret_cast<const kernels::code_t*>(codes.data());
      const auto flat = static_cast<std::uint16_t>(bins / 64 * 63);
      std::size_t without_texture = 0;
      const std::size_t blocks = for_each_block(d, [&](const Block& b) {
        const std::vector<std::uint32_t> want = count_by_hand(codes, d, b, bins);
        const std::uint16_t first = codes[b.lo[0] + d.nx * (b.lo[1] + d.ny * b.lo[2])];
        without_texture += first == kNoTexture;
        // Hints: the first voxel's code alone (kNoTexture included), the most frequent code with
        // 0 second, and codes the block may not hold at all.
        const std::uint16_t most = static_cast<std::uint16_t>(std::max_element(want.begin(), want.end()) - want.begin());
        const std::uint16_t hints[][2] = {{first, first}, {most, 0}, {flat, 0}, {0, static_cast<std::uint16_t>(bins - 1)}};
        for (const auto& hint : hints) {
          for (const bool may_lack : {true, false}) {
            if (!may_lack && !textured) continue;  // (the contract: no kNoTexture in the block)
            const kernels::BlockCodes in{c, d, b, may_lack, hint[0], hint[1]};
            std::vector<std::uint32_t> got(bins, 7), base(bins, 9);
            here().count(in, bins, got.data());
            scalar().count(in, bins, base.data());
            ASSERT_EQ(base, want) << "scalar, bins " << bins << " block x " << b.lo[0] << " width "
                                  << b.hi[0] - b.lo[0] << " rows " << b.hi[1] - b.lo[1];
            ASSERT_EQ(got, base) << "bins " << bins << " block x " << b.lo[0] << " width " << b.hi[0] - b.lo[0]
                                 << " rows " << b.hi[1] - b.lo[1] << " planes " << b.hi[2] - b.lo[2] << " hint "
                                 << hint[0] << ", " << hint[1] << " may lack texture " << may_lack;
          }
        }
      });
      EXPECT_GT(blocks, 1000u);
      if (!textured) {
        EXPECT_GT(without_texture, 10u);
      }
    }
  }
}

TEST_P(DivideKernels, CountOfUniformAndEmptyOfTextureBlocks) {
  const Dims d{33, 9, 4};
  for (const std::uint16_t v : {std::uint16_t(0), std::uint16_t(511), kNoTexture}) {
    const std::vector<std::uint16_t> codes(d.count(), v);
    const auto* c = reinterpret_cast<const kernels::code_t*>(codes.data());
    for_each_block(d, [&](const Block& b) {
      const std::vector<std::uint32_t> want = count_by_hand(codes, d, b, 512);
      for (const std::uint16_t common : {v, std::uint16_t(5)}) {
        std::vector<std::uint32_t> got(512, 3);
        here().count(kernels::BlockCodes{c, d, b, true, common, common}, 512, got.data());
        ASSERT_EQ(got, want) << "code " << v << " hint " << common << " width " << b.hi[0] - b.lo[0];
      }
    });
  }
}

TEST_P(DivideKernels, NonzeroValuesMatchScalar) {
  test::Rng r(3);
  for (std::size_t n = 0; n <= 70; n += n < 34 ? 1 : 9) {
    for (int pattern = 0; pattern < 4; ++pattern) {
      // 0: random, mostly zero; 1: none zero; 2: all zero; 3: the largest counts, a + b too.
      std::vector<std::uint32_t> a(n), b(n);
      for (std::size_t i = 0; i < n; ++i) {
        const bool zero = pattern == 2 || (pattern == 0 && r.below(3) != 0);
        a[i] = zero ? 0 : pattern == 3 ? 0x7FFFFFF0u + static_cast<std::uint32_t>(i % 8)
                                      : 1 + static_cast<std::uint32_t>(r.below(1000));
        b[i] = pattern == 2 ? 0 : pattern == 3 ? static_cast<std::uint32_t>(i % 5) * 3
                                                : r.below(2) ? 0 : static_cast<std::uint32_t>(r.below(70000));
      }
      for (const bool two : {false, true}) {
        std::vector<std::uint32_t> got(n + 16, 0xDEADu), want(n + 16, 0xBEEFu);
        const std::size_t m = here().nonzero_values(a.data(), two ? b.data() : nullptr, n, got.data());
        const std::size_t w = scalar().nonzero_values(a.data(), two ? b.data() : nullptr, n, want.data());
        std::vector<std::uint32_t> by_hand;
        for (std::size_t i = 0; i < n; ++i)
          if (const std::uint32_t v = two ? a[i] + b[i] : a[i]) by_hand.push_back(v);
        ASSERT_EQ(std::vector<std::uint32_t>(want.begin(), want.begin() + static_cast<long>(w)), by_hand)
            << "scalar, n " << n << " pattern " << pattern << " two " << two;
        ASSERT_EQ(m, w) << "n " << n << " pattern " << pattern << " two " << two;
        EXPECT_TRUE(std::equal(got.begin(), got.begin() + static_cast<long>(m), want.begin()))
            << "n " << n << " pattern " << pattern << " two " << two;
      }
    }
  }
}

TEST_P(DivideKernels, TotalMatchesScalar) {
  test::Rng r(4);
  for (std::size_t n = 0; n <= 80; n += n < 40 ? 1 : 13) {
    std::vector<std::uint32_t> h(n);
    for (int pattern = 0; pattern < 3; ++pattern) {
      for (std::size_t i = 0; i < n; ++i)
        h[i] = pattern == 0 ? static_cast<std::uint32_t>(r.below(100000)) : pattern == 1 ? 0xFFFFFFFFu : 0u;
      std::uint64_t want = 0;
      for (std::uint32_t v : h) want += v;  // beyond 32 bits with the largest counts
      EXPECT_EQ(scalar().total(h.data(), n), want) << "scalar, n " << n;
      EXPECT_EQ(here().total(h.data(), n), want) << "n " << n << " pattern " << pattern;
    }
  }
}

TEST_P(DivideKernels, SumEightAndAddCountsMatchScalar) {
  test::Rng r(5);
  for (std::size_t n = 0; n <= 72; n += n < 40 ? 1 : 8) {
    for (const std::size_t stride : {n, n + 3, std::size_t(512)}) {
      if (stride < n) continue;
      std::vector<std::uint32_t> a(8 * stride + 1);
      for (auto& v : a) v = static_cast<std::uint32_t>(r.below(1 << 20));
      a[0] = 0x1FFFFFFFu;  // counts that need 32 bits once summed
      std::vector<std::uint32_t> sums(n, 0);
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < 8; ++k) sums[i] += a[k * stride + i];
      std::vector<std::uint32_t> got(n + 4, 0xABCDu), want(n + 4, 0xABCDu);
      here().sum_eight(got.data(), a.data(), stride, n);
      scalar().sum_eight(want.data(), a.data(), stride, n);
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(want[i], sums[i]) << "scalar sum_eight, n " << n << " i " << i;
      ASSERT_EQ(got, want) << "sum_eight, n " << n << " stride " << stride;  // nothing past n written
      here().add_counts(got.data(), a.data() + stride, n);
      scalar().add_counts(want.data(), a.data() + stride, n);
      for (std::size_t i = 0; i < n; ++i)
        ASSERT_EQ(want[i], sums[i] + a[stride + i]) << "scalar add_counts, n " << n << " i " << i;
      ASSERT_EQ(got, want) << "add_counts, n " << n << " stride " << stride;
    }
  }
}

OCCSEG_INSTANTIATE_ISA_LEVELS(DivideKernels);

}  // namespace
