// Random occupancy maps for comparing the fast pipeline against the reference: noisy free space,
// occupied boxes and shells, unknown boxes at exactly 0.5, single-voxel 0.5 gaps (rays missed),
// values quantised like uint8 maps. Deterministic (own generator, same on every platform).
#pragma once
#include <algorithm>
#include <cstdint>

#include "occseg/grid.hpp"

namespace occseg::test {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed * 0x9E3779B97F4A7C15ull + 1) {}
  std::uint64_t next() {  // splitmix64
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  int below(int n) { return static_cast<int>(uniform() * n); }

 private:
  std::uint64_t s_;
};

// `noise` in [0, 1]: amplitude of the per-voxel noise and density of the 0.5 gaps.
inline Grid random_map(Dims d, std::uint64_t seed, double noise) {
  Rng r(seed);
  Grid g(d, 0.15f);
  auto rnd_box = [&](float v, bool shell) {
    const int x0 = r.below(static_cast<int>(d.nx)), y0 = r.below(static_cast<int>(d.ny)),
              z0 = r.below(static_cast<int>(d.nz));
    const int x1 = x0 + 1 + r.below(static_cast<int>(d.nx) / 2 + 1), y1 = y0 + 1 + r.below(static_cast<int>(d.ny) / 2 + 1),
              z1 = z0 + 1 + r.below(static_cast<int>(d.nz) / 2 + 1);
    for (int z = z0; z < z1 && z < static_cast<int>(d.nz); ++z)
      for (int y = y0; y < y1 && y < static_cast<int>(d.ny); ++y)
        for (int x = x0; x < x1 && x < static_cast<int>(d.nx); ++x) {
          const bool edge = x == x0 || x == x1 - 1 || y == y0 || y == y1 - 1 || z == z0 || z == z1 - 1;
          if (!shell || edge) g.at(x, y, z) = v;
        }
  };
  for (int k = 0; k < 4; ++k) rnd_box(0.5f, false);                      // unknown regions
  for (int k = 0; k < 3; ++k) rnd_box(static_cast<float>(0.6 + 0.39 * r.uniform()), k == 0);  // objects
  for (auto& v : g.p) {
    const double u = r.uniform();
    if (u < 0.1 * noise) {
      v = 0.5f;  // a gap between rays
    } else if (u < 0.2 * noise) {
      v = static_cast<float>(r.below(256)) / 255.0f;  // quantised like a uint8 map
    } else if (v != 0.5f) {
      const double n = (r.uniform() - 0.5) * noise * 0.2;
      v = static_cast<float>(std::min(1.0, std::max(0.0, v + n)));
    }
  }
  return g;
}

}  // namespace occseg::test
