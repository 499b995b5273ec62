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
#include "rules/planes.hpp"
#include "stages/refine.hpp"
#include "occseg/registry.hpp"
#include "stages/texture.hpp"
#include "stages/codes.hpp"
#include "kernels/kernels.hpp"
#include "util/huge_pages.hpp"
#include "stages/own_states.hpp"
#include "util/parallel_pool.hpp"
#include "pipeline/segment_internal.hpp"

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

// Hands the pages of freed stage buffers back to the system. glibc raises its mmap threshold after
// the first large free, so later buffers of a few MB come from the heap and stay resident when
// freed; without this the process keeps every stage's buffers and its peak grows to ~8 bytes per
// voxel instead of the ~5 that are alive at any time (docs/performance.md).
void release_freed_memory() {
#if defined(__GLIBC__)
  // Serialised: when glibc's malloc is not the process's allocator (sanitizers, jemalloc or
  // tcmalloc hosts) it is still uninitialised, and two first calls at once race in its lazy
  // setup (a crash found by Concurrency.ProgressIsReportedOnTheCallingThread under ASan).
  static std::mutex trim;
  std::lock_guard<std::mutex> lock(trim);
  malloc_trim(0);
#endif
}

// check_probabilities(), with the common case (a valid map) tested in parallel vector code; the
// scalar check runs only to name the first problem. values = false leaves the values to the
// texture stage (the built-in operator tests each row while it reads it: one pass over the map
// fewer, 3.7 ms of a 320 x 320 x 128 call on two threads).
void check_map(const Grid& grid, int threads, bool values) {
  check_dims(grid.dims);
  bool ok = grid.p.size() == grid.dims.count() && grid.voxel_size > 0 && std::isfinite(grid.voxel_size);
  if (ok && values) {
    const std::size_t chunk = std::size_t(1) << 18, n = grid.p.size();
    const std::size_t chunks = (n + chunk - 1) / chunk;
    std::vector<std::uint8_t> good(chunks, 0);
    parallel_for(chunks, threads, [&](std::size_t c0, std::size_t c1) {
      for (std::size_t c = c0; c < c1; ++c)
        good[c] = probabilities_in_range(grid.p.data() + c * chunk, std::min(chunk, n - c * chunk));
    });
    for (auto g : good) ok = ok && g;
  }
  if (!ok) check_probabilities(grid);
}

}  // namespace

Result segment(const Grid& grid, const Params& params, bool keep_stages) {
  // Without a caller's context, one pool for this call: its 20-odd parallel loops would otherwise
  // each start their threads (about 40 us per loop, bench/bench_pipeline.cpp's
  // BM_ParallelForDispatch). The call stays self-contained: the pool ends with it.
  // (No Workspace: the call's bit arrays are freed before the labelling's peak, as without a pool.)
  params.validate();
  if (!pool_installed() && resolve_threads(params.threads) > 1) {
    Context pool(params.threads);
    Result r;
    pool.run([&] { r = segment_into(grid, params, keep_stages, LabelArray()); });
    return r;
  }
  return segment_into(grid, params, keep_stages, LabelArray());
}

Result segment_into(const Grid& grid, const Params& requested, bool keep_stages, LabelArray&& labels,
                    Workspace* workspace) {
  requested.validate();
  Params params = requested;  // with texture "auto" resolved for this map
  params.texture = resolved_texture(requested, grid.dims);
  // The kernels of this call, chosen once on the calling thread and handed to every stage.
  const kernels::Table& k = kernels::active();
  (void)k;
  // The built-in texture operator checks the values itself (compute_texture); plugins get a
  // checked map.
  const TextureOperator* op = find_texture(params.texture);
  check_map(grid, params.threads, !(op && op->native));
  Result r;
  r.dims = grid.dims;
  // A recycled array large enough is kept (resize_huge below); a smaller one would only be copied
  // into fresh storage.
  if (labels.capacity() < grid.dims.count()) labels = LabelArray();
  r.labels = std::move(labels);
  Stages st(params, r);

  // The label array holds the stages' per-voxel scratch until the labelling writes the labels:
  // the texture codes (bytes [0, 2n)) through the division, with the texture's LBP codes in
  // [2n, 3n) while it runs; the refinement's bit masks take [0, 3n) once the codes are counted.
  // The voxels' own states are bits (detail::OwnBits, 1/4 byte per voxel) in [3n, 4n) from the
  // texture's first pass through the rules; with a plugin's texture the creation writes them as
  // bytes into [3n, 4n), packed into bits of the workspace. The array is allocated (or recycled)
  // once and paged in once; separate arrays cost more allocations, zero-fills and page-ins
  // (docs/performance.md, "Fourth round"). Peak: the labels and the states (5 bytes per voxel);
  // a recycled array does not add to it.
  const std::size_t n = grid.dims.count();
  detail::check_labels_fit(n);  // before any stage allocates: the labels could not hold the result
  std::vector<Block> blocks;
  float own_lo = 0, own_hi = 0;
  detail::float_bounds(params.free_below, params.occupied_above, own_lo, own_hi);
  std::optional<detail::CellRows> rows;  // the map's rows as the texture read them, for the creation
  Workspace local;
  Workspace& ws = workspace ? *workspace : local;
  // The own states' bits: in the label array's last quarter (nothing allocated, nothing held by a
  // context between calls) when the texture's pass writes them and they fit (not for maps a few
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
  bool own_written = false;  // by the texture's first pass
  st.begin("texture");
  if (op && op->native_into) {
    resize_huge(r.labels, n);  // not zeroed (LabelArray): every stage writes before it reads
    // Fresh pages faulted in (and zeroed by the system) over the threads, not by whichever
    // stage first touches them; a recycled array's are in already and cost a write per page.
    touch_pages(r.labels.data(), n * sizeof(std::uint32_t), params.threads);
    // codes in bytes [0, 2n), the operator's scratch (LBP codes) in [2n, 3n), own states as bits
    std::uint8_t* const bytes = reinterpret_cast<std::uint8_t*>(r.labels.data());
    const std::size_t at = (3 * n + 63) / 64 * 64;  // (the array starts on a page)
    if (at + 2 * bit_words * sizeof(std::uint64_t) <= 4 * n) {
      unknown = reinterpret_cast<detail::word_t*>(bytes + at);
      occupied = unknown + bit_words;
    } else {
      in_workspace();
    }
    rows.emplace(grid, nullptr, own_lo, own_hi, unknown, occupied);
    own_written = true;
    const int codes = op->native_into(grid, params, reinterpret_cast<std::uint16_t*>(bytes), bytes + 2 * n, &*rows);
    st.begin("division");
    blocks = detail::divide_codes(grid, reinterpret_cast<const detail::code_t*>(r.labels.data()), codes, params,
                                  /*faces_only=*/true);
  } else {  // a plugin's codes come in their own array: the label array waits for it to go
    TextureMap tex = run_texture(grid, params);
    st.begin("division");
    blocks = divide(grid, tex, params);
    tex = TextureMap();
    release_freed_memory();
    resize_huge(r.labels, n);
    in_workspace();
  }
  own.unknown = unknown;
  own.occupied = occupied;
  st.begin("creation");
  std::uint8_t* const scratch = reinterpret_cast<std::uint8_t*>(r.labels.data());
  // The growth's masks go where it keeps them (the label array's first bytes, free once the
  // codes are counted), written by the creation if it can (GrowthRows).
  const std::size_t room = 3 * n;
  std::vector<std::uint8_t> occupied_rows(grid.dims.ny * grid.dims.nz);
  detail::GrowthRows growth;
  growth.scratch = scratch;
  growth.unknown_bits = own.unknown;
  growth.occupied_rows = occupied_rows.data();
  growth.defer_states = !keep_stages;  // (the created states are kept as they were created)
  const bool prefill = own_written && room >= detail::grow_unknown_scratch_bytes(grid.dims);
  std::uint8_t* const own_bytes = own_written ? nullptr : scratch + 3 * n;  // (a plugin's texture)
  UninitVector<std::uint8_t> states = detail::create_segments_and_own_states(
      grid, blocks, params, own_bytes, rows ? &*rows : nullptr, prefill ? &growth : nullptr);
  rows.reset();
  if (own_bytes)
    detail::pack_own_bits(own_bytes, grid.dims, params.threads, unknown, occupied);
  if (keep_stages) {
    r.blocks = blocks;
    r.created_states.assign(states.begin(), states.end());
  }
  st.begin("refinement");
  // The rest of the label array (3 bytes per voxel, before the own states) takes the unknown
  // growth's bit masks, then the rules': allocated apart, they raised the peak by 0.25 byte per
  // voxel.
  detail::refine(states.data(), own, grid.dims, params, scratch, room, &growth);
  if (params.preset == Preset::default_preset)
    detail::apply_voxel_rules(states.data(), own, grid.dims, params, scratch, room);
  if (!workspace) {  // not at the labelling's peak
    local.unknown_bits = std::vector<std::uint64_t>();
    local.occupied_bits = std::vector<std::uint64_t>();
  }
  release_freed_memory();
  st.begin("labelling");
  // The states go in: they are freed inside, before the segment statistics.
  detail::label_components(std::move(states), grid, r.labels, r.segments, params.threads,
                           params.occupied_connectivity == 26, ws.run_starts);
  // Part of "labelling" for callers: it decides which connected regions are separate objects.
  if (params.preset == Preset::default_preset && params.support_plane > 0)
    split_support_planes(grid, r.labels, r.segments, static_cast<std::size_t>(params.support_plane),
                         params.occupied_connectivity == 26, params.threads);
  st.end();
  return r;
}

std::vector<std::uint8_t> voxel_states(const Result& r) {
  std::vector<std::uint8_t> s(r.labels.size());
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<std::uint8_t>(r.segments[r.labels[i]].state);
  return s;
}

}  // namespace occseg
