// `occseg simulate --scene NAME --out DIR`: simulate the range sensor of the paper's section 4
// over a catalogue scene, fuse the scans into a probabilistic map and write it with its ground
// truth (map.npy, truth_state.npy, truth_objects.npy, scene.json), all four or none (OutputSet):
// a failure or Ctrl-C leaves the old files of DIR as they were.
#include <cstdint>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "options.hpp"
#include "occseg/error.hpp"
#include "occseg/sim/scanner.hpp"
#include "occseg/sim/truth.hpp"
#include "outputs.hpp"
#include "progress.hpp"
#include "sim_io.hpp"

namespace occseg::cli {

namespace {

struct SimulateOptions {
  std::string scene, out_dir, mode = "planar";
  std::uint64_t seed = 1;
  std::vector<std::size_t> dims{320, 320, 128};
  double voxel_size = 0.04, sigma = 0.04, step = 0.5, ring_step = 3.0, max_range = 8.0;
  int threads = 0;
};

int run(const SimulateOptions& o) {
  install_interrupt_handlers();  // Ctrl-C stops the simulation at its next layer
  if (o.dims.size() != 3) throw Error(Status::invalid_argument, "--dims takes three numbers: NX NY NZ");
  const sim::Scene scene = sim::make_scene(o.scene, Dims{o.dims[0], o.dims[1], o.dims[2]}, o.voxel_size);
  sim::ScanConfig c;
  c.mode = scan_mode(o.mode);
  c.seed = o.seed;
  c.range_sigma = o.sigma;
  c.angle_step_deg = o.step;
  c.ring_step_deg = o.ring_step;
  c.max_range = o.max_range;
  c.threads = o.threads;
  c.progress = [](double) { return interrupt_signal() == 0; };
  c.validate();
  OutputSet out(o.out_dir);
  set_activity("simulating scans");
  const Grid map = sim::simulate_map(scene, c);
  set_activity("computing the ground truth");
  const sim::Truth truth = sim::ground_truth(scene, c);
  check_interrupted();
  set_activity("writing the map and the ground truth");
  out.write({"map.npy", "truth_state.npy", "truth_objects.npy", "scene.json"},
            [&](StagedFiles& s) { write_simulation(out.dir(), scene, c, map, truth, &s); });
  set_activity("putting the output files in place");
  out.commit();
  std::size_t seen = 0;
  for (float p : map.p) seen += p != 0.5f;
  std::cout << "scene " << scene.name << " (" << sim::scan_mode_name(c.mode) << ", " << scene.viewpoints.size()
            << " viewpoints, seed " << c.seed << "): " << seen << " of " << map.p.size()
            << " voxels observed, written to " << o.out_dir << "\n";
  return kOk;
}

}  // namespace

Runner add_simulate(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* c = app.add_subcommand("simulate", "Simulate a range sensor over a scene: map and ground truth");
  c->add_option("--scene", o->scene,
                "cone, cube, cylinder (the paper's), close, table, doorway, building (a storey of five rooms and a "
                "corridor; its defaults: --dims 400 300 60 --voxel-size 0.05 --mode rings --max-range 25)")
      ->required()
      ->check(CLI::IsMember(sim::scene_names()));
  c->add_option("--out,-o", o->out_dir, "output directory (created if missing)")->required();
  c->add_option("--seed", o->seed, "seed of the range noise (default 1)")->transform(whole_number(0, UINT64_MAX));
  c->add_option("--mode", o->mode,
                "planar (the paper's stack of planar scans), full3d or rings (a spinning multi-beam lidar)")
      ->check(CLI::IsMember({"planar", "full3d", "rings"}));
  c->add_option("--dims", o->dims, "map size NX NY NZ in voxels (default 320 320 128)")->expected(3)
      ->transform(whole_number(1, std::size_t(1) << 40));
  c->add_option("--voxel-size", o->voxel_size, "voxel edge in metres (default 0.04)")->check(positive_number());
  c->add_option("--sigma", o->sigma, "range noise standard deviation, metres (default 0.04)")
      ->check(nonnegative_number());
  c->add_option("--angle-step", o->step, "degrees between rays (default 0.5)")->check(number_in(0.01, 90.0));
  c->add_option("--ring-step", o->ring_step, "rings mode: degrees between rings (default 3)")
      ->check(number_in(0.01, 90.0));
  c->add_option("--max-range", o->max_range, "metres (default 8)")->check(positive_number());
  c->add_option("--threads", o->threads, "worker threads, 0 = all cores")->transform(whole_number(0, 1024));
  return [c, o]() -> int {
    if (!c->parsed()) return -1;
    apply_scene_defaults(*c, o->scene, o->dims, o->voxel_size, o->mode, o->max_range);
    return run(*o);
  };
}

}  // namespace occseg::cli
