// Plugin "pcl_reader": PCL .pcd clouds for occseg_map_read, fused into a probabilistic grid by ray
// casting (liboccseg_pcl), so that C programs read them without linking PCL. Options:
//   voxel_size (default 0.05 m), max_range (m, default unlimited), margin (m),
//   bbox=xmin,ymin,zmin,xmax,ymax,zmax, sensor_origin=x,y,z and sensor_orientation=w,x,y,z (each
//   replaces its half of the file's VIEWPOINT, as the command's --sensor-origin and
//   --sensor-orientation do)
#include "occseg/pcd.hpp"
#include "plugin_options.hpp"

namespace {

using occseg::plugin::Options;

int read_cloud(const occseg_plugin_call* call, const char* path, const char* const* options, occseg_plugin_map_sink* sink) {
  return occseg::plugin::guarded(call, [&] {
    const Options o(path, options, {"voxel_size", "max_range", "margin", "bbox", "sensor_origin", "sensor_orientation"});
    occseg::ScanOptions s;
    s.voxel_size = o.number("voxel_size", s.voxel_size);
    s.model.max_range = o.number("max_range", s.model.max_range);
    s.margin = o.number("margin", s.margin);
    if (o.has("bbox")) {
      const std::vector<double> b = o.numbers("bbox", 6);
      s.bbox = occseg::Box{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
    }
    occseg::plugin::sensor_pose_options(o, s);
    s.threads = static_cast<int>(call->threads);
    occseg::plugin::deliver(call, sink, occseg::read_pcd(path, s));
  });
}

int register_pcl(const occseg_plugin_host* host, occseg_plugin_registrar* r) {
  const occseg_plugin_reader reader = {
      sizeof(occseg_plugin_reader), ".pcd",
      "PCL point cloud, ray-cast from its viewpoint; options voxel_size, max_range, margin, bbox, sensor_origin, "
      "sensor_orientation",
      read_cloud, nullptr};
  return host->register_reader(r, &reader);
}

const occseg_plugin_descriptor kDescriptor = {
    OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, sizeof(occseg_plugin_descriptor), "pcl_reader",
    OCCSEG_PLUGIN_VERSION, "PCL .pcd clouds fused into a grid (liboccseg_pcl)", register_pcl};

}  // namespace

OCCSEG_PLUGIN_EXPORT const occseg_plugin_descriptor* occseg_plugin_entry(void) { return &kDescriptor; }
