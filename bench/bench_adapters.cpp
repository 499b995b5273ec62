// Scan integration speed: occseg's fusion (liboccseg_pcl) against OctoMap's insertPointCloud on
// the same real clouds at the same resolution and sensor model. Each iteration starts from an
// empty map (grid or tree) and inserts the whole cloud. Results: docs/adapters.md.
#include <benchmark/benchmark.h>
#include <octomap/OcTree.h>
#include <octomap/ScanGraph.h>
#include <pcl/io/pcd_io.h>

#include <cstdlib>
#include <string>

#include "kernels/kernels.hpp"
#include "occseg/pcl_cloud.hpp"

namespace {

const std::string kTable = std::string(OCCSEG_SHARED_DATA) + "/table_scene_mug_stereo_textured.pcd";
const std::string kOffice = std::string(OCCSEG_SHARED_DATA) + "/office1.pcd";

struct Scene {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  Eigen::Isometry3f pose;
  octomap::Pointcloud world;  // the same finite points, in the world frame, for OctoMap
  octomap::point3d origin;
  std::size_t rays = 0;
};

const Scene& scene(int which) {
  static Scene scenes[2];
  Scene& s = scenes[which];
  if (s.rays) return s;
  if (pcl::io::loadPCDFile(which ? kOffice : kTable, s.cloud) != 0) std::abort();
  s.pose = occseg::cloud_pose(s.cloud);
  for (const auto& p : s.cloud) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    const Eigen::Vector3f w = s.pose * Eigen::Vector3f(p.x, p.y, p.z);
    s.world.push_back(w.x(), w.y(), w.z());
  }
  const Eigen::Vector3f o = s.pose.translation();
  s.origin = octomap::point3d(o.x(), o.y(), o.z());
  s.rays = s.world.size();
  return s;
}

// Args: scene (0 table, 1 office), voxel size in mm, threads (occseg only). Report the wall-clock
// "Time" column: "CPU" counts the calling thread only, so it understates 2 threads.
void BM_Occseg(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const double vs = state.range(1) / 1000.0;
  occseg::ScanBounds bounds;
  occseg::add_cloud_bounds(bounds, s.cloud, s.pose, -1);
  const occseg::GridFrame frame = bounds.frame(vs, 0);
  for (auto _ : state) {
    occseg::OccupancyFusion fusion(frame);
    occseg::insert_cloud(fusion, s.cloud, s.pose, static_cast<int>(state.range(2)));
    benchmark::DoNotOptimize(fusion.log_odds().data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * s.rays));
  state.counters["voxels"] = static_cast<double>(frame.dims.count());
}

// The same with the kernels capped at SSE2 (what a processor without AVX2 runs), for the ratio.
void BM_OccsegSse2(benchmark::State& state) {
  occseg::kernels::ScopedIsa sse2(occseg::kernels::Isa::sse2);
  BM_Occseg(state);
}

void BM_Octomap(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const double vs = state.range(1) / 1000.0;
  std::size_t nodes = 0;
  for (auto _ : state) {
    octomap::OcTree tree(vs);  // OctoMap's default model: 0.7 / 0.4, clamping 0.12 / 0.97
    tree.insertPointCloud(s.world, s.origin, -1, false, false);
    nodes = tree.size();
    benchmark::DoNotOptimize(nodes);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * s.rays));
  state.counters["nodes"] = static_cast<double>(nodes);
}

}  // namespace

BENCHMARK(BM_Occseg)->ArgNames({"scene", "mm", "threads"})
    ->Args({0, 20, 1})->Args({0, 20, 2})->Args({0, 10, 1})->Args({0, 10, 2})->Args({0, 5, 1})->Args({0, 5, 2})
    ->Args({1, 50, 1})->Args({1, 50, 2})->Args({1, 20, 1})->Args({1, 20, 2})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OccsegSse2)->ArgNames({"scene", "mm", "threads"})
    ->Args({0, 10, 1})->Args({0, 10, 2})->Args({0, 5, 1})->Args({0, 5, 2})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Octomap)->ArgNames({"scene", "mm"})
    ->Args({0, 20})->Args({0, 10})->Args({0, 5})->Args({1, 50})->Args({1, 20})
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
