// A user's C++ program against the installed liboccseg_octomap (found by find_package(occseg
// COMPONENTS octomap) or pkg-config occseg-octomap): an OctoMap tree to a dense grid, and a
// hand-made segmentation of it back to a ColorOcTree (segments.ot), read back with OctoMap.
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <cstdio>
#include <memory>

#include <occseg/octomap_segments.hpp>
#include <occseg/octomap_tree.hpp>

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "segments.ot";
  octomap::OcTree tree(0.1);
  for (int x = 0; x < 3; ++x) tree.updateNode(octomap::point3d(0.05f + 0.1f * x, 0.05f, 0.05f), true);
  const occseg::Grid g = occseg::grid_from_octree(tree);
  occseg::Result r;
  r.dims = g.dims;
  r.labels.assign(g.dims.count(), 1);
  r.segments.resize(2);
  r.segments[1].id = 1;
  r.segments[1].state = occseg::State::occupied;
  occseg::write_segments_octree(out, g, r);
  std::unique_ptr<octomap::AbstractOcTree> back(octomap::AbstractOcTree::read(out));
  const auto* c = dynamic_cast<const octomap::ColorOcTree*>(back.get());
  if (!c) return 1;
  std::printf("grid %zu x %zu x %zu, segments.ot: %zu leaves of %g m\n", g.dims.nx, g.dims.ny, g.dims.nz,
              c->getNumLeafNodes(), c->getResolution());
  return c->getNumLeafNodes() == 3 ? 0 : 1;
}
