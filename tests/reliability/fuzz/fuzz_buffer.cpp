// The C ABI end to end: occseg_map_from_buffer_flags and occseg_map_view_buffer on the same
// arbitrary small dims, dtypes, strides (dense, Fortran, flipped, arbitrary and overlapping),
// flags (byte-swapped items too) and values, then occseg_segment with either preset and 1 or 3
// threads. The view must give the copy's answer: the same status when the arguments are refused,
// the copy's status and text from the first call that reads a value the copy refused, else the
// same values and labels. An accepted map must come back voxel for voxel, and a
// result must be a valid labelling: every voxel labelled, counts and states consistent, each
// segment of one state, and the same with a different thread count. Neighbours of one state share
// a label, except that the default preset may keep two occupied segments apart where they touch
// (objects standing on or against each other), but never a clutter segment (rule 7: a speckle
// joins the object it touches).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "../c_calls.h"
#include "occseg/occseg.h"

namespace {

struct Reader {
  const std::uint8_t* p;
  std::size_t n;
  std::uint8_t byte() {
    if (!n) return 0;
    --n;
    return *p++;
  }
};

void require(bool ok) {
  if (!ok) std::abort();
}

// A bit of the import flags that is no occseg_import_flags value (the target sets it on purpose).
constexpr std::uint32_t kNoFlag = 8;

std::size_t item_size(int dtype) {
  return dtype == OCCSEG_F64 ? 8 : dtype == OCCSEG_F32 ? 4 : dtype == OCCSEG_U16 ? 2 : 1;
}

// The probability the library must have stored for one element.
double expected(const std::uint8_t* e, int t, std::uint32_t flags, bool* reject) {
  std::uint8_t swapped[8];
  const std::size_t item = item_size(t);
  if (flags & OCCSEG_IMPORT_BYTE_SWAPPED) {  // (one-byte items have no byte order)
    for (std::size_t k = 0; k < item; ++k) swapped[k] = e[item - 1 - k];
    e = swapped;
  }
  double v;
  switch (t) {
    case OCCSEG_F32: { float f; std::memcpy(&f, e, 4); v = f; break; }
    case OCCSEG_F64: std::memcpy(&v, e, 8); break;
    case OCCSEG_U8: return e[0] / 255.0;
    case OCCSEG_I8_OCCUPANCY: {  // ROS OccupancyGrid: -1 unknown, 0..100 percent, nothing else
      const auto c = static_cast<std::int8_t>(e[0]);
      if (c == -1) return 0.5;
      if (c >= 0 && c <= 100) return c / 100.0;
      *reject = true;
      return 0;
    }
    default: { std::uint16_t u; std::memcpy(&u, e, 2); return u / 65535.0; }
  }
  if (v >= 0 && v <= 1) return v;
  if (std::isnan(v) && (flags & OCCSEG_IMPORT_NAN_UNKNOWN)) return 0.5;
  if (!std::isnan(v) && (flags & OCCSEG_IMPORT_CLAMP)) return v < 0 ? 0.0 : 1.0;
  *reject = true;
  return 0;
}

// An error text without the name of the function that failed ("occseg_map_values: data: ...").
std::string detail(const std::string& e) {
  const std::size_t colon = e.find(": ");
  return colon == std::string::npos ? e : e.substr(colon + 2);
}

int segment(occseg_result** r, const occseg_map* map, int preset, int threads) {
  occseg_params* params = nullptr;
  require(occseg_params_create(&params) == OCCSEG_OK);
  require(occseg_params_set(params, "preset", preset ? "paper" : "default") == OCCSEG_OK);
  require(occseg_params_set_int(params, "threads", threads) == OCCSEG_OK);
  require(occseg_params_set_int(params, "smax", 8) == OCCSEG_OK);  // several blocks even in small maps
  require(occseg_params_set_int(params, "smin", 2) == OCCSEG_OK);
  const int rc = occseg_segment(r, map, params);
  occseg_params_free(params);
  require((rc == OCCSEG_OK) == (*r != nullptr));
  return rc;
}

occseg_result* run(const occseg_map* map, int preset, int threads) {
  occseg_result* r = nullptr;
  require(segment(&r, map, preset, threads) == OCCSEG_OK);
  return r;
}

void check_result(const occseg_result* r, const std::size_t d[3], int preset, std::vector<std::uint32_t>& labels) {
  const std::size_t n = d[0] * d[1] * d[2];
  labels.assign(n, 0);
  std::vector<std::uint8_t> states(n);
  require(occseg_result_labels(r, labels.data(), n) == OCCSEG_OK);
  require(occseg_result_states(r, states.data(), n) == OCCSEG_OK);
  const std::uint32_t count = occseg_result_segment_count(r);
  require(count >= 1 && count <= n);
  std::vector<std::uint64_t> voxels(count, 0);
  for (std::size_t i = 0; i < n; ++i) {
    require(labels[i] < count);
    ++voxels[labels[i]];
  }
  std::vector<occseg_state> seg_state(count);
  std::vector<occseg_kind> seg_kind(count);
  for (std::uint32_t s = 0; s < count; ++s) {
    occseg_segment_info info;
    info.struct_size = sizeof info;
    require(occseg_result_segment(r, s, &info) == OCCSEG_OK);
    require(info.id == s && info.voxels == voxels[s] && info.mop >= 0 && info.mop <= 1);
    seg_state[s] = info.state;
    seg_kind[s] = info.kind;
  }
  // Neighbours share a label exactly when they share a state (but for the default preset's objects).
  for (std::size_t z = 0; z < d[2]; ++z)
    for (std::size_t y = 0; y < d[1]; ++y)
      for (std::size_t x = 0; x < d[0]; ++x) {
        const std::size_t i = x + d[0] * (y + d[1] * z);
        require(states[i] == seg_state[labels[i]]);
        const std::size_t next[3] = {x + 1 < d[0] ? i + 1 : i, y + 1 < d[1] ? i + d[0] : i,
                                     z + 1 < d[2] ? i + d[0] * d[1] : i};
        for (std::size_t j : next) {
          if (j == i) continue;
          const bool apart_objects = preset == 0 && states[i] == OCCSEG_OCCUPIED && states[j] == OCCSEG_OCCUPIED &&
                                     seg_kind[labels[i]] != OCCSEG_KIND_CLUTTER && seg_kind[labels[j]] != OCCSEG_KIND_CLUTTER;
          if (!apart_objects) require((states[i] == states[j]) == (labels[i] == labels[j]));
        }
      }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  // b % 5 picks F32 .. U16, or for 4 either I8_OCCUPANCY or (odd b / 5) an invalid dtype on
  // purpose (an int: see c_calls.c), so the inputs found before I8_OCCUPANCY keep their meaning.
  const int b = in.byte();
  const int dtype = b % 5 < 4 ? b % 5 : ((b / 5) % 2 ? 5 : OCCSEG_I8_OCCUPANCY);
  std::size_t dims[3];
  for (std::size_t& v : dims) v = in.byte() % 13;  // 0 .. 12, zero on purpose
  // fb % 5 picks strict, clamp, NaN-unknown or both; 4 either byte-swapped items with one of
  // those four (even fb / 5) or a bit that is no import flag, on purpose (odd).
  const std::uint8_t fb = in.byte();
  std::uint32_t flags = fb % 5;
  if (flags == 4) flags = (fb / 5) % 2 ? kNoFlag : OCCSEG_IMPORT_BYTE_SWAPPED | (fb / 10) % 4;
  const int mode = in.byte() % 4, preset = in.byte() % 2;
  const std::size_t item = item_size(dtype);
  ptrdiff_t s[3];
  if (mode == 1) {  // Fortran order
    s[2] = item; s[1] = s[2] * dims[2]; s[0] = s[1] * dims[1];
  } else if (mode == 2) {  // C order, every axis flipped
    s[0] = -ptrdiff_t(item); s[1] = s[0] * ptrdiff_t(dims[0]); s[2] = s[1] * ptrdiff_t(dims[1]);
  } else {  // arbitrary, possibly overlapping (mode 3), or dense (mode 0: strides == NULL)
    for (ptrdiff_t& v : s) v = static_cast<std::int8_t>(in.byte());
  }
  // Span of the strided view, so the buffer is large enough whatever the library accepts.
  ptrdiff_t lo = 0, hi = ptrdiff_t(item);
  const std::size_t dense[3] = {item, item * dims[0], item * dims[0] * dims[1]};
  for (int k = 0; k < 3; ++k) {
    const ptrdiff_t step = mode == 0 ? ptrdiff_t(dense[k]) : s[k];
    const ptrdiff_t last = dims[k] ? step * ptrdiff_t(dims[k] - 1) : 0;
    (last < 0 ? lo : hi) += last;
  }
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(hi - lo));
  for (std::size_t i = 0; i < buf.size(); ++i) buf[i] = in.byte();
  const std::uint8_t* origin = buf.data() - lo;

  occseg_map* map = nullptr;
  const int rc = occseg_test_from_buffer(&map, origin, dtype, dims, mode == 0 ? nullptr : s, 0.5, flags);
  const std::string copy_error = rc == OCCSEG_OK ? "" : occseg_last_error();
  occseg_map* view = nullptr;
  const int view_rc = occseg_test_view_buffer(&view, origin, dtype, dims, mode == 0 ? nullptr : s, 0.5, flags);
  require((view_rc == OCCSEG_OK) == (view != nullptr));
  // Which failures are allowed, and that a valid request is not refused.
  const std::size_t n = dims[0] * dims[1] * dims[2];
  if (rc != OCCSEG_OK) {
    require(!map && !copy_error.empty());
    require(rc == OCCSEG_EINVAL || rc == OCCSEG_EDIMS || rc == OCCSEG_EVALUE);
    if (rc == OCCSEG_EDIMS) require(n == 0);
    // Dense, Fortran and flipped views are valid; only arbitrary strides may overlap.
    if (rc == OCCSEG_EINVAL) require(dtype > OCCSEG_I8_OCCUPANCY || (flags & kNoFlag) || mode == 3);
    if (rc == OCCSEG_EVALUE)
      require(((dtype == OCCSEG_F32 || dtype == OCCSEG_F64) && (flags & 3) != 3) || dtype == OCCSEG_I8_OCCUPANCY);
    if (rc != OCCSEG_EVALUE) {  // refused by its arguments: the view is refused alike
      require(view_rc == rc);
      return 0;
    }
    // The values are read by the calls: the first one fails as the copy did, and so does the next.
    require(view_rc == OCCSEG_OK);
    std::vector<float> values(n);
    require(occseg_map_values(view, values.data(), n) == OCCSEG_EVALUE && detail(copy_error) == detail(occseg_last_error()));
    occseg_result* r = nullptr;
    require(segment(&r, view, preset, 1) == OCCSEG_EVALUE && detail(copy_error) == detail(occseg_last_error()));
    occseg_map_free(view);
    return 0;
  }
  require(map && view_rc == OCCSEG_OK && dtype <= OCCSEG_I8_OCCUPANCY && !(flags & kNoFlag) && n > 0);
  // Every voxel as the caller's buffer says.
  std::vector<float> values(n);
  require(occseg_map_values(map, values.data(), n) == OCCSEG_OK);
  const ptrdiff_t* st = mode == 0 ? nullptr : s;
  for (std::size_t z = 0; z < dims[2]; ++z)
    for (std::size_t y = 0; y < dims[1]; ++y)
      for (std::size_t x = 0; x < dims[0]; ++x) {
        const ptrdiff_t off = st ? ptrdiff_t(x) * st[0] + ptrdiff_t(y) * st[1] + ptrdiff_t(z) * st[2]
                                 : ptrdiff_t(item * (x + dims[0] * (y + dims[1] * z)));
        bool reject = false;
        const double want = expected(origin + off, dtype, flags, &reject);
        require(!reject);  // the library accepted a value it should have refused
        require(values[x + dims[0] * (y + dims[1] * z)] == static_cast<float>(want));
      }
  std::vector<float> viewed(n);
  require(occseg_map_values(view, viewed.data(), n) == OCCSEG_OK && viewed == values);
  std::vector<std::uint32_t> one, three;
  occseg_result* r1 = run(map, preset, 1);
  check_result(r1, dims, preset, one);
  occseg_result* r3 = run(map, preset, 3);
  check_result(r3, dims, preset, three);
  require(one == three);  // results never depend on the thread count
  occseg_result* rv = run(view, preset, 1);
  const std::uint32_t* view_labels = nullptr;
  std::size_t view_count = 0;
  require(occseg_result_labels_view(rv, &view_labels, &view_count) == OCCSEG_OK && view_count == n);
  require(std::equal(one.begin(), one.end(), view_labels));  // a view segments as its copy does
  occseg_result_free(rv);
  occseg_map_free(view);
  occseg_result_free(r1);
  occseg_result_free(r3);
  occseg_map_free(map);
  return 0;
}
