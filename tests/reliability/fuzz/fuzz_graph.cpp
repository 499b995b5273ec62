// OctoMap .graph reader (layout check, ScanGraph::readBinary, fusion), in a fixed grid box.
#include "fuzz_common.hpp"
#include "occseg/octomap_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = occseg::fuzz::as_file(data, size);
  occseg::ScanOptions o;
  o.voxel_size = 0.1;
  o.bbox = occseg::Box{{-2, -2, -2}, {2, 2, 2}};
  o.threads = 1;
  try {
    const occseg::Grid g = occseg::read_scan_graph(path, o);
    if (g.dims.nx != 40 || g.dims.ny != 40 || g.dims.nz != 40) std::abort();
    occseg::check_probabilities(g);
  } catch (const occseg::Error& e) {
    occseg::fuzz::check_error(e);
  }
  return 0;
}
