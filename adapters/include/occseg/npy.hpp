// NumPy .npy files (format versions 1.0, 2.0 and 3.0), read and written without NumPy.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/grid.hpp"
#include "occseg/io_progress.hpp"
#include "occseg/uninit_vector.hpp"

namespace occseg {

class StagedFiles;  // occseg/file_write.hpp

struct NpyArray {
  std::string descr;                // numpy dtype string as stored, e.g. "<f4", "|u1", "<u4"
  std::vector<std::size_t> shape;   // as stored, slowest axis first (C order)
  bool fortran_order = false;
  std::vector<unsigned char> data;  // little-endian element bytes, in file order
  bool big_endian = false;          // the file's were big-endian ('>f4'): swapped, descr made '<f4'
  std::size_t element_count() const;
};

// Parses an .npy file. Throws Error(io) if it cannot be read and Error(format) naming the problem
// for a wrong magic, a malformed header, an unsupported dtype (only f4, f8, u1, u2, u4 and i4 are
// read, in either byte order: big-endian data is swapped to little-endian, see NpyArray), an
// element count beyond 2^40 or a file shorter than its header claims.
NpyArray read_npy(const std::string& path);
NpyArray parse_npy(const unsigned char* bytes, std::size_t size, const std::string& name);

// The header of an .npy file held in bytes[0, size) (at least the whole header): the array
// without its data, and the offset where the data starts. The errors of parse_npy, except that
// the data is not looked at.
NpyArray parse_npy_header(const unsigned char* bytes, std::size_t size, const std::string& name,
                          std::size_t& data_offset);

// read_npy + grid_from_npy in one pass over the file: the header is read and checked (file
// size, dims, dtype, geometry) before anything is allocated, then the samples go straight from
// the file into the grid (float32 in C order), through a small piece of scratch per thread that
// is converted into the grid (other dtypes in C order), or into one buffer that is converted
// (Fortran order); every value is checked as it lands in the grid. Same errors as the pair.
// `header` (if given) gets the header's fields; `progress`: the fraction read, reported from the
// calling thread. `threads` (0: all cores, at most 8) read and check disjoint pieces at once.
Grid read_npy_grid(const std::string& path, double voxel_size, NpyArray* header = nullptr,
                   const IoProgress& progress = {}, int threads = 0);

// Writes a C-order array atomically (write_file_atomically), or stages it `into` a set of files
// replaced together.
void write_npy(const std::string& path, const std::string& descr, const std::vector<std::size_t>& shape,
               const void* data, std::size_t bytes, StagedFiles* into = nullptr);

// An occupancy map from an array indexed [z, y, x] (or [y, x] for a 2D map, nz = 1), C or Fortran
// order. f4/f8 values must be probabilities in [0, 1]; u1 and u2 map 0..max to 0..1. Values are
// checked (check_probabilities), and so is the geometry (check_geometry: the voxel size, and the
// extent within reach of the world origin): Error(bad_value) naming `name`.
Grid grid_from_npy(const NpyArray& a, double voxel_size, const std::string& name);

// Writes a map as float32 [z, y, x] and labels as uint32 [z, y, x] (`into`: as write_npy).
void write_grid_npy(const std::string& path, const Grid& g, StagedFiles* into = nullptr);
// Writes a map as [z, y, x] in any dtype the C ABI takes: "<f4", "<f8", "|u1" or "<u2"; integer
// dtypes store round(p * max), which grid_from_npy maps back to within 0.5 / max. Throws
// Error(invalid_argument) for another dtype.
void write_grid_npy_as(const std::string& path, const Grid& g, const std::string& descr);
void write_labels_npy(const std::string& path, const Dims& d, const LabelArray& labels, StagedFiles* into = nullptr);

}  // namespace occseg
