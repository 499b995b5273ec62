// The labelling's kernels in plain C++: the meaning every other level's kernels are tested against.
#include "kernels/label_levels.hpp"

namespace occseg::kernels::scalar {

void label_row_starts(const std::uint8_t* row, std::size_t nx, std::uint8_t* bits, std::size_t i0) {
  for (std::size_t x = 0; x < nx; ++x)
    if (x == 0 || row[x] != row[x - 1])
      bits[(i0 + x) / 8] = static_cast<std::uint8_t>(bits[(i0 + x) / 8] | (1u << ((i0 + x) % 8)));
}

std::size_t label_count_runs(const std::uint8_t* s, std::size_t rows, std::size_t nx, std::size_t every) {
  std::size_t runs = 0;
  for (std::size_t r = 0; r < rows; r += every) {
    const std::uint8_t* row = s + r * nx;
    runs += 1;
    for (std::size_t x = 1; x < nx; ++x) runs += row[x] != row[x - 1];
  }
  return runs;
}

double label_run_sum(const float* v, std::size_t n) {
  double l[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (std::size_t k = 0; k < n; ++k) l[k & 7] += v[k];
  return ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]));
}

}  // namespace occseg::kernels::scalar
