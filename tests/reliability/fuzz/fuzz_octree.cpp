// OctoMap .bt/.ot reader (structure walk, OctoMap's readers, painting leaves into a grid). The
// box is 16 x 16 x 16 tree voxels around the origin, so a tiny file naming far-apart leaves
// cannot ask for a huge grid (legal, OCCSEG_ENOMEM in the normal build, but not a finding).
#include <cmath>
#include <string>

#include "fuzz_common.hpp"
#include "occseg/octomap_file.hpp"
#include "octree_header.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The resolution the reader will use: the header as liboctomap reads it (a line-by-line guess
  // would miss a one-line header and size the box in the wrong unit).
  const occseg::octree_detail::RawHeader h =
      occseg::octree_detail::parse_raw_header(std::string(reinterpret_cast<const char*>(data), size));
  const double res = h.complete && h.res > 0 && std::isfinite(h.res) ? h.res : 1;  // else refused anyway
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
