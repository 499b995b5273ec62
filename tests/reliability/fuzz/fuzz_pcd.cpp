// .pcd reader (header check, PCL's reader, fusion). The grid box is fixed, so a file cannot ask
// for a huge grid: that is legal (the normal build reports OCCSEG_ENOMEM) but not a finding.
#include <pcl/console/print.h>

#include "fuzz_common.hpp"
#include "occseg/pcd.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // PCL's complaints are expected
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = occseg::fuzz::as_file(data, size);
  occseg::ScanOptions o;
  o.voxel_size = 0.1;
  o.bbox = occseg::Box{{-2, -2, -1}, {2, 2, 3}};
  o.threads = 1;
  try {
    const occseg::Grid g = occseg::read_pcd(path, o);
    if (g.dims.nx != 40 || g.dims.ny != 40 || g.dims.nz != 40) std::abort();
    occseg::check_probabilities(g);
  } catch (const occseg::Error& e) {
    occseg::fuzz::check_error(e);
  }
  return 0;
}
