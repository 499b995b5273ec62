// Shared by the capi/*.cpp files: the structs behind the opaque handles and the one place that
// turns C++ exceptions into status codes, so no exception ever crosses the C ABI.
#pragma once
#include <array>
#include <cstdio>
#include <cstring>
#include <exception>
#include <functional>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "occseg/boxes.hpp"
#include "occseg/context.hpp"
#include "occseg/error.hpp"
#include "occseg/grid.hpp"
#include "occseg/occseg.h"
#include "occseg/params.hpp"
#include "occseg/segment.hpp"

struct occseg_params {
  occseg::Params params;  // params.progress stays empty: the C callback is wired in at segment time
  occseg_progress_fn progress = nullptr;
  void* progress_user = nullptr;
};

struct occseg_map {
  occseg::Grid grid;
  std::string nrrd_space;  // the named space of the .nrrd file it was read from; "" otherwise
  // A map made by occseg_map_view_buffer reads the caller's buffer: `grid` then holds the dims,
  // voxel size and origin, grid.p is empty, and grid.borrowed points at the buffer when it is
  // dense float32 with x fastest (the pipeline reads it as it lies); the pipeline reads other
  // buffers through a converter (capi::with_values), a writer's or a plugin's call through a copy.
  struct View {
    const char* data = nullptr;  // voxel (0, 0, 0)
    int dtype = 0;
    ptrdiff_t strides[3] = {0, 0, 0};  // bytes
    uint32_t flags = 0;                // occseg_import_flags
  };
  bool is_view = false;
  View view;
};

struct occseg_context {
  explicit occseg_context(int threads) : context(threads) {}
  occseg::Context context;
};

struct occseg_result {
  occseg::Result result;
  std::string preset;  // for segments.json
  // The segmented map's frame, for the boxes in metres and segments.json / labels.nrrd.
  double voxel_size = 1;
  std::array<double, 3> origin{0, 0, 0};
  std::string nrrd_space;
  // The oriented boxes, computed on first use (occseg_result_segment_box, occseg_result_write):
  // once, even when several threads read the result at once (a mutex, not std::call_once: an
  // exception such as bad_alloc leaves it simply not computed, to be tried again).
  const std::vector<occseg::OrientedBox>& boxes() const {
    std::lock_guard<std::mutex> lock(boxes_mutex);
    if (!boxes_done) {
      boxes_cache = occseg::oriented_boxes(result, voxel_size, origin);
      boxes_done = true;
    }
    return boxes_cache;
  }
  mutable std::mutex boxes_mutex;
  mutable bool boxes_done = false;
  mutable std::vector<occseg::OrientedBox> boxes_cache;
  // occseg_result_states_view's array, made on its first call (once, whichever thread asks).
  std::once_flag states_once;
  std::vector<uint8_t> states;
  // occseg_result_segments_view's table, made on its first call likewise.
  std::once_flag table_once;
  std::vector<occseg_segment_info> table;
};

namespace occseg::capi {

// The calling thread's last-error text. Fixed storage: setting it never allocates or throws.
void clear_error() noexcept;
// Sets the error to "function: prefix message" and returns `code`.
int fail(const char* function, int code, const char* message, const char* prefix = "") noexcept;

// The value a C caller passed for an enum parameter. C may pass any int there, and reading an
// out-of-range value as the C++ enum type is undefined, so the bytes are read as the integer.
template <class E>
int enum_value(const E& e) noexcept {
  std::underlying_type_t<E> v;
  std::memcpy(&v, &e, sizeof v);
  return static_cast<int>(v);
}

// Throws Error(invalid_argument) "argument 'name' is NULL" when p is NULL.
inline void require(const void* p, const char* name) {
  if (!p) throw Error(Status::invalid_argument, std::string("argument '") + name + "' is NULL");
}

// Throws Error(invalid_argument) with `message`.
[[noreturn]] inline void invalid(const std::string& message) { throw Error(Status::invalid_argument, message); }

// `v` as printf's %.<digits>g writes it: 17 digits round-trip a double; "nan", "inf" as they are.
inline std::string number(double v, int digits = 17) {
  char t[64];
  std::snprintf(t, sizeof t, "%.*g", digits, v);
  return t;
}

// Copies `text` into a caller's buffer, snprintf-like (see occseg_params_get in occseg.h): the
// length always goes to `length` when given; buf NULL with size 0 is a pure length query (which
// then needs `length`); a buffer too small is Error(out_of_range) and is left as it was.
inline void copy_text(const std::string& text, char* buf, std::size_t size, std::size_t* length) {
  if (length) *length = text.size();
  if (!buf && size == 0) {
    require(length, "length");
    return;
  }
  require(buf, "buf");
  if (size < text.size() + 1)
    throw Error(Status::out_of_range, "buffer of " + std::to_string(size) + " bytes is too small for '" + text +
                                          "' (needs " + std::to_string(text.size() + 1) + ")");
  std::memcpy(buf, text.c_str(), text.size() + 1);
}

// Throws Error(out_of_range) "index I is out of range (there are N <what>)".
[[noreturn]] inline void index_out_of_range(std::size_t index, std::size_t count, const char* what) {
  throw Error(Status::out_of_range, "index " + std::to_string(index) + " is out of range (there are " +
                                        std::to_string(count) + " " + what + ")");
}

// Calls fn(grid) with the map's values as a Grid for segment(): the map's own grid, or for a map
// that views a caller's buffer, a grid that borrows the buffer (dense float32 that needs no
// import flag: no copy; the pipeline checks the values as it reads them) or one that reads it
// through a converter (Grid::source: other dtypes and strides, and float32 whose values need a
// flag; the stages convert the runs they read into scratch of their own, with the values and
// checks of occseg_map_from_buffer_flags). Bad values in a borrowed buffer fail with the status
// and text occseg_map_from_buffer_flags gives for the same buffer. (`threads`: unused now that
// nothing is converted whole here.)
void with_values(const occseg_map* map, const std::function<void(const Grid&)>& fn, int threads = 0);
// The map's values in a grid of its own: a copy of the map's grid, or of a viewed buffer
// converted and checked as occseg_map_from_buffer_flags does (throws as it would).
Grid converted(const occseg_map* map, int threads = 0);

// Runs `body`; returns 0 and clears the error on success, or the status of whatever it threw.
template <class Body>
int guard(const char* function, Body&& body) noexcept {
  try {
    body();
    clear_error();
    return 0;
  } catch (const Error& e) {
    return fail(function, static_cast<int>(e.status()), e.what());
  } catch (const std::bad_alloc&) {
    return fail(function, static_cast<int>(Status::no_memory), "out of memory");
  } catch (const std::length_error&) {  // a container asked for more than it can hold
    return fail(function, static_cast<int>(Status::no_memory), "out of memory (size limit)");
  } catch (const std::exception& e) {
    return fail(function, static_cast<int>(Status::internal), e.what(), "internal error: ");
  } catch (...) {
    return fail(function, static_cast<int>(Status::internal), "internal error: unknown exception");
  }
}

// Creates `dir` (not its parents) when missing; true when this call created it. Error(io) when it
// cannot be created or is not a directory (occseg_result_write and occseg_result_write_outputs).
bool make_dir(const std::string& dir);

}  // namespace occseg::capi
