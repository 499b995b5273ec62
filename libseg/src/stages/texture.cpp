// Stage 1 of the paper (section 2.2): the LBP/C texture code of every voxel, in two passes over
// the map (the first parks each voxel's contrast step, the second writes the codes once the
// steps' distribution has set the contrast levels).
#include "stages/texture.hpp"

#include <algorithm>
#include <atomic>
#include <string>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "pipeline/map_pass.hpp"
#include "stages/codes.hpp"
#include "util/huge_pages.hpp"
#include "util/thread_scratch.hpp"

namespace occseg {

TextureUnit texture_unit(double centre, const double n[6], unsigned present) {
  // The meaning of the kernels' contrasts (kernels/texture.hpp), which certify their float
  // arithmetic against it or recompute a voxel with it (exact_step).
  TextureUnit u;
  double sum1 = 0, sum0 = 0;
  int n1 = 0, n0 = 0;
  for (int i = 0; i < 6; ++i) {
    if (!(present & (1u << i))) continue;
    if (n[i] >= centre) {
      u.lbp = static_cast<std::uint8_t>(u.lbp | (1u << i));
      sum1 += n[i];
      ++n1;
    } else {
      sum0 += n[i];
      ++n0;
    }
  }
  u.contrast = (n1 && n0) ? sum1 / n1 - sum0 / n0 : 0.0;
  return u;
}

namespace {

using kernels::kRecheckStep;
using kernels::kStepHistograms;
using kernels::kStepStride;

// Offsets of the six neighbours; an absent neighbour (axis of size 1) has offset 0 and is masked
// out by `present`.
struct Stencil {
  std::ptrdiff_t off[6];
  unsigned present;
};

Stencil stencil(const Dims& d) {
  const bool hx = d.nx > 1, hy = d.ny > 1, hz = d.nz > 1;
  const auto sy = static_cast<std::ptrdiff_t>(d.nx), sz = static_cast<std::ptrdiff_t>(d.nx * d.ny);
  Stencil s{{hx ? -1 : 0, hx ? 1 : 0, hy ? -sy : 0, hy ? sy : 0, hz ? -sz : 0, hz ? sz : 0},
            (hx ? 3u : 0u) | (hy ? 12u : 0u) | (hz ? 48u : 0u)};
  return s;
}

// Interior voxels of row (y, z): [x0, x1) along x. Returns false for rows on an outer face.
bool interior_row(const Dims& d, std::size_t y, std::size_t z, std::size_t& x0, std::size_t& x1) {
  const bool fx = d.nx == 1, fy = d.ny == 1, fz = d.nz == 1;
  if (!fz && (z == 0 || z == d.nz - 1)) return false;
  if (!fy && (y == 0 || y == d.ny - 1)) return false;
  x0 = fx ? 0 : 1;
  x1 = fx ? 1 : d.nx - 1;
  return x0 < x1;
}

// The exact parked step of one voxel (texture_unit() in double), for kRecheckStep voxels.
std::uint16_t exact_step(const float* p, const std::ptrdiff_t* off, unsigned present) {
  double nb[6];
  for (int k = 0; k < 6; ++k) nb[k] = p[off[k]];
  const TextureUnit u = texture_unit(p[0], nb, present);
  // A valid map's contrasts lie in [0, 1]; anything else (NaN, infinities: an invalid map, which
  // pass 1 reports once it ends) must not reach fine_step's conversion.
  return u.contrast <= 1 ? ContrastQuantizer::parked_step(u.contrast) : 0;
}

// Asks for [p, p + bytes) in L2: rows a few ahead of the ones being computed.
void prefetch_row(const void* p, std::size_t bytes) {
  for (std::size_t b = 0; b < bytes; b += 64) __builtin_prefetch(static_cast<const char*>(p) + b, 0, 2);
}

void check_contrast_bins(int contrast_bins) {
  if (contrast_bins < 2 || contrast_bins > 64)
    throw Error(Status::invalid_argument, "contrast_bins = " + std::to_string(contrast_bins) +
                                              " is outside [2, 64]");
}

}  // namespace

TextureMap compute_texture(const Grid& grid, int contrast_bins, int threads, const kernels::Table& k) {
  check_contrast_bins(contrast_bins);  // before the code array is allocated
  TextureMap tm;
  tm.bins = contrast_bins;
  resize_huge(tm.codes, grid.dims.count());
  detail::compute_texture_into(grid, contrast_bins, threads, reinterpret_cast<detail::code_t*>(tm.codes.data()),
                               nullptr, nullptr, k);
  return tm;
}

void detail::compute_texture_into(const Grid& grid, int contrast_bins, int threads, code_t* codes,
                                  std::uint8_t* lbp_scratch, const MapRowSink* rows, const kernels::Table& k) {
  check_contrast_bins(contrast_bins);
  if (grid.source && !lbp_scratch) {  // pass 2 would read the map again: as floats of its own
    const Grid copy = with_float_values(grid, threads);
    return compute_texture_into(copy, contrast_bins, threads, codes, nullptr, rows, k);
  }
  const kernels::TextureKernels& tk = k.texture;
  const Dims& d = grid.dims;
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz;
  const Stencil sten = stencil(d);
  const bool full = sten.present == 63;  // all six neighbours: the row kernels for them
  const float* p = grid.values();  // null for a grid read through a source
  const MapSource* const source = grid.source;
  // Pass 1: the parked step of every interior voxel, in the code array, and the distribution of
  // the non-zero contrasts (per-thread histograms summed in thread order: integer counts, so the
  // total is exact whoever counted what). Threads take groups of planes from a shared counter (a
  // fixed share each would leave one waiting for another). A group is 1 to 4 times
  // kMapPassPlanes deep (so that a sink's planes stay on one thread: MapRowSink), at least two
  // groups per thread where the map is deep enough; thinner groups, interleaving the threads
  // more, were slower.
  const std::size_t layers = (nz + kMapPassPlanes - 1) / kMapPassPlanes;
  const int wanted = resolve_threads(threads);
  const std::size_t G = kMapPassPlanes * std::clamp<std::size_t>(layers / (2 * static_cast<std::size_t>(wanted)), 1, 4);
  const std::size_t groups = (nz + G - 1) / G;
  const int t = std::max(1, std::min<int>(wanted, static_cast<int>(groups)));
  std::vector<ThreadScratch<std::uint64_t>> part(t, ThreadScratch<std::uint64_t>(kStepHistograms * kStepStride, 0));
  // The input check rides along, so the map is read once for both, and the codes of a bad map
  // are never used: the pass stops and the first bad voxel is named. Kernels that check values
  // (checks_values) check each row's own values as they load them: a bad value may reach the
  // arithmetic of the rows around it before it is seen, which is defined for any float there.
  // The others' is not (float to int conversions): there plane z + 1 is checked just before
  // plane z's texture reads it (and a group's first planes before it starts).
  std::atomic<bool> bad_values{false};
  const bool by_rows = full && tk.checks_values;
  const std::size_t plane = nx * ny;
  // A grid read through a source: each thread converts the planes it reads into a ring of three
  // (planes z - 1, z and z + 1 while plane z is computed), checked as they are converted, and its
  // rows' neighbours in z are found through offsets between the ring's planes.
  const auto ring_plane = [&](float* ring, std::size_t z) { return ring + plane * (z % 3); };
  // Plane z made ready to be read (converted, for a source), false when it holds a bad value.
  auto plane_ok = [&](float* ring, std::size_t z) {
    if (source) return source->read(plane * z, plane, ring_plane(ring, z));
    return by_rows || tk.values_in_range(p + plane * z, plane);
  };
  std::atomic<std::size_t> next_group{0};
  // Planes [z0, z1) into the histograms h; false when a value outside [0, 1] was seen. A function
  // of its own: GCC compiled it slower inlined into the loop over groups below.
  const auto planes = [&](std::size_t z0, std::size_t z1, std::uint64_t* h, std::uint16_t* list_data,
                          float* ring) __attribute__((noinline)) {
    bool ok = (z0 == 0 || plane_ok(ring, z0 - 1)) && plane_ok(ring, z0);
    for (std::size_t z = z0; ok && z < z1; ++z) {
      if (z + 1 < nz && !(ok = plane_ok(ring, z + 1))) break;
      const float* const pz = source ? ring_plane(ring, z) : p + plane * z;
      std::ptrdiff_t off[6];
      std::copy(sten.off, sten.off + 6, off);
      if (source && (sten.present & 48u) && z > 0 && z + 1 < nz) {  // (faces have no interior rows)
        off[4] = ring_plane(ring, z - 1) - pz;
        off[5] = ring_plane(ring, z + 1) - pz;
      }
      for (std::size_t y = 0; ok && y < ny; ++y) {
        // Plane z + 2 is fetched from memory into L2 while plane z is computed.
        if (!source && z + 2 < nz) prefetch_row(p + nx * (y + ny * (z + 2)), nx * sizeof(float));
        code_t* row = codes + nx * (y + ny * z);
        const float* const prow = pz + nx * y;
        std::size_t x0 = 0, x1 = 0;
        if (!interior_row(d, y, z, x0, x1)) {
          std::fill(row, row + nx, kNoTexture);
          ok = !by_rows || tk.values_in_range(prow, nx);
          if (rows) rows->row(rows->self, y, z, prow);
          continue;
        }
        std::fill(row, row + x0, kNoTexture);
        std::fill(row + x1, row + nx, kNoTexture);
        ok = !by_rows || (tk.values_in_range(prow, x0) && tk.values_in_range(prow + x1, nx - x1));
        const float* prow0 = prow + x0;
        const std::size_t n = x1 - x0;
        // With scratch, the LBP codes now, from the contrast kernel's own comparisons: pass 2
        // then reads 3 bytes per voxel instead of the map's rows again.
        std::uint8_t* lrow = lbp_scratch ? lbp_scratch + nx * (y + ny * z) + x0 : nullptr;
        bool rechecks = true;  // unless the kernel says there are none
        if (full) ok = tk.contrast_row(prow0, off, n, row + x0, lrow, rechecks) && ok;
        else tk.contrast_row_any(prow0, off, n, sten.present, row + x0, lrow);
        if (rechecks && tk.any_recheck(row + x0, n)) {
          for (std::size_t x = x0; x < x1; ++x)
            if (row[x] == kRecheckStep) row[x] = exact_step(prow + x, off, sten.present);
        }
        tk.count_steps(row + x0, n, h, list_data);
        if (rows) rows->row(rows->self, y, z, prow);
      }
    }
    return ok;
  };
  parallel_for(static_cast<std::size_t>(t), t, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      std::uint64_t* h = part[i].data();
      ThreadScratch<std::uint16_t> list(nx + 32);  // count_steps' room
      ThreadScratch<float> ring(source ? 3 * plane : 0);
      for (std::size_t gi; (gi = next_group.fetch_add(1, std::memory_order_relaxed)) < groups;) {
        if (bad_values.load(std::memory_order_relaxed)) break;  // the map is rejected anyway
        const std::size_t z0 = gi * G;
        if (!planes(z0, std::min(nz, z0 + G), h, list.data(), ring.data()))
          bad_values.store(true, std::memory_order_relaxed);
      }
    }
  });
  if (bad_values.load()) check_probabilities(grid);  // throws, naming the first bad voxel
  std::vector<std::uint64_t> fine(ContrastQuantizer::kFine, 0);
  for (auto& h : part)
    for (std::size_t j = 0; j < kStepHistograms; ++j)
      for (int f = 0; f < ContrastQuantizer::kFine; ++f) fine[f] += h[j * kStepStride + f + 1];
  const ContrastQuantizer q(contrast_bins, fine);
  // Pass 2: codes = lbp * bins + level of the parked step, by a few vector compares (rises())
  // for the usual handful of levels, else by the table of levels.
  const std::vector<std::uint16_t> level = q.parked_levels(), rises = q.rises();
  const bool by_compares = rises.size() <= 16;
  const auto bins = static_cast<std::uint16_t>(contrast_bins);
  parallel_for(nz, threads, [&](std::size_t z0, std::size_t z1) {
    ThreadScratch<std::uint8_t> lbp(nx);
    ThreadScratch<std::uint16_t> lvl(nx);
    for (std::size_t z = z0; z < z1; ++z)
      for (std::size_t y = 0; y < ny; ++y) {
        if (lbp_scratch) {  // the LBP codes are there: no map reads
          // The parked steps and LBP codes four rows on: the hardware prefetchers stop at each
          // 4 KB page.
          if (y + 4 < ny) {
            const std::size_t ahead = nx * (y + 4 + ny * z);
            prefetch_row(codes + ahead, nx * sizeof(code_t));
            prefetch_row(lbp_scratch + ahead, nx);
          }
          std::size_t x0 = 0, x1 = 0;
          if (!interior_row(d, y, z, x0, x1)) continue;
          const std::size_t at = nx * (y + ny * z) + x0, n = x1 - x0;
          code_t* const row = codes + at;
          if (by_compares) {
            tk.codes_from_lbp(row, lbp_scratch + at, n, rises.data(), rises.size(), bins);
          } else {
            for (std::size_t x = 0; x < n; ++x) lvl[x] = level[row[x]];
            tk.combine_row(lbp_scratch + at, lvl.data(), n, bins, row);
          }
          continue;
        }
        if (z + 2 < nz) prefetch_row(p + nx * (y + ny * (z + 2)), nx * sizeof(float));
        std::size_t x0 = 0, x1 = 0;
        if (!interior_row(d, y, z, x0, x1)) continue;
        code_t* row = codes + nx * (y + ny * z) + x0;
        const float* prow = p + nx * (y + ny * z) + x0;
        std::size_t n = x1 - x0;
        if (by_compares && full) {  // a prefix of the row from the map in one kernel, where one exists
          const std::size_t done = tk.codes_row(prow, sten.off, n, rises.data(), rises.size(), bins, row);
          row += done, prow += done, n -= done;
        }
        tk.lbp_row(prow, sten.off, n, sten.present, lbp.data());
        if (by_compares) {
          tk.levels_row(row, n, rises.data(), rises.size(), lvl.data());
        } else {
          for (std::size_t x = 0; x < n; ++x) lvl[x] = level[row[x]];
        }
        tk.combine_row(lbp.data(), lvl.data(), n, bins, row);
      }
  });
}

}  // namespace occseg
