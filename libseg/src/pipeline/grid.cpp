// occseg::Grid and the checks of a map's dims and values (grid.hpp).
#include "occseg/grid.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "occseg/error.hpp"
#include "occseg/fill_values.hpp"
#include "occseg/parallel.hpp"
#include "kernels/kernels.hpp"
#include "util/huge_pages.hpp"

namespace occseg {

namespace {
GridSizeCheck g_size_check = nullptr;
}  // namespace

void set_grid_size_check(GridSizeCheck check) { g_size_check = check; }

void check_dims(const Dims& d) {
  if (d.nx == 0 || d.ny == 0 || d.nz == 0)
    throw Error(Status::bad_dims, "dimensions " + std::to_string(d.nx) + " x " +
                                      std::to_string(d.ny) + " x " + std::to_string(d.nz) +
                                      " have a zero");
  const std::size_t lim = kMaxVoxels;
  if (d.nx > lim || d.ny > lim / d.nx || d.nz > lim / (d.nx * d.ny))
    throw Error(Status::bad_dims, "dimensions " + std::to_string(d.nx) + " x " +
                                      std::to_string(d.ny) + " x " + std::to_string(d.nz) +
                                      " exceed the limit of 2^40 voxels");
  if (g_size_check) g_size_check(d);
}

Grid::Grid(Dims d, float fill, double vs) : dims(d), voxel_size(vs) {
  check_dims(d);
  p.assign(d.count(), fill);
}

void resize_for_fill(std::vector<float>& v, std::size_t n, int threads) {
  std::vector<float>().swap(v);
  v.reserve(n);
  const std::size_t bytes = n * sizeof(float);
  advise_huge_pages(v.data(), bytes);
  // Threads only where they pay for their start, at most 8 (clearing pages is bounded by memory
  // bandwidth, not by cores). The storage is written before its floats exist: trivial type.
  const int t = bytes >= (std::size_t(8) << 20) ? std::min(resolve_threads(threads), 8) : 1;
  if (t > 1) touch_pages(v.data(), bytes, t);
  v.resize(n);
}

bool probabilities_in_range(const float* p, std::size_t n) { return kernels::active().texture.values_in_range(p, n); }

float Grid::source_value(std::size_t i) const {
  float v;
  if (!source->read(i, 1, &v)) source->fail();
  return v;
}

Grid with_float_values(const Grid& g, int threads) {
  if (!g.source) return g;
  Grid copy;
  copy.dims = g.dims;
  copy.voxel_size = g.voxel_size;
  copy.origin = g.origin;
  resize_for_fill(copy.p, g.dims.count(), 0);
  const std::size_t rows = g.dims.ny * g.dims.nz, nx = g.dims.nx;
  std::atomic<bool> bad{false};
  parallel_for(rows, threads, [&](std::size_t r0, std::size_t r1) {
    if (!g.source->read(r0 * nx, (r1 - r0) * nx, copy.p.data() + r0 * nx)) bad.store(true);
  });
  if (bad.load()) g.source->fail();
  return copy;
}

void check_probabilities(const Grid& g) {
  check_dims(g.dims);
  if (g.value_count() != g.dims.count())
    throw Error(Status::invalid_argument, "grid holds " + std::to_string(g.value_count()) +
                                              " values for " + std::to_string(g.dims.count()) +
                                              " voxels");
  if (!(g.voxel_size > 0) || !std::isfinite(g.voxel_size))
    throw Error(Status::bad_value, "voxel size " + std::to_string(g.voxel_size) +
                                       " is not a positive finite number");
  if (g.source) {  // row by row, in order: the first row the source refuses holds the first bad voxel
    std::vector<float> row(g.dims.nx);
    for (std::size_t r = 0; r < g.dims.ny * g.dims.nz; ++r)
      if (!g.source->read(r * g.dims.nx, g.dims.nx, row.data())) g.source->fail();
    return;
  }
  const float* const p = g.values();
  // The vectorised check first; the loop below only looks for the first bad voxel to name it.
  if (probabilities_in_range(p, g.value_count())) return;
  for (std::size_t i = 0; i < g.value_count(); ++i) {
    const float v = p[i];
    if (!(v >= 0.0f && v <= 1.0f)) {  // also catches NaN
      const std::size_t x = i % g.dims.nx, y = (i / g.dims.nx) % g.dims.ny,
                        z = i / (g.dims.nx * g.dims.ny);
      const char* what = std::isnan(v) ? "is NaN" : (std::isinf(v) ? "is infinite" : "is outside [0, 1]");
      throw Error(Status::bad_value, "probability at voxel (" + std::to_string(x) + ", " +
                                         std::to_string(y) + ", " + std::to_string(z) + ") = " +
                                         std::to_string(v) + " " + what);
    }
  }
}

}  // namespace occseg
