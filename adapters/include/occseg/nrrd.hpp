// NRRD volumes (.nrrd, attached header), read and written without Teem, so ParaView, 3D Slicer
// and ITK open occseg's maps and labels in their place in the world.
//
// Geometry: occseg's Grid::origin is the corner of voxel (0, 0, 0); NRRD's "space origin" is the
// centre of the first sample. Reading takes the numbers as they are, in the file's own space: a
// file in `space: left-posterior-superior` (3D Slicer's and DICOM's) gives a grid in LPS
// coordinates, and NrrdVolume::space says so. Files are written with diagonal `space directions`
// of the voxel size, `space origin` = origin + voxel_size / 2 and the space they are given: the
// space of the input they came from (labels of an LPS volume are written in LPS, so they lie on
// the volume), or `right-anterior-superior` (world x, y, z shown as R, A, S, without mirroring)
// for maps of no named space.
//
// The header is read as teem reads it: field names in any case and in teem's spellings
// ("Data File", "spacedirections"), each field once, the per-axis fields after "dimension" and
// the vectors after "space" or "space dimension"; a line that names no field is an error unless
// it is a "key:=value" pair.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/gzip.hpp"
#include "occseg/io_progress.hpp"
#include "occseg/uninit_vector.hpp"

namespace occseg {

class StagedFiles;  // occseg/file_write.hpp

enum class NrrdType { u8, u16, u32, i32, f32, f64 };
const char* nrrd_type_name(NrrdType t);  // the NRRD spelling: "uint8", ..., "float", "double"

struct NrrdVolume {
  NrrdType type = NrrdType::f32;
  Dims dims;                                // sizes, x fastest (a 2D file has nz = 1)
  std::array<double, 3> spacing{1, 1, 1};   // from space directions or spacings; 1 when absent
  std::array<double, 3> origin{0, 0, 0};    // space origin (centre of the first sample)
  std::string space;                        // teem's name of the file's 3D space ("" when none is named)
  std::vector<unsigned char> data;          // samples in host byte order, x fastest
};

// Reads a .nrrd file with encoding raw, gzip (gz; what 3D Slicer saves by default) or ascii
// (text/txt), little or big endian, dimension 2 or 3, axis-aligned space directions. Throws
// Error(io) when it cannot be read, Error(format) for a malformed or truncated file, gzip data
// that is truncated or corrupt or decompresses to more or fewer bytes than the sizes say (never
// more than those bytes are decompressed), Error(unsupported) for bzip2 or other encodings,
// detached data files, rotated or flipped axes, or an unsupported type; messages name the file.
// `progress`: the fraction of the gzip data inflated.
NrrdVolume read_nrrd(const std::string& path, const IoProgress& progress = {});

// How write_nrrd stores the samples: raw, or gzip-compressed (zlib `level`, 1 fastest; on up to
// `threads` threads, 0 all cores, the file the same for any count; see write_gzip).
struct NrrdWriteOptions {
  bool gzip = false;
  int level = 1;
  int threads = 0;
  IoProgress progress;  // fraction of the samples written
  // Runs of equal words to code without zlib (write_gzip); write_labels_nrrd sets them for its
  // uint32 labels, rows and slices of the grid.
  GzipRuns runs;
};

// A map from a volume: float/double probabilities in [0, 1], uint8/uint16 scaled 0..max to
// 0..1. Spacing must be isotropic (the voxel size); the grid origin is the corner of the first
// voxel. Throws Error(format) for integer label types or anisotropic spacing, Error(bad_value)
// for values outside [0, 1] and for a geometry check_geometry refuses (a box out of range).
Grid grid_from_nrrd(const NrrdVolume& v, const std::string& name);

// The space written when none is given: occseg's world x, y, z as 3D Slicer's R, A, S.
inline const char* const kNrrdDefaultSpace = "right-anterior-superior";

// Writes little-endian data (raw, or gzip per `options`) with the grid geometry above, atomically (write_file_atomically),
// in `space` (a 3D space's name as teem spells it; empty: kNrrdDefaultSpace), or stages it
// `into` a set of files replaced together. Throws Error(invalid_argument) for a name that is no
// 3D NRRD space, and Error(bad_value), writing nothing, when read_nrrd + grid_from_nrrd would
// refuse the geometry (check_geometry of the corner and of the corner read back from the written
// centre).
void write_nrrd(const std::string& path, NrrdType type, const Dims& dims, double voxel_size,
                const std::array<double, 3>& corner_origin, const void* data, std::size_t bytes,
                const std::string& content = "", const std::string& space = "", StagedFiles* into = nullptr,
                const NrrdWriteOptions& options = {});
// A map as float, and a label volume (uint32, same geometry as `grid`), in `space` as above.
void write_grid_nrrd(const std::string& path, const Grid& grid, const std::string& space = "",
                     StagedFiles* into = nullptr, const NrrdWriteOptions& options = {});
void write_labels_nrrd(const std::string& path, const Grid& grid, const LabelArray& labels,
                       const std::string& space = "", StagedFiles* into = nullptr,
                       const NrrdWriteOptions& options = {});

}  // namespace occseg
