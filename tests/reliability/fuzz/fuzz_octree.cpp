// OctoMap .bt/.ot reader (structure walk, OctoMap's readers, painting leaves into a grid). The
// box is 16 x 16 x 16 tree voxels around the origin, so a tiny file naming far-apart leaves
// cannot ask for a huge grid (legal, OCCSEG_ENOMEM in the normal build, but not a finding).
#include <cmath>
#include <sstream>

#include "fuzz_common.hpp"
#include "occseg/octomap_file.hpp"

namespace {

// The smallest 'res' of the header lines (the reader keeps the last; the smallest bounds all).
double header_res(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  std::string line;
  double res = 0;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string key;
    double r;
    if (!(ls >> key)) continue;
    if (key == "data") break;
    if (key == "res" && ls >> r && r > 0 && (res == 0 || r < res)) res = r;
  }
  return res;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  double res = header_res(data, size);
  if (!(res > 0) || !std::isfinite(res)) res = 1;  // the reader rejects the file anyway
  const std::string path = occseg::fuzz::as_file(data, size);
  occseg::OctreeOptions o;
  o.bbox = occseg::Box{{-8 * res, -8 * res, -8 * res}, {8 * res, 8 * res, 8 * res}};
  if (size % 2) {  // odd sizes also exercise coarsening (2 x 2 x 2 tree voxels, mean rule)
    o.voxel_size = 2 * res;
    o.coarsen = occseg::Coarsen::mean;
  }
  try {
    const occseg::Grid g = occseg::read_octree_file(path, o);
    if (g.dims.count() > 17 * 17 * 17) std::abort();
    occseg::check_probabilities(g);
  } catch (const occseg::Error& e) {
    occseg::fuzz::check_error(e);
  }
  return 0;
}
