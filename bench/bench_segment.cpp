// Helper of bench/compare: writes the benchmark maps as .npy and times occseg::segment() on a
// map file inside the process (no file I/O in the figures), reporting JSON on stdout.
//   occseg_bench_segment make scene|noisy NX NY NZ out.npy
//   occseg_bench_segment time map.npy PRESET THREADS REPEATS [context|context-fresh]
// With "context" every call goes through one occseg::Context (its threads kept), and each result
// not kept is handed back with Context::recycle, as a program segmenting map after map would;
// "context-fresh" keeps the threads but recycles nothing (every call gets fresh label memory).
// OCCSEG_BENCH_VOXEL_SIZE=METRES: the map's voxel edge (default 1; a .npy holds none), which the
// default preset's rule 11 reads (structure_extent is in metres): the simulated buildings need
// 0.05, as `occseg segment --voxel-size 0.05` gives them.
// OCCSEG_BENCH_ISA=scalar|sse2|avx2|avx512|avx512vbmi caps the kernels of every stage at that
// instruction-set level (kernels/isa.hpp; the fastest the processor has by default), to compare
// them side by side (unset or empty: no cap); a level the processor lacks gives the highest one
// below it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "occseg/context.hpp"
#include "occseg/npy.hpp"
#include "kernels/kernels.hpp"
#include "occseg/segment.hpp"
#include "scenes.hpp"

using namespace occseg;

namespace {

// Linux: a field of /proc/self/status in kB (VmRSS: now, VmHWM: peak since the last reset).
long status_kb(const char* field) {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long v = -1;
  const std::size_t n = std::strlen(field);
  while (std::fgets(line, sizeof line, f))
    if (!std::strncmp(line, field, n)) v = std::atol(line + n);
  std::fclose(f);
  return v;
}

// Resets the peak (VmHWM) to the current resident size.
void reset_peak() {
  if (std::FILE* f = std::fopen("/proc/self/clear_refs", "w")) {
    std::fputs("5", f);
    std::fclose(f);
  }
}

int usage() {
  std::fprintf(stderr,
               "usage: occseg_bench_segment make scene|noisy NX NY NZ out.npy\n"
               "       occseg_bench_segment time map.npy paper|default THREADS REPEATS [context|context-fresh]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc == 7 && std::string(argv[1]) == "make") {
      const Dims d{std::stoul(argv[3]), std::stoul(argv[4]), std::stoul(argv[5])};
      const std::string kind = argv[2];
      if (kind != "scene" && kind != "noisy") return usage();
      write_grid_npy(argv[6], kind == "scene" ? bench::scene(d) : bench::noisy(d));
      return 0;
    }
    const bool timing = (argc == 6 || (argc == 7 && (std::string(argv[6]) == "context" ||
                                                     std::string(argv[6]) == "context-fresh"))) &&
                        std::string(argv[1]) == "time";
    if (timing) {
      double voxel_size = 1.0;
      if (const char* v = std::getenv("OCCSEG_BENCH_VOXEL_SIZE"); v && *v) {
        char* end = nullptr;
        voxel_size = std::strtod(v, &end);
        if (*end || !(voxel_size > 0) || !std::isfinite(voxel_size)) {
          std::fprintf(stderr, "occseg_bench_segment: OCCSEG_BENCH_VOXEL_SIZE=%s is not a positive number\n", v);
          return 2;
        }
      }
      const Grid g = grid_from_npy(read_npy(argv[2]), voxel_size, argv[2]);
      std::optional<kernels::ScopedIsa> isa;  // (on this thread, which runs every call)
      if (const char* level = std::getenv("OCCSEG_BENCH_ISA"); level && *level) {
        const kernels::Isa* found = nullptr;
        for (const kernels::Isa& l : kernels::kIsaLevels)
          if (std::string(level) == kernels::isa_name(l)) found = &l;
        if (!found) {
          std::fprintf(stderr, "occseg_bench_segment: OCCSEG_BENCH_ISA=%s is not one of scalar, sse2, avx2, "
                               "avx512, avx512vbmi\n", level);
          return 2;
        }
        isa.emplace(*found);
      }
      Params p;
      set_param(p, "preset", argv[3]);
      set_param(p, "threads", argv[4]);
      // OCCSEG_BENCH_PARAMS="name=value,name=value": further parameters (e.g. the object rules off,
      // to time them side by side in one run).
      if (const char* extra = std::getenv("OCCSEG_BENCH_PARAMS"); extra && *extra) {
        std::string list = extra;
        for (std::size_t at = 0; at <= list.size();) {
          const std::size_t end = std::min(list.find(',', at), list.size());
          const std::string item = list.substr(at, end - at);
          const std::size_t eq = item.find('=');
          if (eq == std::string::npos) {
            std::fprintf(stderr, "occseg_bench_segment: OCCSEG_BENCH_PARAMS item '%s' is not name=value\n", item.c_str());
            return 2;
          }
          set_param(p, item.substr(0, eq), item.substr(eq + 1));
          at = end + 1;
        }
      }
      const int repeats = std::max(1, std::atoi(argv[5]));
      std::unique_ptr<Context> ctx;
      if (argc == 7) ctx = std::make_unique<Context>(p.threads);
      const bool recycle = argc == 7 && std::string(argv[6]) == "context";
      auto run = [&] { return ctx ? segment(*ctx, g, p) : segment(g, p); };
      // Peak memory beyond the map (the result's labels included) of a first call and of a second
      // one after the first result is freed (or, with a context, recycled: the context then holds
      // its array during the second call); the larger of the two is reported.
      // Both are printed too: memory the allocator kept from the first call (per-thread arenas of
      // the worker threads) can show in the second.
      reset_peak();
      const long rss0 = status_kb("VmRSS:");
      long rss1 = rss0, peak[2] = {rss0, rss0};
      for (int call = 0; call < 2; ++call) {
        {
          Result first = run();
          if (recycle) ctx->recycle(std::move(first));
        }
        peak[call] = status_kb("VmHWM:");
        rss1 = std::max(rss1, peak[call]);
        reset_peak();
      }
      std::vector<double> totals;
      Result best;
      double best_total = 1e300;
      for (int r = 0; r < repeats; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        Result res = run();
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        totals.push_back(s);
        if (s < best_total) {
          best_total = s;
          std::swap(best, res);
        }
        if (recycle) ctx->recycle(std::move(res));  // the slower of the two
      }
      std::sort(totals.begin(), totals.end());
      std::uint64_t checksum = 1469598103934665603ull;  // FNV-1a over the labels
      for (std::uint32_t l : best.labels) checksum = (checksum ^ l) * 1099511628211ull;
      const double n = static_cast<double>(g.p.size());
      std::printf("{\"voxels\": %.0f, \"best_s\": %.6f, \"median_s\": %.6f, \"ns_per_voxel\": %.3f, "
                  "\"segments\": %zu, \"labels_fnv1a\": \"%016llx\", \"peak_extra_bytes_per_voxel\": %.3f, "
                  "\"first_and_second_call\": [%.3f, %.3f], \"stages\": {",
                  n, best_total, totals[totals.size() / 2], best_total * 1e9 / n, best.segments.size(),
                  static_cast<unsigned long long>(checksum), (rss1 - rss0) * 1024.0 / n, (peak[0] - rss0) * 1024.0 / n,
                  (peak[1] - rss0) * 1024.0 / n);
      for (std::size_t k = 0; k < best.timings.size(); ++k)
        std::printf("%s\"%s\": %.6f", k ? ", " : "", best.timings[k].stage.c_str(), best.timings[k].seconds);
      std::printf("}}\n");
      return 0;
    }
    return usage();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "occseg_bench_segment: %s\n", e.what());
    return 1;
  }
}
