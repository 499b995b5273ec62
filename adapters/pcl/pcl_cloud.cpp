// The one translation unit that instantiates the cloud templates for the common point types,
// plus labelled output clouds.
#include "occseg/pcl_cloud.hpp"

#include <string>

#include "occseg/error.hpp"

namespace occseg {

#define OCCSEG_PCL_INSTANTIATE(T)                                                                       \
  template void insert_cloud<T>(OccupancyFusion&, const pcl::PointCloud<T>&, const Eigen::Isometry3f&, \
                                int);                                                                   \
  template void insert_cloud<T>(OccupancyFusion&, const pcl::PointCloud<T>&, int);                     \
  template Grid integrate_clouds<T>(const std::vector<const pcl::PointCloud<T>*>&, const ScanOptions&); \
  template Grid integrate_cloud<T>(const pcl::PointCloud<T>&, const ScanOptions&);
OCCSEG_PCL_INSTANTIATE(pcl::PointXYZ)
OCCSEG_PCL_INSTANTIATE(pcl::PointXYZI)
OCCSEG_PCL_INSTANTIATE(pcl::PointXYZL)
OCCSEG_PCL_INSTANTIATE(pcl::PointXYZRGB)
OCCSEG_PCL_INSTANTIATE(pcl::PointXYZRGBA)
OCCSEG_PCL_INSTANTIATE(pcl::PointXYZRGBL)
OCCSEG_PCL_INSTANTIATE(pcl::PointNormal)
OCCSEG_PCL_INSTANTIATE(pcl::PointXYZRGBNormal)
OCCSEG_PCL_INSTANTIATE(pcl::PointXYZINormal)
#undef OCCSEG_PCL_INSTANTIATE

namespace {

void check_match(const Grid& grid, const Result& result) {
  if (!(grid.dims == result.dims) || result.labels.size() != grid.dims.count())
    throw Error(Status::invalid_argument, "result (" + std::to_string(result.dims.nx) + "x" +
                                              std::to_string(result.dims.ny) + "x" + std::to_string(result.dims.nz) +
                                              ") was not computed on this grid (" + std::to_string(grid.dims.nx) +
                                              "x" + std::to_string(grid.dims.ny) + "x" +
                                              std::to_string(grid.dims.nz) + ")");
}

// Calls fn(point, id) for every voxel whose segment has a chosen state, in index order.
template <typename Fn>
void for_chosen_voxels(const Grid& grid, const Result& result, StateSet states, Fn&& fn) {
  check_match(grid, result);
  const Dims d = grid.dims;
  const double vs = grid.voxel_size;
  std::size_t i = 0;
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t y = 0; y < d.ny; ++y)
      for (std::size_t x = 0; x < d.nx; ++x, ++i) {
        const std::uint32_t id = result.labels[i];
        if (id >= result.segments.size())
          throw Error(Status::invalid_argument, "label " + std::to_string(id) + " has no segment");
        if (!states.has(result.segments[id].state)) continue;
        pcl::PointXYZL p;
        p.x = static_cast<float>(grid.origin[0] + (x + 0.5) * vs);
        p.y = static_cast<float>(grid.origin[1] + (y + 0.5) * vs);
        p.z = static_cast<float>(grid.origin[2] + (z + 0.5) * vs);
        p.label = id;
        fn(p, id);
      }
}

}  // namespace

pcl::PointCloud<pcl::PointXYZL> labelled_cloud(const Grid& grid, const Result& result, StateSet states) {
  pcl::PointCloud<pcl::PointXYZL> cloud;
  for_chosen_voxels(grid, result, states, [&](const pcl::PointXYZL& p, std::uint32_t) { cloud.push_back(p); });
  return cloud;
}

std::vector<pcl::PointCloud<pcl::PointXYZL>> segment_clouds(const Grid& grid, const Result& result, StateSet states) {
  std::vector<pcl::PointCloud<pcl::PointXYZL>> clouds(result.segments.size());
  for_chosen_voxels(grid, result, states, [&](const pcl::PointXYZL& p, std::uint32_t id) { clouds[id].push_back(p); });
  return clouds;
}

}  // namespace occseg
