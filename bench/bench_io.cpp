// Readers against their floor, side by side in one run (docs/performance.md, "Reading and
// writing"; bench/compare prints the ratios):
//   occseg_bench_io bt FILE.bt [REPEATS]   liboctomap's readBinary + a walk over every leaf, and
//                                          occseg's read_octree_file (what `occseg segment` reads
//                                          .bt with), taking turns; best of REPEATS each
//   occseg_bench_io npy FILE.npy [REPEATS] occseg's read_npy_grid (numpy.load is timed by
//                                          bench/compare beside it)
//   occseg_bench_io make-bt MAP.npy VOXEL OUT.bt
//                                          an OcTree of a .npy map (every voxel not 0.5 set to
//                                          its log-odds, pruned), to make a large .bt to read
// Prints one JSON object of seconds.
#include <octomap/OcTree.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "occseg/npy.hpp"
#include "occseg/octomap_file.hpp"

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

int bt(const std::string& path, int repeats) {
  double octomap_best = 1e30, occseg_best = 1e30;
  std::size_t leaves = 0, voxels = 0;
  double sink = 0;
  for (int r = 0; r < repeats; ++r) {
    double t = now();
    {
      octomap::OcTree tree(0.1);
      std::cout.flush();
      if (!tree.readBinary(path)) {
        std::fprintf(stderr, "liboctomap cannot read %s\n", path.c_str());
        return 2;
      }
      leaves = 0;
      for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it, ++leaves) sink += it->getLogOdds();
    }
    octomap_best = std::min(octomap_best, now() - t);
    t = now();
    {
      const occseg::Grid g = occseg::read_octree_file(path);
      voxels = g.p.size();
      sink += g.p[voxels / 2];
    }
    occseg_best = std::min(occseg_best, now() - t);
  }
  std::printf("{\"octomap_read_walk\": %.6f, \"occseg_read\": %.6f, \"leaves\": %zu, \"voxels\": %zu, \"sink\": %g}\n",
              octomap_best, occseg_best, leaves, voxels, sink == 12345.678 ? 1.0 : 0.0);
  return 0;
}

int npy(const std::string& path, int repeats) {
  double best = 1e30;
  std::size_t voxels = 0;
  for (int r = 0; r < repeats; ++r) {
    const double t = now();
    const occseg::Grid g = occseg::read_npy_grid(path, 1.0);
    voxels = g.p.size();
    best = std::min(best, now() - t);
  }
  std::printf("{\"occseg_read\": %.6f, \"voxels\": %zu}\n", best, voxels);
  return 0;
}

int make_bt(const std::string& in, double voxel, const std::string& out) {
  const occseg::Grid g = occseg::read_npy_grid(in, voxel);
  octomap::OcTree tree(voxel);
  for (std::size_t z = 0; z < g.dims.nz; ++z)
    for (std::size_t y = 0; y < g.dims.ny; ++y)
      for (std::size_t x = 0; x < g.dims.nx; ++x) {
        const float p = g.at(x, y, z);
        if (p == 0.5f) continue;
        const octomap::point3d c(float((double(x) + 0.5) * voxel), float((double(y) + 0.5) * voxel),
                                 float((double(z) + 0.5) * voxel));
        tree.setNodeValue(c, octomap::logodds(std::clamp(p, 0.001f, 0.999f)), true);
      }
  tree.toMaxLikelihood();
  tree.prune();
  if (!tree.writeBinary(out)) return 2;
  std::printf("{\"nodes\": %zu}\n", tree.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string cmd = argc > 1 ? argv[1] : "";
  try {
    if (cmd == "bt" && argc >= 3) return bt(argv[2], argc > 3 ? std::atoi(argv[3]) : 5);
    if (cmd == "npy" && argc >= 3) return npy(argv[2], argc > 3 ? std::atoi(argv[3]) : 5);
    if (cmd == "make-bt" && argc == 5) return make_bt(argv[2], std::atof(argv[3]), argv[4]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "occseg_bench_io: %s\n", e.what());
    return 2;
  }
  std::fprintf(stderr, "usage: occseg_bench_io bt FILE.bt [REPEATS] | npy FILE.npy [REPEATS] | make-bt MAP.npy VOXEL OUT.bt\n");
  return 1;
}
