// NRRD volumes (.nrrd, attached header), read and written without Teem, so ParaView, 3D Slicer
// and ITK open occseg's maps and labels in their place in the world.
//
// Geometry: occseg's Grid::origin is the corner of voxel (0, 0, 0); NRRD's "space origin" is the
// centre of the first sample. Files are written with `space: right-anterior-superior` (so Slicer
// shows world x, y, z as R, A, S without mirroring), diagonal `space directions` of the voxel
// size and `space origin` = origin + voxel_size / 2. Reading takes the numbers as they are.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/uninit_vector.hpp"

namespace occseg {

enum class NrrdType { u8, u16, u32, i32, f32, f64 };
const char* nrrd_type_name(NrrdType t);  // the NRRD spelling: "uint8", ..., "float", "double"

struct NrrdVolume {
  NrrdType type = NrrdType::f32;
  Dims dims;                                // sizes, x fastest (a 2D file has nz = 1)
  std::array<double, 3> spacing{1, 1, 1};   // from space directions or spacings; 1 when absent
  std::array<double, 3> origin{0, 0, 0};    // space origin (centre of the first sample)
  std::vector<unsigned char> data;          // samples in host byte order, x fastest
};

// Reads a .nrrd file with encoding raw or ascii (text/txt), little or big endian, dimension 2 or
// 3, axis-aligned space directions. Throws Error(io) when it cannot be read, Error(format) for a
// malformed or truncated file, Error(unsupported) for gzip/bzip2 encodings, detached data files,
// rotated or flipped axes, or an unsupported type; messages name the file.
NrrdVolume read_nrrd(const std::string& path);

// A map from a volume: float/double probabilities in [0, 1], uint8/uint16 scaled 0..max to
// 0..1. Spacing must be isotropic (the voxel size); the grid origin is the corner of the first
// voxel. Throws Error(format) for integer label types or anisotropic spacing, Error(bad_value)
// for values outside [0, 1] and for a geometry check_geometry refuses (a box out of range).
Grid grid_from_nrrd(const NrrdVolume& v, const std::string& name);

// Writes raw little-endian data with the grid geometry above, atomically. Throws Error(bad_value)
// and writes nothing when read_nrrd + grid_from_nrrd would refuse the geometry (check_geometry
// of the corner and of the corner read back from the written centre).
void write_nrrd(const std::string& path, NrrdType type, const Dims& dims, double voxel_size,
                const std::array<double, 3>& corner_origin, const void* data, std::size_t bytes,
                const std::string& content = "");
// A map as float, and a label volume (uint32, same geometry as `grid`).
void write_grid_nrrd(const std::string& path, const Grid& grid);
void write_labels_nrrd(const std::string& path, const Grid& grid, const LabelArray& labels);

}  // namespace occseg
