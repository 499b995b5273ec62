// Plugin "octomap_reader": OctoMap trees (.bt, .ot) and scan graphs (.graph) for occseg_map_read,
// through liboccseg_octomap, so that C programs read them without linking OctoMap.
//   .bt/.ot options:  voxel_size (a multiple of the tree's resolution; default: the resolution),
//                     coarsen=max|mean, bbox=xmin,ymin,zmin,xmax,ymax,zmax (metres)
//   .graph options:   voxel_size (default 0.05), max_range, margin, bbox, sensor_origin=x,y,z and
//                     sensor_orientation=w,x,y,z (each replaces its half of every node's pose)
#include "occseg/octomap_file.hpp"
#include "plugin_options.hpp"

namespace {

using occseg::plugin::Options;

std::optional<occseg::Box> bbox_of(const Options& o) {
  if (!o.has("bbox")) return std::nullopt;
  const std::vector<double> b = o.numbers("bbox", 6);
  return occseg::Box{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
}

int read_tree(const occseg_plugin_call* call, const char* path, const char* const* options, occseg_plugin_map_sink* sink) {
  return occseg::plugin::guarded(call, [&] {
    const Options o(path, options, {"voxel_size", "coarsen", "bbox"});
    occseg::OctreeOptions t;
    t.voxel_size = o.number("voxel_size", 0.0);
    t.bbox = bbox_of(o);
    const std::string c = o.text("coarsen", "max");
    if (c != "max" && c != "mean") o.fail("option coarsen: '" + c + "' is not max or mean");
    t.coarsen = c == "mean" ? occseg::Coarsen::mean : occseg::Coarsen::max;
    occseg::plugin::deliver(call, sink, occseg::read_octree_file(path, t));
  });
}

int read_graph(const occseg_plugin_call* call, const char* path, const char* const* options, occseg_plugin_map_sink* sink) {
  return occseg::plugin::guarded(call, [&] {
    const Options o(path, options,
                    {"voxel_size", "max_range", "margin", "bbox", "sensor_origin", "sensor_orientation"});
    occseg::ScanOptions s;
    s.voxel_size = o.number("voxel_size", s.voxel_size);
    s.model.max_range = o.number("max_range", s.model.max_range);
    s.margin = o.number("margin", s.margin);
    s.bbox = bbox_of(o);
    occseg::plugin::sensor_pose_options(o, s);
    s.threads = static_cast<int>(call->threads);
    occseg::plugin::deliver(call, sink, occseg::read_scan_graph(path, s));
  });
}

int register_octomap(const occseg_plugin_host* host, occseg_plugin_registrar* r) {
  const occseg_plugin_reader readers[] = {
      {sizeof(occseg_plugin_reader), ".bt", "OctoMap binary tree; options voxel_size, coarsen, bbox", read_tree, nullptr},
      {sizeof(occseg_plugin_reader), ".ot", "OctoMap full tree (log-odds); options voxel_size, coarsen, bbox", read_tree,
       nullptr},
      {sizeof(occseg_plugin_reader), ".graph", "OctoMap scan graph, fused; options voxel_size, max_range, margin, bbox, sensor_origin, sensor_orientation",
       read_graph, nullptr},
  };
  for (const auto& x : readers)
    if (int rc = host->register_reader(r, &x)) return rc;
  return 0;
}

const occseg_plugin_descriptor kDescriptor = {
    OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, sizeof(occseg_plugin_descriptor), "octomap_reader",
    OCCSEG_PLUGIN_VERSION, "OctoMap .bt/.ot trees and .graph scan graphs (liboccseg_octomap)", register_octomap};

}  // namespace

OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor* occseg_plugin_entry(void) { return &kDescriptor; }
