// .nrrd reader: header fields, raw, gzip (one or several members) and ascii encodings, endianness, geometry.
#include "fuzz_common.hpp"
#include "occseg/nrrd.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = occseg::fuzz::as_file(data, size);
  try {
    const occseg::NrrdVolume v = occseg::read_nrrd(path);
    if (v.data.size() % v.dims.count() != 0) std::abort();
    const occseg::Grid g = occseg::grid_from_nrrd(v, path);
    if (g.p.size() != g.dims.count() || !(g.voxel_size > 0)) std::abort();
  } catch (const occseg::Error& e) {
    occseg::fuzz::check_error(e);
  }
  return 0;
}
