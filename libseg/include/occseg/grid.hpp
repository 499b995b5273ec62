// occseg::Grid: a dense probabilistic occupancy map, x varying fastest.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace occseg {

struct Dims {
  std::size_t nx = 0, ny = 0, nz = 0;
  std::size_t count() const { return nx * ny * nz; }
  bool operator==(const Dims& o) const { return nx == o.nx && ny == o.ny && nz == o.nz; }
};

// A map's values kept in storage that is not a float array (the C ABI's view of a caller's buffer
// of another dtype or layout, capi/map.cpp), read through a converter: the stages convert the runs
// of voxels they read, into scratch of their own, instead of the whole map into a float copy.
// read() gives exactly the floats a whole conversion would. Its owner keeps it (and what it
// reads) alive and unchanged while a Grid that points at it is in use.
class MapSource {
 public:
  virtual ~MapSource() = default;
  // Voxels [i, i + n) (index x + nx * (y + ny * z); a run may cross rows) as probabilities into
  // out[0, n). False when one of them converts to no valid probability (out is then unspecified):
  // fail() names the first. Safe to call from several threads at once.
  virtual bool read(std::size_t i, std::size_t n, float* out) const = 0;
  // Throws Error(bad_value) naming the first voxel in x-fastest order that read() refuses, with the
  // text the source's own conversion gives (the C ABI's: that of occseg_map_from_buffer_flags).
  [[noreturn]] virtual void fail() const = 0;
};

// Occupancy probabilities in [0, 1], one float per voxel, index = x + nx * (y + ny * z).
struct Grid {
  Dims dims;
  double voxel_size = 1.0;                   // metres per voxel edge
  std::array<double, 3> origin{0, 0, 0};     // world position of the corner of voxel (0, 0, 0)
  std::vector<float> p;
  // A caller's dense float array of dims.count() probabilities, x fastest, that the grid reads
  // instead of `p` (then empty): set only by a map that borrows its buffer (the C ABI's
  // occseg_map_view_buffer). Its owner keeps it alive and unchanged while the grid is in use.
  // Copying the Grid copies the pointer, not the values.
  const float* borrowed = nullptr;
  // Or a converter the grid reads its values through (then p is empty, borrowed null and values()
  // null): set only by the C ABI's view of a non-float32 or strided buffer. Only the stages of
  // segment() that say so read such a grid (the fused map pass, the creation, the labelling, rules
  // 5 and 11, through value() and MapRows); segment() converts it whole for the others (a
  // plugin's texture operator). Copying the Grid copies the pointer.
  const MapSource* source = nullptr;

  Grid() = default;
  // Allocates nx*ny*nz voxels at `fill`. Throws Error(bad_dims) on zero or overflowing dims.
  Grid(Dims d, float fill = 0.5f, double voxel_size = 1.0);

  std::size_t index(std::size_t x, std::size_t y, std::size_t z) const {
    return x + dims.nx * (y + dims.ny * z);
  }
  // The probabilities as floats, wherever they are (null for a grid read through a source).
  const float* values() const { return borrowed ? borrowed : p.data(); }
  // Number of values the grid holds (for a source: every voxel).
  std::size_t value_count() const { return borrowed || source ? dims.count() : p.size(); }
  // Voxel i's value, from the floats or through the source (whose map the caller has checked:
  // a value the source refuses throws its error).
  float value(std::size_t i) const { return source ? source_value(i) : values()[i]; }
  float at(std::size_t x, std::size_t y, std::size_t z) const { return value(index(x, y, z)); }
  float& at(std::size_t x, std::size_t y, std::size_t z) { return p[index(x, y, z)]; }

 private:
  float source_value(std::size_t i) const;
};

// A grid of the same map holding its values as floats of its own: `g` itself (a copy, sharing a
// borrowed buffer) unless it reads through a source, whose values are then converted whole (the
// first bad one throws as MapSource::fail says).
Grid with_float_values(const Grid& g, int threads = 0);

// Largest voxel count a map may have (2^40): keeps every index and every count exact in
// size_t, uint64 and double, and rejects absurd headers before allocating.
constexpr std::size_t kMaxVoxels = std::size_t(1) << 40;

// Throws Error(bad_dims) naming the problem when a dimension is zero or the product overflows
// or exceeds kMaxVoxels; then calls the size check, if one is set.
void check_dims(const Dims& d);

// A check of a map's size against the memory it will take, called by check_dims after its own
// checks: every reader calls check_dims once it knows the dims and before it allocates the grid,
// so a map too large for the machine can fail there, with the numbers, instead of when memory
// runs out. It throws to refuse (the `occseg` command: Error(no_memory) naming the voxel count,
// the bytes needed and what would fit). None by default; set it before other threads start.
using GridSizeCheck = void (*)(const Dims& dims);
void set_grid_size_check(GridSizeCheck check);

// Throws Error(bad_value) naming the first voxel (x, y, z) whose value is NaN, infinite or
// outside [0, 1] (for a grid read through a source: the first the source refuses).
void check_probabilities(const Grid& g);

// True when all n values are in [0, 1] (NaN is not): the vectorised test that lets callers run
// check_probabilities() (scalar, to name the voxel) only when something is wrong.
bool probabilities_in_range(const float* p, std::size_t n);

}  // namespace occseg
