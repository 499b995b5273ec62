// Google Benchmark suite: every stage and the whole pipeline on 320 x 320 x 128 maps (the paper's
// size), with ns per voxel and voxels per second as counters. Args: scene (0 = sensor scene,
// 1 = noisy worst case), threads.
#include <benchmark/benchmark.h>

#include <atomic>
#include <map>
#include <memory>

#include "occseg/context.hpp"
#include "stages/create.hpp"
#include "rules/departures.hpp"
#include "occseg/parallel.hpp"
#include "stages/refine.hpp"
#include "rules/planes.hpp"
#include "occseg/segment.hpp"
#include "stages/texture.hpp"
#include "scenes.hpp"

using namespace occseg;

namespace {

const Dims kPaper{320, 320, 128};

// Inputs of every stage, computed once per (scene, dims).
struct Inputs {
  Grid grid;
  TextureMap texture;
  std::vector<Block> blocks;
  std::vector<std::uint8_t> created, refined_paper, refined_default;
};

const Inputs& inputs(int kind, Dims d = kPaper) {
  static std::map<std::tuple<int, std::size_t, std::size_t, std::size_t>, std::unique_ptr<Inputs>> cache;
  auto& slot = cache[{kind, d.nx, d.ny, d.nz}];
  if (!slot) {
    slot = std::make_unique<Inputs>();
    Inputs& in = *slot;
    in.grid = kind == 0 ? bench::scene(d) : bench::noisy(d);
    const Params p = Params::defaults();
    in.texture = compute_texture(in.grid, p.contrast_bins, 0);
    in.blocks = divide(in.grid, in.texture, p);
    in.created = create_segments(in.grid, in.blocks, p);
    in.refined_paper = in.created;
    refine_unknown(in.refined_paper, in.grid, p);
    refine_boundaries(in.refined_paper, in.grid, p);
    in.refined_default = in.refined_paper;
    apply_voxel_rules(in.refined_default, in.grid, p);
  }
  return *slot;
}

void counters(benchmark::State& state, std::size_t voxels) {
  const double n = static_cast<double>(voxels);
  state.counters["ns_per_voxel"] =
      benchmark::Counter(n * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["voxels_per_s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(state.range(0) == 0 ? "scene" : "noisy");
}

Params params_for(benchmark::State& state, Preset preset = Preset::default_preset) {
  Params p = preset == Preset::paper ? Params::paper() : Params::defaults();
  p.threads = static_cast<int>(state.range(1));
  return p;
}

void BM_Texture(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  const Params p = params_for(state);
  for (auto _ : state) benchmark::DoNotOptimize(compute_texture(in.grid, p.contrast_bins, p.threads));
  counters(state, in.grid.p.size());
}

void BM_Division(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  const Params p = params_for(state);
  for (auto _ : state) benchmark::DoNotOptimize(divide(in.grid, in.texture, p));
  counters(state, in.grid.p.size());
}

void BM_Creation(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  const Params p = params_for(state);
  for (auto _ : state) benchmark::DoNotOptimize(create_segments(in.grid, in.blocks, p));
  counters(state, in.grid.p.size());
}

void BM_RefineUnknown(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  const Params p = params_for(state);
  std::vector<std::uint8_t> st;
  for (auto _ : state) {
    st = in.created;
    refine_unknown(st, in.grid, p);
  }
  counters(state, in.grid.p.size());
}

void BM_RefineBoundaries(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  const Params p = params_for(state);
  std::vector<std::uint8_t> st;
  for (auto _ : state) {
    st = in.created;
    refine_boundaries(st, in.grid, p);
  }
  counters(state, in.grid.p.size());
}

void BM_VoxelRules(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  const Params p = params_for(state);
  std::vector<std::uint8_t> st;
  for (auto _ : state) {
    st = in.refined_paper;
    apply_voxel_rules(st, in.grid, p);
  }
  counters(state, in.grid.p.size());
}

void BM_Labelling(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  LabelArray labels;
  std::vector<Segment> segments;
  const int threads = static_cast<int>(state.range(1));
  for (auto _ : state) label_components(in.refined_default, in.grid, labels, segments, threads);
  counters(state, in.grid.p.size());
}

// The default preset's support-plane split after labelling (one thread by design).
void BM_SupportPlanes(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  LabelArray labels0, labels;
  std::vector<Segment> segments0, segments;
  label_components(in.refined_default, in.grid, labels0, segments0, 2, true);
  for (auto _ : state) {
    state.PauseTiming();
    labels = labels0;
    segments = segments0;
    state.ResumeTiming();
    split_support_planes(in.grid, labels, segments, Params().support_plane, true);
  }
  state.counters["segments_added"] = static_cast<double>(segments.size() - segments0.size());
  counters(state, in.grid.p.size());
}

void BM_SegmentPaper(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  const Params p = params_for(state, Preset::paper);
  for (auto _ : state) benchmark::DoNotOptimize(segment(in.grid, p));
  counters(state, in.grid.p.size());
}

void BM_SegmentDefault(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  const Params p = params_for(state);
  for (auto _ : state) benchmark::DoNotOptimize(segment(in.grid, p));
  counters(state, in.grid.p.size());
}

// Linearity: the sensor scene at 1/8, 1 and 6.4 times the paper's voxel count (2 threads).
void BM_SegmentDefaultSize(benchmark::State& state) {
  const Dims d{static_cast<std::size_t>(state.range(0)), static_cast<std::size_t>(state.range(0)),
               static_cast<std::size_t>(state.range(1))};
  const Inputs& in = inputs(0, d);
  Params p = Params::defaults();
  p.threads = 2;
  for (auto _ : state) benchmark::DoNotOptimize(segment(in.grid, p));
  const double n = static_cast<double>(in.grid.p.size());
  state.counters["ns_per_voxel"] =
      benchmark::Counter(n * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["voxels_per_s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
}

void stage_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"noisy", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
  for (int kind : {0, 1})
    for (int t : {1, 2}) b->Args({kind, t});
}

}  // namespace

// The cost of one parallel loop of two chunks that do nothing: started on a context's pool (its
// workers spin briefly between loops) or with threads started for the loop (calls without a
// context). A segmentation makes about 20 such loops.
void BM_ParallelForDispatch(benchmark::State& state) {
  std::unique_ptr<Context> ctx;
  if (state.range(0)) ctx = std::make_unique<Context>(2);
  std::atomic<std::size_t> sink{0};
  auto loop = [&] { parallel_for(2, 2, [&](std::size_t b, std::size_t e) { sink += e - b; }); };
  for (auto _ : state) {
    if (ctx) ctx->run(loop);
    else loop();
  }
  benchmark::DoNotOptimize(sink.load());
}

BENCHMARK(BM_ParallelForDispatch)->ArgNames({"context"})->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_Texture)->Apply(stage_args);
BENCHMARK(BM_Division)->Apply(stage_args);
BENCHMARK(BM_Creation)->Apply(stage_args);
BENCHMARK(BM_RefineUnknown)->Apply(stage_args);
BENCHMARK(BM_RefineBoundaries)->Apply(stage_args);
BENCHMARK(BM_VoxelRules)->Apply(stage_args);
BENCHMARK(BM_Labelling)->Apply(stage_args);
BENCHMARK(BM_SupportPlanes)->ArgNames({"noisy"})->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SegmentPaper)->Apply(stage_args);
BENCHMARK(BM_SegmentDefault)->Apply(stage_args);
BENCHMARK(BM_SegmentDefaultSize)->ArgNames({"n", "nz"})->Args({160, 64})->Args({320, 128})->Args({512, 256})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
