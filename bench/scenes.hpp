// Benchmark inputs: synthetic maps shaped like the paper's 320 x 320 x 128 scenes.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "occseg/grid.hpp"

namespace occseg::bench {

inline std::uint64_t mix(std::uint64_t z) {  // splitmix64 finaliser: a hash per voxel
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// A sensor looking along +y over a floor with a cube, a cylinder and a cone: free space with
// log-odds-like levels and 0.5 gaps between rays, thin occupied shells (quantised values),
// unknown interiors and shadows, unknown beyond the sensor's range.
inline Grid scene(Dims d, std::uint64_t seed = 1) {
  Grid g(d, 0.5f, 0.01);
  const double nx = static_cast<double>(d.nx), ny = static_cast<double>(d.ny), nz = static_cast<double>(d.nz);
  // Solid test at a voxel centre, in map fractions.
  auto inside = [&](double x, double y, double z) {
    const double fx = x / nx, fy = y / ny, fz = z / nz;
    if (fz < 0.06) return true;  // floor
    if (fx > 0.15 && fx < 0.35 && fy > 0.40 && fy < 0.55 && fz < 0.50) return true;  // cube
    const double cx = (fx - 0.62) / 0.09, cy = (fy - 0.45) / 0.09;
    if (cx * cx + cy * cy < 1 && fz < 0.70) return true;  // cylinder
    const double kx = (fx - 0.45) / 0.12, ky = (fy - 0.75) / 0.12, h = fz / 0.8;
    if (h < 1 && kx * kx + ky * ky < (1 - h) * (1 - h)) return true;  // cone
    return false;
  };
  const std::size_t range = static_cast<std::size_t>(0.92 * ny);
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t x = 0; x < d.nx; ++x) {
      // March along y: free until the first surface, a shell of two voxels, then shadow.
      int hit = -1;
      for (std::size_t y = 0; y < d.ny; ++y) {
        const std::size_t i = g.index(x, y, z);
        const std::uint64_t h = mix(i ^ (seed << 40));
        const double u = static_cast<double>(h >> 11) * 0x1.0p-53;
        float v;
        if (y >= range) {
          v = 0.5f;
        } else if (hit < 0 && inside(x + 0.5, y + 0.5, z + 0.5)) {
          hit = static_cast<int>(y);
        }
        if (y >= range) {
        } else if (hit < 0) {
          // free: a few log-odds levels, 4% of voxels never crossed by a ray
          v = u < 0.04 ? 0.5f : (u < 0.7 ? 0.12f : (u < 0.9 ? 0.18f : 0.3f));
        } else if (static_cast<int>(y) - hit < 2) {
          v = u < 0.05 ? 0.5f : static_cast<float>(std::round((0.7 + 0.29 * u) * 255) / 255);
        } else {
          v = 0.5f;  // interior and shadow
        }
        g.p[i] = v;
      }
    }
  return g;
}

// Worst case: every voxel noisy (values all over [0, 1]), so every block splits to Smin and
// every unit has contrast.
inline Grid noisy(Dims d, std::uint64_t seed = 2) {
  Grid g(d, 0.5f, 0.01);
  for (std::size_t i = 0; i < g.p.size(); ++i) {
    const double u = static_cast<double>(mix(i ^ (seed << 40)) >> 11) * 0x1.0p-53;
    const std::size_t x = i % d.nx, z = i / (d.nx * d.ny);
    const double base = (x * 3 < d.nx) ? 0.15 : (z * 2 < d.nz ? 0.5 : 0.85);
    g.p[i] = static_cast<float>(std::clamp(base + (u - 0.5) * 0.3, 0.0, 1.0));
    if (u < 0.05) g.p[i] = 0.5f;
  }
  return g;
}

}  // namespace occseg::bench
