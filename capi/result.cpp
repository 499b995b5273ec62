// occseg_segment and the occseg_result_* accessors.
#include <cstddef>
#include <algorithm>
#include <cstring>
#include <memory>

#include "internal.hpp"

using occseg::Error;
using occseg::Status;
using occseg::capi::guard;
using occseg::capi::require;

namespace {

// Throws Error(out_of_range) unless `count` elements hold one value per voxel.
void check_capacity(const occseg_result* r, std::size_t count) {
  const std::size_t n = r->result.labels.size();
  if (count < n)
    throw Error(Status::out_of_range, "count " + std::to_string(count) + " is smaller than the " +
                                          std::to_string(n) + " voxels of the result");
}

// Throws Error(out_of_range) "index I is out of range (the result has N <what>)".
[[noreturn]] void out_of_result(std::size_t index, std::size_t count, const char* what) {
  throw Error(Status::out_of_range, "index " + std::to_string(index) + " is out of range (the result has " +
                                        std::to_string(count) + " " + what + ")");
}

// The fields of `info` after struct_size, from a segment.
void fill_info(const occseg::Segment& s, occseg_segment_info& info) {
  info.id = s.id;
  info.state = static_cast<occseg_state>(s.state);
  info.voxels = s.voxels;
  info.mop = s.mop;
  for (int k = 0; k < 3; ++k) {
    info.bbox_min[k] = s.bbox_min[k];
    info.bbox_max[k] = s.bbox_max[k];
    info.centroid[k] = s.centroid[k];
  }
  // Appended after version 1 (OCCSEG_SEGMENT_INFO_SIZE_V1): filled only for callers whose struct has it.
  if (info.struct_size >= offsetof(occseg_segment_info, kind) + sizeof info.kind)
    info.kind = static_cast<occseg_kind>(s.kind);
}

// The start of every occseg_result_*_view: `out` and `count` cleared first (a failed call
// leaves no stale view behind), then the three pointers checked.
template <class T>
void start_view(const occseg_result* result, const T** out, std::size_t* count) {
  if (out) *out = nullptr;
  if (count) *count = 0;
  require(result, "result");
  require(out, "out");
  require(count, "count");
}

// The body of occseg_segment and occseg_context_segment (context: NULL for none).
void run_segment(occseg_result** out, occseg::Context* context, const occseg_map* map, const occseg_params* params) {
  require(out, "out");
  *out = nullptr;
  require(map, "map");
  occseg::Params p = params ? params->params : occseg::Params::defaults();
  if (params && params->progress) {
    const occseg_progress_fn fn = params->progress;
    void* const user = params->progress_user;
    p.progress = [fn, user](const char* stage, double fraction) { return fn(stage, fraction, user) == 0; };
  }
  auto r = std::make_unique<occseg_result>();
  occseg::capi::with_values(map, [&](const occseg::Grid& grid) {
    r->result = context ? occseg::segment(*context, grid, p) : occseg::segment(grid, p);
  }, p.threads);
  r->preset = occseg::preset_name(p.preset);
  r->voxel_size = map->grid.voxel_size;
  r->origin = map->grid.origin;
  r->nrrd_space = map->nrrd_space;
  *out = r.release();
}

}  // namespace

extern "C" {

int occseg_segment(occseg_result** out, const occseg_map* map, const occseg_params* params) {
  return guard("occseg_segment", [&] { run_segment(out, nullptr, map, params); });
}

int occseg_context_segment(occseg_result** out, occseg_context* context, const occseg_map* map,
                           const occseg_params* params) {
  return guard("occseg_context_segment", [&] {
    if (out) *out = nullptr;
    require(context, "context");
    run_segment(out, &context->context, map, params);
  });
}

void occseg_result_free(occseg_result* result) { delete result; }

int occseg_result_dims(const occseg_result* result, size_t dims[3]) {
  return guard("occseg_result_dims", [&] {
    require(result, "result");
    require(dims, "dims");
    dims[0] = result->result.dims.nx;
    dims[1] = result->result.dims.ny;
    dims[2] = result->result.dims.nz;
  });
}

uint32_t occseg_result_segment_count(const occseg_result* result) {
  uint32_t n = 0;
  guard("occseg_result_segment_count", [&] {
    require(result, "result");
    n = static_cast<uint32_t>(result->result.segments.size());
  });
  return n;
}

// The old layout is this one cut before `kind`; the kinds' values are the library's.
static_assert(OCCSEG_SEGMENT_INFO_SIZE_V1 == offsetof(occseg_segment_info, kind),
              "occseg_segment_info: fields before 'kind' moved");
static_assert(OCCSEG_KIND_FREE == static_cast<int>(occseg::Kind::free) &&
              OCCSEG_KIND_UNKNOWN == static_cast<int>(occseg::Kind::unknown) &&
              OCCSEG_KIND_STRUCTURE == static_cast<int>(occseg::Kind::structure) &&
              OCCSEG_KIND_OBJECT == static_cast<int>(occseg::Kind::object) &&
              OCCSEG_KIND_CLUTTER == static_cast<int>(occseg::Kind::clutter));

int occseg_result_segment(const occseg_result* result, uint32_t index, occseg_segment_info* out) {
  return guard("occseg_result_segment", [&] {
    require(result, "result");
    require(out, "out");
    // Two layouts: this header's, and the one before `kind` was appended (old callers).
    if (out->struct_size != sizeof(occseg_segment_info) && out->struct_size != OCCSEG_SEGMENT_INFO_SIZE_V1)
      throw Error(Status::invalid_argument, "out->struct_size " + std::to_string(out->struct_size) +
                                                " is not sizeof(occseg_segment_info) = " +
                                                std::to_string(sizeof(occseg_segment_info)) +
                                                " nor the size before 'kind', " +
                                                std::to_string(OCCSEG_SEGMENT_INFO_SIZE_V1));
    const auto& segs = result->result.segments;
    if (index >= segs.size()) out_of_result(index, segs.size(), "segments");
    fill_info(segs[index], *out);
  });
}

int occseg_result_labels(const occseg_result* result, uint32_t* out, size_t count) {
  return guard("occseg_result_labels", [&] {
    require(result, "result");
    require(out, "out");
    check_capacity(result, count);
    std::copy(result->result.labels.begin(), result->result.labels.end(), out);
  });
}

int occseg_result_states(const occseg_result* result, uint8_t* out, size_t count) {
  return guard("occseg_result_states", [&] {
    require(result, "result");
    require(out, "out");
    check_capacity(result, count);
    const auto& labels = result->result.labels;
    const auto& segs = result->result.segments;
    for (std::size_t i = 0; i < labels.size(); ++i) out[i] = static_cast<uint8_t>(segs[labels[i]].state);
  });
}

int occseg_result_labels_view(const occseg_result* result, const uint32_t** out, size_t* count) {
  return guard("occseg_result_labels_view", [&] {
    start_view(result, out, count);
    *out = result->result.labels.data();
    *count = result->result.labels.size();
  });
}

int occseg_result_states_view(const occseg_result* result, const uint8_t** out, size_t* count) {
  return guard("occseg_result_states_view", [&] {
    start_view(result, out, count);
    // Made once (call_once: readers on several threads at once are allowed); a failed
    // allocation leaves it to be tried again by the next call.
    auto* r = const_cast<occseg_result*>(result);
    std::call_once(r->states_once, [r] { r->states = occseg::voxel_states(r->result); });
    *out = r->states.data();
    *count = r->states.size();
  });
}

int occseg_result_segments_view(const occseg_result* result, const occseg_segment_info** out, size_t* count) {
  return guard("occseg_result_segments_view", [&] {
    start_view(result, out, count);
    auto* r = const_cast<occseg_result*>(result);
    std::call_once(r->table_once, [r] {
      std::vector<occseg_segment_info> t(r->result.segments.size());
      for (std::size_t i = 0; i < t.size(); ++i) {
        std::memset(&t[i], 0, sizeof t[i]);  // padding too: the table is compared bytewise
        t[i].struct_size = sizeof(occseg_segment_info);
        fill_info(r->result.segments[i], t[i]);
      }
      r->table = std::move(t);
    });
    *out = r->table.data();
    *count = r->table.size();
  });
}

uint32_t occseg_result_stage_count(const occseg_result* result) {
  uint32_t n = 0;
  guard("occseg_result_stage_count", [&] {
    require(result, "result");
    n = static_cast<uint32_t>(result->result.timings.size());
  });
  return n;
}

int occseg_result_stage(const occseg_result* result, uint32_t index, const char** stage, double* seconds) {
  return guard("occseg_result_stage", [&] {
    require(result, "result");
    const auto& t = result->result.timings;
    if (index >= t.size()) out_of_result(index, t.size(), "stages");
    if (stage) *stage = t[index].stage.c_str();
    if (seconds) *seconds = t[index].seconds;
  });
}

}  // extern "C"
