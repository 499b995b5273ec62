// Portable pseudo-random numbers for the simulator. std::mt19937_64 is fully specified by the
// C++ standard, but std::normal_distribution is not (libstdc++ and libc++ differ), so Gaussian
// draws use our own Box-Muller transform: a given seed gives the same map with any standard
// library, on any thread count.
#pragma once
#include <cstdint>
#include <random>

namespace occseg::sim {

// SplitMix64 finaliser: derives independent stream seeds from (seed, a, b) so that every scan
// gets its own generator and results do not depend on the order scans are computed in.
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0);

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  // Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  // Standard normal N(0, 1) by Box-Muller (one draw per call, two uniforms consumed).
  double gaussian();

 private:
  std::mt19937_64 engine_;
};

}  // namespace occseg::sim
