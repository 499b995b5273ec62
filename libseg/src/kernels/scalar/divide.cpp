// The division's kernels in plain C++: what every other level's kernel must compute.
#include "kernels/divide_levels.hpp"
#include "kernels/generic/divide_loops.hpp"

namespace occseg::kernels::scalar {

void count(const BlockCodes& in, std::size_t bins, std::uint32_t* h) {
  for (std::size_t i = 0; i < bins; ++i) h[i] = 0;
  const Block& b = in.b;
  for (std::uint32_t z = b.lo[2]; z < b.hi[2]; ++z)
    for (std::uint32_t y = b.lo[1]; y < b.hi[1]; ++y)
      generic::count_run<true>(in.codes + in.dims.nx * (y + in.dims.ny * std::size_t(z)), b.lo[0], b.hi[0], h);
}

std::size_t nonzero_values(const std::uint32_t* a, const std::uint32_t* b, std::size_t n, std::uint32_t* out) {
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t v = b ? a[i] + b[i] : a[i];
    if (v != 0) out[m++] = v;
  }
  return m;
}

std::uint64_t total(const std::uint32_t* h, std::size_t n) { return generic::total(h, n); }

void sum_eight(std::uint32_t* h, const std::uint32_t* a, std::size_t stride, std::size_t n) {
  generic::sum_eight(h, a, stride, n);
}

void add_counts(std::uint32_t* h, const std::uint32_t* a, std::size_t n) { generic::add_counts(h, a, n); }

}  // namespace occseg::kernels::scalar
