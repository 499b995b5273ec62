// The whole pipeline (segment.hpp): the order of the stages, their timings, progress and cancel.
#include "occseg/segment.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "occseg/context.hpp"
#include "stages/create.hpp"
#include "rules/departures.hpp"
#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "rules/objects.hpp"
#include "rules/planes.hpp"
#include "rules/surface_band.hpp"
#include "rules/plane_holes.hpp"
#include "rules/structure.hpp"
#include "stages/refine.hpp"
#include "occseg/registry.hpp"
#include "stages/texture.hpp"
#include "stages/codes.hpp"
#include "kernels/kernels.hpp"
#include "util/huge_pages.hpp"
#include "stages/own_states.hpp"
#include "util/parallel_pool.hpp"
#include "pipeline/map_pass.hpp"
#include "pipeline/label_scratch.hpp"
#include "pipeline/segment_internal.hpp"
#include "pipeline/shared_pools.hpp"

namespace occseg {

namespace {

class Stages {
 public:
  Stages(const Params& p, Result& r) : params_(p), result_(r) {}
  // Reports the stage about to start; throws Error(cancelled) if the callback says stop.
  void begin(const char* name) {
    end();
    report(name, 0.0);
    name_ = name;
    start_ = std::chrono::steady_clock::now();
  }
  void end() {
    if (!name_) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    result_.timings.push_back({name_, s});
    report(name_, 1.0);
    name_ = nullptr;
  }

 private:
  void report(const char* name, double f) {
    if (params_.progress && !params_.progress(name, f))
      throw Error(Status::cancelled, std::string("cancelled by the progress callback at stage '") + name + "'");
  }
  const Params& params_;
  Result& result_;
  const char* name_ = nullptr;
  std::chrono::steady_clock::time_point start_;
};

// check_probabilities(), with the common case (a valid map) tested in parallel vector code; the
// scalar check runs only to name the first problem. values = false leaves the values to the
// texture stage (the built-in operator tests each row while it reads it: one pass over the map
// fewer).
void check_map(const Grid& grid, int threads, bool values, const kernels::Table& k) {
  check_dims(grid.dims);
  bool ok = grid.value_count() == grid.dims.count() && grid.voxel_size > 0 && std::isfinite(grid.voxel_size);
  if (ok && values) {
    const std::size_t chunk = std::size_t(1) << 18, n = grid.value_count();
    const std::size_t chunks = (n + chunk - 1) / chunk;
    std::vector<std::uint8_t> good(chunks, 0);
    parallel_for(chunks, threads, [&](std::size_t c0, std::size_t c1) {
      for (std::size_t c = c0; c < c1; ++c)
        good[c] = k.texture.values_in_range(grid.values() + c * chunk, std::min(chunk, n - c * chunk));
    });
    for (auto g : good) ok = ok && g;
  }
  if (!ok) check_probabilities(grid);
}

}  // namespace

// Hands the pages of freed stage buffers back to the system. glibc raises its mmap threshold after
// the first large free, so later buffers of a few MB come from the heap and stay resident when
// freed; without this the process keeps every stage's buffers and its peak grows to ~8 bytes per
// voxel instead of the ~5 that are alive at any time (docs/performance.md).
void detail::release_freed_memory() {
#if defined(__GLIBC__)
  // Serialised: when glibc's malloc is not the process's allocator (sanitizers, jemalloc or
  // tcmalloc hosts) it is still uninitialised, and two first calls at once race in its lazy
  // setup (a crash found by Concurrency.ProgressIsReportedOnTheCallingThread under ASan).
  static std::mutex trim;
  std::lock_guard<std::mutex> lock(trim);
  malloc_trim(0);
#endif
}

Result segment(const Grid& grid, const Params& params, bool keep_stages) {
  // Without a caller's context, a pool for this call: its 20-odd parallel loops would otherwise
  // each start their threads (measured by bench/bench_pipeline.cpp's BM_ParallelForDispatch). It
  // is leased from the process's idle pools (shared_pools.hpp), so that a one-shot call does not
  // start and join threads either; nothing else is kept between calls (no Workspace, no label
  // array: the call's bit arrays are freed before the labelling's peak, as without a pool).
  params.validate();
  if (!pool_installed() && resolve_threads(params.threads) > 1) {
    detail::PoolLease pool(params.threads);
    Result r;
    pool.context().run([&] { r = segment_into(grid, params, keep_stages, LabelArray()); });
    return r;
  }
  return segment_into(grid, params, keep_stages, LabelArray());
}

Result segment_into(const Grid& input, const Params& requested, bool keep_stages, LabelArray&& labels,
                    Workspace* workspace) {
  requested.validate();
  Params params = requested;  // with texture "auto" resolved for this map
  params.texture = resolved_texture(requested, input.dims);
  // The kernels of this call, chosen once on the calling thread and handed to every stage.
  const kernels::Table& k = kernels::active();
  // The built-in texture operator checks the values itself (compute_texture); plugins get a
  // checked map.
  const TextureOperator* op = find_texture(params.texture);
  // A map read through a converter (Grid::source) is read so by the fused map pass and every
  // stage after it; a plugin's texture operator takes floats, so for it the map is converted whole.
  Grid floats;
  const Grid& grid = input.source && !(op && op->native_into) ? (floats = with_float_values(input, params.threads)) : input;
  check_map(grid, params.threads, !(op && op->native), k);
  Result r;
  r.dims = grid.dims;
  r.voxel_size = grid.voxel_size;
  r.origin = grid.origin;
  // A recycled array large enough is kept (resize_huge below); a smaller one would only be copied
  // into fresh storage.
  if (labels.capacity() < grid.dims.count()) labels = LabelArray();
  r.labels = std::move(labels);
  Stages st(params, r);

  // The label array holds the stages' per-voxel scratch until the labelling writes the labels
  // (LabelScratch, label_scratch.hpp); with a plugin's texture the own states come as bytes and
  // are packed into bits of the workspace.
  const std::size_t n = grid.dims.count();
  detail::check_labels_fit(n);  // before any stage allocates: the labels could not hold the result
  std::vector<Block> blocks;
  float own_lo = 0, own_hi = 0;
  detail::float_bounds(params.free_below, params.occupied_above, own_lo, own_hi);
  std::optional<detail::CellRows> rows;  // the map's rows as the fused map pass read them, for the creation
  Workspace local;
  Workspace& ws = workspace ? *workspace : local;
  // The own states' bits: in the label array's last quarter (nothing allocated, nothing held by a
  // context between calls) when the fused map pass writes them and they fit (not for maps a few
  // voxels wide: a word per row), else in the workspace.
  const std::size_t words = (grid.dims.nx + 63) / 64, bit_words = grid.dims.ny * grid.dims.nz * words;
  detail::OwnBits own{nullptr, nullptr, words};
  detail::word_t *unknown = nullptr, *occupied = nullptr;  // (own's words, writable)
  const auto in_workspace = [&] {
    ws.unknown_bits.resize(bit_words);  // every word is written
    ws.occupied_bits.resize(bit_words);
    unknown = ws.unknown_bits.data();
    occupied = ws.occupied_bits.data();
  };
  bool own_written = false;  // by the fused map pass
  st.begin("texture");
  if (op && op->native_into) {
    resize_huge(r.labels, n);  // not zeroed (LabelArray): every stage writes before it reads
    // Fresh pages faulted in (and zeroed by the system) over the threads, not by whichever
    // stage first touches them; a recycled array's are in already and cost a write per page.
    touch_pages(r.labels.data(), n * sizeof(std::uint32_t), params.threads);
    const detail::LabelScratch scratch(r.labels, n);
    if (detail::word_t* const bits = scratch.own_bits(bit_words)) {
      unknown = bits;
      occupied = bits + bit_words;
    } else {
      in_workspace();
    }
    rows.emplace(grid, nullptr, own_lo, own_hi, unknown, occupied, k.create);
    own_written = true;
    // The texture with the creation's reading of the map fused into its first pass (map_pass.hpp).
    const int codes = detail::fused_map_pass(*op, grid, params, k, scratch.codes(), scratch.texture_scratch(), *rows);
    st.begin("division");
    blocks = detail::divide_codes(grid, scratch.codes(), codes, params, /*faces_only=*/true, k);
  } else {  // a plugin's codes come in their own array: the label array waits for it to go
    TextureMap tex = run_texture(grid, params);
    st.begin("division");
    blocks = divide(grid, tex, params, k);
    tex = TextureMap();
    detail::release_freed_memory();
    resize_huge(r.labels, n);
    in_workspace();
  }
  own.unknown = unknown;
  own.occupied = occupied;
  st.begin("creation");
  const detail::LabelScratch label_scratch(r.labels, n);
  std::uint8_t* const scratch = label_scratch.refinement();
  // The growth's masks go where it keeps them (the label array's first bytes, free once the
  // codes are counted), written by the creation if it can (GrowthRows: fused into its writing of
  // the states, from its cells' states).
  const std::size_t room = label_scratch.refinement_bytes();
  std::vector<std::uint8_t> occupied_rows(grid.dims.ny * grid.dims.nz);
  detail::GrowthRows growth;
  growth.scratch = scratch;
  growth.unknown_bits = own.unknown;
  growth.occupied_rows = occupied_rows.data();
  growth.defer_states = !keep_stages;  // (the created states are kept as they were created)
  const bool prefill = own_written && room >= detail::grow_unknown_scratch_bytes(grid.dims);
  std::uint8_t* const own_bytes = own_written ? nullptr : label_scratch.own_bytes();  // (a plugin's texture)
  UninitVector<std::uint8_t> states = detail::create_segments_and_own_states(
      grid, blocks, params, own_bytes, rows ? &*rows : nullptr, prefill ? &growth : nullptr, k);
  rows.reset();
  if (own_bytes)
    detail::pack_own_bits(own_bytes, grid.dims, params.threads, unknown, occupied, k.create);
  if (keep_stages) {
    r.blocks = blocks;
    r.created_states.assign(states.begin(), states.end());
  }
  st.begin("refinement");
  // The rest of the label array (3 bytes per voxel, before the own states) takes the unknown
  // growth's bit masks, then the rules': allocated apart, they raised the peak by 0.25 byte per
  // voxel.
  detail::refine(states.data(), own, grid.dims, params, scratch, room, &growth, k);
  std::vector<std::uint64_t> band;  // the voxels the surface band made occupied, for rule 7's sizes
  if (params.preset == Preset::default_preset) {
    // The rules leave the states' bits for the band (no second reading of the states): in the
    // scratch's first part, the region mask then the band's masks after them.
    const std::size_t state_bytes = 3 * bit_words * sizeof(std::uint64_t);
    std::vector<std::uint8_t> row_kinds(grid.dims.ny * grid.dims.nz);
    std::vector<std::uint64_t> own_state_bits;
    std::uint64_t* state_storage;
    std::uint8_t* rest = scratch;
    std::size_t rest_bytes = room;
    if (room >= state_bytes) {
      state_storage = reinterpret_cast<std::uint64_t*>(scratch);
      rest = scratch + state_bytes;
      rest_bytes = room - state_bytes;
    } else {
      own_state_bits.resize(3 * bit_words);
      state_storage = own_state_bits.data();
    }
    detail::StateBits bits;
    detail::apply_voxel_rules(states.data(), own, grid.dims, params, rest, rest_bytes, k, &bits, state_storage,
                              row_kinds.data());
    detail::apply_surface_band(states.data(), bits, grid.dims, params, rest, rest_bytes,
                               params.min_object_voxels > 0 ? &band : nullptr);
  }
  if (!workspace) {  // not at the labelling's peak
    local.unknown_bits = std::vector<std::uint64_t>();
    local.occupied_bits = std::vector<std::uint64_t>();
  }
  st.begin("labelling");
  // The states go in: they are freed inside, before the segment statistics.
  detail::label_components(std::move(states), grid, r.labels, r.segments, params.threads,
                           params.occupied_connectivity == 26, ws.run_starts, k);
  // Part of "labelling" for callers: they decide which regions are objects.
  if (params.preset == Preset::default_preset) {
    const std::vector<std::uint64_t> band_voxels =
        surface_band_voxels(band, grid.dims, r.labels.data(), r.segments.size());
    band = std::vector<std::uint64_t>();
    group_objects(grid, r.labels, r.segments, params, &band_voxels);
    // Rule 11 before rule 5: a segment it makes structure (several planes) is not split again at
    // its largest plane alone (which would cut the walls off a floor as objects standing on it).
    // (Nothing is handed back to the system between the steps: what one frees the next reuses,
    // and pages handed back are faulted in and zeroed again by the next call; docs/performance.md,
    // "Memory handed back to the system".)
    std::vector<PlanePiece> pieces;
    split_structure(grid, r.labels, r.segments, params, k, params.plane_holes > 0 ? &pieces : nullptr);
    // Rule 12 on rule 11's pieces, before rule 5 looks at what its planes see.
    fill_plane_holes(grid, r.labels, r.segments, params, pieces);
    if (params.support_plane > 0)
      split_support_planes(grid, r.labels, r.segments, static_cast<std::size_t>(params.support_plane),
                           params.occupied_connectivity == 26, params.threads, k);
  }
  assign_kinds(r.segments, params, grid.dims);
  st.end();
  return r;
}

std::vector<std::uint8_t> voxel_states(const Result& r) {
  std::vector<std::uint8_t> s(r.labels.size());
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<std::uint8_t>(r.segments[r.labels[i]].state);
  return s;
}

}  // namespace occseg
