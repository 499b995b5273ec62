// The default rules' kernels (kernels/rules.hpp) at every level against the scalar ones, and the
// scalar one against rules/voxel_rules.hpp. They take voxel states (0, 1, 2) and bit rows only, no
// values: the edge inputs are the row lengths (0, 1, the 32-voxel steps' tails and overlapping last
// step, the 64-voxel words), all-set and empty bit rows, touching bits past the row's end, and
// seeds at both ends of a row.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "isa_levels.hpp"
#include "kernels/kernels.hpp"
#include "random_maps.hpp"
#include "rules/voxel_rules.hpp"

using namespace occseg;
using occseg::testing_isa::for_each_isa;

namespace {

std::vector<std::size_t> lengths() {
  std::vector<std::size_t> n;
  for (std::size_t i = 0; i <= 70; ++i) n.push_back(i);
  for (std::size_t i : {95u, 96u, 97u, 127u, 128u, 129u, 200u}) n.push_back(i);
  return n;
}

// A bit row of n voxels (`past`: bits past n set too), each set with probability `density`.
std::vector<std::uint64_t> bits(test::Rng& r, std::size_t n, double density, bool past = false) {
  std::vector<std::uint64_t> w((n + 63) / 64 + 1, 0);  // (a word more: rows are read up to their end only)
  for (std::size_t x = 0; x < 64 * w.size(); ++x)
    if ((x < n || past) && r.uniform() < density) w[x / 64] |= std::uint64_t(1) << (x % 64);
  return w;
}

const detail::word_t* words(const std::vector<std::uint64_t>& v) {
  return reinterpret_cast<const detail::word_t*>(v.data());
}

bool bit(const std::vector<std::uint64_t>& v, std::size_t x) { return (v[x / 64] >> (x % 64)) & 1u; }

}  // namespace

TEST(KernelsRules, RulesRowAtEveryLevelIsTheScalarOne) {
  test::Rng r(11);
  std::size_t seeds_seen = 0;
  const int levels = for_each_isa([&](kernels::Isa) {
    const kernels::RulesKernels& k = kernels::active().rules;
    const kernels::RulesKernels& s = kernels::table(kernels::Isa::scalar).rules;
    for (std::size_t n : lengths())
      for (double density : {0.0, 0.02, 0.3, 0.7, 1.0}) {  // (0, 0.02: words of known voxels only)
        // own states: unknown (u), occupied (o) never both
        auto u = bits(r, n, density), o = bits(r, n, 0.5);
        for (std::size_t i = 0; i < u.size(); ++i) o[i] &= ~u[i];
        const auto reg = bits(r, n, density < 1.0 ? 0.3 : 1.0), t = bits(r, n, density, /*past=*/true);
        std::vector<std::uint8_t> st(n);
        for (auto& v : st) v = static_cast<std::uint8_t>(r.below(3));
        auto want = st, plain = st;
        const std::size_t first = static_cast<std::size_t>(r.below(1000)) * 64 + 5;
        std::vector<std::size_t> seeds{7}, want_seeds{7}, plain_seeds{7};  // (appended to)
        // The result's bit rows, over words holding garbage: every word of the row is written.
        const std::size_t W = (n + 63) / 64;
        std::vector<std::uint64_t> f(W + 1, ~0ull), un(W + 1, 0x5555555555555555ull), oc(W + 1, ~0ull);
        const auto out = [](std::vector<std::uint64_t>& v) { return reinterpret_cast<detail::word_t*>(v.data()); };
        k.rules_row(st.data(), words(u), words(o), words(reg), words(t), n, first, seeds, out(f), out(un), out(oc));
        s.rules_row(want.data(), words(u), words(o), words(reg), words(t), n, first, want_seeds, nullptr, nullptr,
                    nullptr);
        k.rules_row(plain.data(), words(u), words(o), words(reg), words(t), n, first, plain_seeds, nullptr, nullptr,
                    nullptr);
        ASSERT_EQ(st, want) << n << " density " << density;
        ASSERT_EQ(seeds, want_seeds) << n << " density " << density;
        ASSERT_EQ(plain, want) << n << " density " << density;
        ASSERT_EQ(plain_seeds, want_seeds) << n << " density " << density;
        for (std::size_t x = 0; x < 64 * W; ++x) {
          const bool in = x < n;
          ASSERT_EQ(bit(f, x), in && st[x] == rules::kFree) << n << " voxel " << x;
          ASSERT_EQ(bit(un, x), in && st[x] == rules::kUnknown) << n << " voxel " << x;
          ASSERT_EQ(bit(oc, x), in && st[x] == rules::kOccupied) << n << " voxel " << x;
        }
        ASSERT_EQ(f[W], ~0ull);  // (nothing past the row's words)
        seeds_seen += seeds.size() - 1;
      }
  });
  EXPECT_GE(levels, 2);
  EXPECT_GT(seeds_seen, 1000u);
}

// The scalar kernel is voxel_rule() and gap_seed() voxel by voxel (every combination of state,
// own state, region and touching bit, at every position of a row of 130).
TEST(KernelsRules, ScalarRulesRowIsTheVoxelRules) {
  const std::size_t n = 130;
  const kernels::RulesKernels& s = kernels::table(kernels::Isa::scalar).rules;
  for (int combo = 0; combo < 3 * 3 * 2 * 2; ++combo) {
    const auto state = static_cast<std::uint8_t>(combo % 3), own = static_cast<std::uint8_t>(combo / 3 % 3);
    const bool region = (combo / 9) % 2, touches = (combo / 18) % 2;
    std::vector<std::uint64_t> u(3, 0), o(3, 0), reg(3, 0), t(3, 0);
    for (std::size_t x = 0; x < n; ++x) {
      if (own == rules::kUnknown) u[x / 64] |= std::uint64_t(1) << (x % 64);
      if (own == rules::kOccupied) o[x / 64] |= std::uint64_t(1) << (x % 64);
      if (region) reg[x / 64] |= std::uint64_t(1) << (x % 64);
      if (touches) t[x / 64] |= std::uint64_t(1) << (x % 64);
    }
    std::vector<std::uint8_t> st(n, state);
    std::vector<std::size_t> seeds;
    s.rules_row(st.data(), words(u), words(o), words(reg), words(t), n, 0, seeds, nullptr, nullptr, nullptr);
    const std::uint8_t want = rules::voxel_rule(state, own, region, touches);
    EXPECT_EQ(st, std::vector<std::uint8_t>(n, want)) << combo;
    EXPECT_EQ(seeds.size(), rules::gap_seed(own, region, touches, want) ? n : 0u) << combo;
  }
}

TEST(KernelsRules, UnpackHalf) {
  test::Rng r(12);
  for_each_isa([&](kernels::Isa) {
    const kernels::RulesKernels& k = kernels::active().rules;
    for (std::size_t n : lengths())
      for (double density : {0.0, 0.5, 1.0}) {
        const auto b = bits(r, n, density);
        std::vector<std::uint8_t> own(n);
        for (auto& v : own) v = static_cast<std::uint8_t>(r.uniform() < density ? 1 : r.below(3));
        std::vector<std::uint8_t> out(n, 0xEE);
        k.unpack_half(words(b), own.data(), n, out.data());
        for (std::size_t x = 0; x < n; ++x) ASSERT_EQ(out[x], bit(b, x) && own[x] == 1 ? 1 : 0) << n << " voxel " << x;
      }
  });
}
