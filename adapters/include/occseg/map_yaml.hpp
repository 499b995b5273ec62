// 2D robot maps as ROS keeps them: nav_msgs/OccupancyGrid cells (int8: -1 unknown, 0..100
// percent) and map_server / Nav2 map files (a YAML file naming a PGM image, with the map's
// resolution, origin and thresholds), read as map_server reads them, and a segmentation written
// back as a trinary PGM/YAML pair that map_server (and so a 2D planner) loads.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/file_write.hpp"
#include "occseg/grid.hpp"

namespace occseg {

// The probability of one OccupancyGrid cell: -1 (unknown) is 0.5, 0..100 is v / 100. False for
// any other value. The one conversion of the int8 buffer dtype and of the map_server reader, so
// a map file and the OccupancyGrid map_server publishes from it give the same map.
inline bool occupancy_cell_probability(int v, float& p) {
  if (v == -1) p = 0.5f;
  else if (v >= 0 && v <= 100) p = static_cast<float>(v / 100.0);
  else return false;
  return true;
}

// How map_server turns pixels into cells (its `mode` key).
enum class MapMode { trinary, scale, raw };

// The keys of a map_server YAML file that occseg uses.
struct MapYaml {
  std::string image;       // as written
  std::string image_path;  // relative names resolved against the YAML file's folder, as map_server does
  double resolution = 0;   // metres per cell
  std::array<double, 3> origin{0, 0, 0};  // x, y of the lower-left corner of the lower-left cell; yaw
  bool negate = false;
  double occupied_thresh = 0, free_thresh = 0;
  MapMode mode = MapMode::trinary;
};

// Parses the YAML subset map_server files use: `key: value` lines at the top level, plain or
// quoted scalars, origin as a flow ([x, y, yaw]) or block (- x) sequence, # comments, a leading
// `---`. Keys other than those above are ignored as map_server ignores them. Throws
// Error(format) "'name': line N: ..." for anything outside the subset (nested mappings, flow
// mappings, anchors, tags, block scalars, tabs, duplicate keys), a missing required key (image,
// resolution, origin, negate, occupied_thresh, free_thresh), a bad number, an unknown mode,
// thresholds outside [0, 1] or free_thresh > occupied_thresh (equal ones in scale mode), a
// resolution that is not positive; Error(unsupported) for an origin rotated about z (yaw != 0:
// an occseg grid is axis-aligned).
MapYaml parse_map_yaml(const std::string& text, const std::string& name);

// A PGM image (netpbm P5 binary with maxval up to 65535, 16-bit samples big-endian, or P2 plain
// text), first row at the top of the picture.
struct PgmImage {
  std::size_t width = 0, height = 0;
  unsigned maxval = 0;
  std::vector<std::uint16_t> pixels;  // width * height, row by row from the top
};

// Throws Error(format) naming `name` and the problem: not a PGM (with a hint for PNG and PPM),
// a malformed header, zero or absurd dimensions (more than 2^40 pixels), maxval outside
// 1..65535, a truncated raster, a sample above maxval.
PgmImage parse_pgm(const unsigned char* bytes, std::size_t size, const std::string& name);

// The OccupancyGrid cells map_server makes of the image (nav2_map_server's loadMapFromFile):
// shade = v / maxval, occ = negate ? shade : 1 - shade; trinary: occ > occupied_thresh -> 100,
// occ < free_thresh -> 0, else -1; scale: the same, with rint(100 (occ - free) / (occupied -
// free)) in between; raw: round(255 shade) when in 0..100, else -1. Row 0 of the result is the
// image's bottom row (y grows upwards), x fastest.
std::vector<std::int8_t> map_server_cells(const MapYaml& yaml, const PgmImage& image);

// Reads `path` (.yaml) and its image into a one-layer map (nz = 1): voxel size = resolution,
// origin = (x, y, 0), p of each cell per occupancy_cell_probability. Errors name the YAML file
// (and the image for image problems): Error(io) when either cannot be read, Error(format) or
// Error(unsupported) as above.
Grid read_map_yaml(const std::string& path);

// map_server's pixel values of a trinary map, as its map_saver writes them.
constexpr std::uint8_t kPgmOccupied = 0, kPgmFree = 254, kPgmUnknown = 205;

// Writes per-cell states (occseg::State values, index x + nx * y) of a one-layer map as an 8-bit
// P5 PGM, occupied 0, free 254, unknown 205, top row (largest y) first; atomically. Throws
// Error(invalid_argument) when nz != 1 or the sizes disagree.
void write_state_pgm(const std::string& path, const Dims& dims, const std::vector<std::uint8_t>& states,
                     StagedFiles* into = nullptr);

// Writes the YAML file map_server loads `image` (a name relative to the YAML's folder) with:
// trinary mode, the grid's voxel size and (x, y) origin, yaw 0, negate 0, occupied_thresh 0.65,
// free_thresh 0.196 (map_saver's values: 205 reads back as unknown, 254 as free, 0 as occupied).
void write_map_yaml(const std::string& path, const std::string& image, const Grid& grid,
                    StagedFiles* into = nullptr);

}  // namespace occseg
