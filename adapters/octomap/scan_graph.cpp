// OctoMap scan graphs (.graph). The binary layout is checked here before octomap::ScanGraph
// reads it, since its reader trusts the counts in the file (a corrupt count means a huge
// allocation or a read past the end).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <istream>
#include <limits>
#include <memory>
#include <string>

#include "occseg/error.hpp"
#include "occseg/file_read.hpp"
#include "occseg/octomap_tree.hpp"

namespace occseg {

namespace {

[[noreturn]] void bad(const std::string& path, const std::string& why) {
  throw Error(Status::format, "'" + path + "' is not a valid OctoMap scan graph: " + why);
}

// Layout (octomap ScanGraph::writeBinary): u32 node count; per node: u32 point count, points as
// (i32 3, 3 x f64), pose as (i32 3, 3 x f64) translation + (i32 4, 4 x f64) quaternion, u32 id;
// then u32 edge count; per edge: u32 first, u32 second, pose, f64 weight.
struct GraphChecker {
  const std::string& b;
  const std::string& path;
  std::size_t pos = 0;

  void need(std::size_t n, const char* what) {
    if (b.size() - pos < n) bad(path, std::string("truncated in ") + what + " at byte " + std::to_string(pos));
  }
  std::uint32_t u32(const char* what) {
    need(4, what);
    std::uint32_t v;
    std::memcpy(&v, b.data() + pos, 4);
    pos += 4;
    return v;
  }
  // OctoMap stores doubles and reads them into floats (Vector3/Quaternion::readBinary): a finite
  // value beyond the float range would be an undefined conversion there, so it is refused; NaN
  // and infinite points stay what they are (holes), poses must be finite.
  void vec(std::uint32_t tag, bool finite, const char* what) {
    if (u32(what) != tag) bad(path, std::string("bad ") + what + " at byte " + std::to_string(pos - 4));
    need(8 * tag, what);
    for (std::uint32_t k = 0; k < tag; ++k) {
      double v;
      std::memcpy(&v, b.data() + pos + 8 * k, 8);
      if (finite && !std::isfinite(v)) bad(path, std::string(what) + " at byte " + std::to_string(pos) + " is not finite");
      if (std::isfinite(v) && std::fabs(v) > double(std::numeric_limits<float>::max()))
        bad(path, std::string(what) + " at byte " + std::to_string(pos) + " is beyond the range of a float");
    }
    pos += 8 * tag;
  }
  void pose() {
    vec(3, true, "pose translation");
    vec(4, true, "pose rotation");
  }
  std::size_t run() {
    const std::uint32_t nodes = u32("node count");
    std::size_t points = 0;
    for (std::uint32_t i = 0; i < nodes; ++i) {
      const std::uint32_t n = u32("point count");
      need(std::size_t(n) * 28, "points");  // before anything is allocated for them
      for (std::uint32_t k = 0; k < n; ++k) vec(3, false, "point");
      points += n;
      pose();
      u32("node id");
    }
    const std::uint32_t edges = u32("edge count");
    need(std::size_t(edges) * 80, "edges");
    for (std::uint32_t i = 0; i < edges; ++i) {
      u32("edge");
      u32("edge");
      pose();
      need(8, "edge weight");
      pos += 8;
    }
    if (pos != b.size()) bad(path, std::to_string(b.size() - pos) + " stray bytes after the last edge");
    if (!nodes) bad(path, "it holds no scan");
    return points;
  }
};

}  // namespace

Grid integrate_scan_graph(const octomap::ScanGraph& graph, const ScanOptions& options) {
  static_assert(sizeof(octomap::point3d) == 3 * sizeof(float), "point3d is three packed floats");
  options.validate();
  auto pose_of = [&](const octomap::ScanNode& n) {
    if (options.sensor_pose) return *options.sensor_pose;
    const octomath::Quaternion& q = n.pose.rot();
    return options.pose_for(
        make_pose({n.pose.trans().x(), n.pose.trans().y(), n.pose.trans().z()}, {q.u(), q.x(), q.y(), q.z()}));
  };
  auto points = [](const octomap::ScanNode& n) -> const float* {
    return n.scan && n.scan->size() ? &(*n.scan)[0](0) : nullptr;
  };
  GridFrame frame;
  if (options.bbox) {
    frame = frame_for_box(*options.bbox, options.voxel_size);
  } else {
    ScanBounds bounds;
    for (const octomap::ScanNode* n : graph)
      bounds.add(pose_of(*n), points(*n), n->scan ? n->scan->size() : 0, 3, options.model.max_range);
    frame = bounds.frame(options.voxel_size, options.margin);
  }
  ScanFusion fusion(frame, options.model);  // precise wherever the grid lies
  std::size_t total = 0, before = 0;
  for (const octomap::ScanNode* n : graph) total += n->scan ? n->scan->size() : 0;
  attach_progress(fusion.fusion(), options, &before, total);
  for (const octomap::ScanNode* n : graph) {
    const std::size_t count = n->scan ? n->scan->size() : 0;
    fusion.insert(pose_of(*n), points(*n), count, 3, options.threads);
    before += count;
  }
  if (!fusion.fusion().rays()) throw Error(Status::bad_value, "no finite point in the scan graph");
  return fusion.grid();
}

Grid read_scan_graph(const std::string& path, const ScanOptions& options) {
  options.validate();
  const std::string bytes = read_file(path);
  GraphChecker{bytes, path}.run();
  // The graph is built from the checked bytes, not the file a second time (which may have
  // changed since), and not by ScanNode::readBinary: liboctomap's Pointcloud::readBinary prints
  // "Reading N points from binary file...done." on stderr, which a library must keep out of its
  // host's streams. The values are converted as liboctomap's readers convert them
  // (Vector3::readBinary and Quaternion::readBinary: each double to float), node by node as
  // ScanGraph::readBinary reads them; the edges are left out, since the fusion uses the scans and
  // their poses only.
  octomap::ScanGraph graph;
  {
    std::size_t pos = 0;
    auto u32 = [&] {
      std::uint32_t v;
      std::memcpy(&v, bytes.data() + pos, 4);
      pos += 4;
      return v;
    };
    auto real = [&] {
      double v;
      std::memcpy(&v, bytes.data() + pos, 8);
      pos += 8;
      return static_cast<float>(v);  // finite values are within the float range (checked)
    };
    const std::uint32_t nodes = u32();
    for (std::uint32_t i = 0; i < nodes; ++i) {
      const std::uint32_t n = u32();
      auto scan = std::make_unique<octomap::Pointcloud>();
      scan->reserve(n);
      for (std::uint32_t k = 0; k < n; ++k) {
        pos += 4;  // the vector's tag, 3 (checked)
        const float x = real(), y = real(), z = real();
        scan->push_back(x, y, z);
      }
      pos += 4;
      const float tx = real(), ty = real(), tz = real();
      pos += 4;
      const float qu = real(), qx = real(), qy = real(), qz = real();
      u32();  // the node id: unused by the fusion (addNode numbers the nodes in file order)
      graph.addNode(scan.get(), octomap::pose6d(octomath::Vector3(tx, ty, tz), octomath::Quaternion(qu, qx, qy, qz)));
      scan.release();  // owned by the graph's node now
    }
    if (graph.size() != nodes) bad(path, "OctoMap could not read the checked scans");
  }
  try {
    return integrate_scan_graph(graph, options);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
}

}  // namespace occseg
