// Concurrent use of the C ABI (run under ThreadSanitizer too): separate handles in separate
// threads, one map and one parameter set shared by readers, per-thread error texts, the
// progress callback's thread, and concurrent writers of one output path.
#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <thread>

#include "support.hpp"

using namespace occseg::reliability;

namespace {

constexpr int kThreads = 8;
constexpr std::size_t kN = 40;

// A map of noisy blobs that differs with the seed.
std::vector<float> blobs(unsigned seed) {
  std::vector<float> p(kN * kN * kN);
  std::uint32_t s = seed * 2654435761u + 1;
  auto rnd = [&] { return (s = s * 1664525u + 1013904223u) >> 8; };
  const int cx = 8 + rnd() % 24, cy = 8 + rnd() % 24, cz = 8 + rnd() % 24, r = 4 + rnd() % 6;
  for (std::size_t z = 0; z < kN; ++z)
    for (std::size_t y = 0; y < kN; ++y)
      for (std::size_t x = 0; x < kN; ++x) {
        const int dx = int(x) - cx, dy = int(y) - cy, dz = int(z) - cz;
        const bool in = dx * dx + dy * dy + dz * dz < r * r || (z < 3 && x > kN / 2);
        const float noise = float(rnd() % 1000) / 20000.0f;  // 0 .. 0.05
        p[x + kN * (y + kN * z)] = in ? 0.9f - noise : (y > 34 ? 0.5f : 0.1f + noise);
      }
  return p;
}

struct Output {
  std::vector<std::uint32_t> labels;
  std::vector<occseg_segment_info> segments;
  bool operator==(const Output& o) const {
    if (labels != o.labels || segments.size() != o.segments.size()) return false;
    for (std::size_t i = 0; i < segments.size(); ++i)
      if (std::memcmp(&segments[i], &o.segments[i], sizeof segments[i]) != 0) return false;
    return true;
  }
};

// The labels of a map of `voxels` voxels (the blobs' by default) and the segment table.
Output collect(const occseg_result* r, std::size_t voxels = kN * kN * kN) {
  Output o;
  o.labels.resize(voxels);
  EXPECT_EQ(occseg_result_labels(r, o.labels.data(), o.labels.size()), OCCSEG_OK);
  for (std::uint32_t i = 0; i < occseg_result_segment_count(r); ++i) {
    occseg_segment_info s;
    std::memset(&s, 0, sizeof s);  // padding too, for memcmp
    s.struct_size = sizeof s;
    EXPECT_EQ(occseg_result_segment(r, i, &s), OCCSEG_OK);
    o.segments.push_back(s);
  }
  return o;
}

// Segments `map` (of `voxels` voxels, the blobs' by default) with the default preset and
// `threads` worker threads.
Output segment(const occseg_map* map, int threads, std::size_t voxels = kN * kN * kN) {
  occseg_params* params = nullptr;
  EXPECT_EQ(occseg_params_create(&params), OCCSEG_OK);
  EXPECT_EQ(occseg_params_set_int(params, "threads", threads), OCCSEG_OK);
  occseg_result* r = nullptr;
  EXPECT_EQ(occseg_segment(&r, map, params), OCCSEG_OK) << occseg_last_error();
  Output o = r ? collect(r, voxels) : Output{};
  occseg_result_free(r);
  occseg_params_free(params);
  return o;
}

// The values p(x, y, z) of a map of dims d, x fastest.
template <class F>
std::vector<float> values_of(const std::size_t d[3], F&& p) {
  std::vector<float> v(d[0] * d[1] * d[2]);
  for (std::size_t z = 0; z < d[2]; ++z)
    for (std::size_t y = 0; y < d[1]; ++y)
      for (std::size_t x = 0; x < d[0]; ++x) v[x + d[0] * (y + d[1] * z)] = p(x, y, z);
  return v;
}

// The map of values p (dims d, voxels of `voxel_size` metres) segmented on 1 and on 2 threads
// (a fatal failure when the map is refused: call it in ASSERT_NO_FATAL_FAILURE).
void on_one_and_two_threads(const std::vector<float>& p, const std::size_t d[3], double voxel_size,
                            std::array<Output, 2>& out) {
  occseg_map* map = nullptr;
  ASSERT_EQ(occseg_map_from_buffer(&map, p.data(), OCCSEG_F32, d, nullptr, voxel_size), OCCSEG_OK);
  out = {segment(map, 1, p.size()), segment(map, 2, p.size())};
  occseg_map_free(map);
}

occseg_map* make_map(unsigned seed) {
  const std::vector<float> p = blobs(seed);
  const std::size_t d[3] = {kN, kN, kN};
  occseg_map* m = nullptr;
  EXPECT_EQ(occseg_map_from_buffer(&m, p.data(), OCCSEG_F32, d, nullptr, 0.05), OCCSEG_OK);
  return m;
}

}  // namespace

TEST(Concurrency, EightSegmentationsInParallelMatchTheSerialResults) {
  std::vector<occseg_map*> maps;
  std::vector<Output> serial;
  for (int i = 0; i < kThreads; ++i) {
    maps.push_back(make_map(i));
    serial.push_back(segment(maps[i], 1));
    ASSERT_GT(serial[i].segments.size(), 1u);
  }
  ASSERT_FALSE(serial[0] == serial[1]);  // the maps differ, so a mix-up would show
  std::vector<Output> parallel(kThreads);
  std::vector<std::thread> pool;
  // Each thread builds its own map, parameters and result from scratch, and uses 2 workers.
  for (int i = 0; i < kThreads; ++i)
    pool.emplace_back([&, i] {
      occseg_map* m = make_map(i);
      parallel[i] = segment(m, 2);
      occseg_map_free(m);
    });
  for (auto& t : pool) t.join();
  for (int i = 0; i < kThreads; ++i) EXPECT_TRUE(parallel[i] == serial[i]) << "map " << i;
  for (occseg_map* m : maps) occseg_map_free(m);
}

TEST(Concurrency, OneMapAndOneParameterSetReadByEightThreads) {
  occseg_map* map = make_map(42);
  occseg_params* params = nullptr;
  ASSERT_EQ(occseg_params_create(&params), OCCSEG_OK);
  ASSERT_EQ(occseg_params_set(params, "preset", "paper"), OCCSEG_OK);
  occseg_result* first = nullptr;
  ASSERT_EQ(occseg_segment(&first, map, params), OCCSEG_OK);
  const Output want = collect(first);
  std::vector<Output> got(kThreads);
  std::vector<std::thread> pool;
  for (int i = 0; i < kThreads; ++i)
    pool.emplace_back([&, i] {
      occseg_result* r = nullptr;
      EXPECT_EQ(occseg_segment(&r, map, params), OCCSEG_OK);
      got[i] = collect(r);
      // Reading one result from many threads is allowed too.
      std::size_t d[3];
      EXPECT_EQ(occseg_result_dims(first, d), OCCSEG_OK);
      EXPECT_EQ(occseg_result_segment_count(first), want.segments.size());
      occseg_result_free(r);
    });
  for (auto& t : pool) t.join();
  for (int i = 0; i < kThreads; ++i) EXPECT_TRUE(got[i] == want) << "thread " << i;
  occseg_result_free(first);
  occseg_params_free(params);
  occseg_map_free(map);
}

TEST(Concurrency, LastErrorIsPerThread) {
  std::atomic<int> ready{0};
  std::vector<std::string> seen(kThreads);
  std::vector<std::thread> pool;
  for (int i = 0; i < kThreads; ++i)
    pool.emplace_back([&, i] {
      occseg_params* p = nullptr;
      EXPECT_EQ(occseg_params_create(&p), OCCSEG_OK);
      const std::string name = "no_such_parameter_" + std::to_string(i);
      EXPECT_EQ(occseg_params_set(p, name.c_str(), "1"), OCCSEG_EINVAL);
      // Wait until every thread has failed, then read: each must still see its own text.
      ready.fetch_add(1);
      while (ready.load() < kThreads) std::this_thread::yield();
      seen[i] = occseg_last_error();
      occseg_params_free(p);
    });
  for (auto& t : pool) t.join();
  for (int i = 0; i < kThreads; ++i)
    EXPECT_NE(seen[i].find("no_such_parameter_" + std::to_string(i) + "'"), std::string::npos) << seen[i];
}

namespace {
struct Calls {
  std::thread::id caller;
  std::atomic<int> wrong{0}, calls{0};
};
int on_progress(const char*, double, void* user) {
  auto* c = static_cast<Calls*>(user);
  c->calls.fetch_add(1);
  if (std::this_thread::get_id() != c->caller) c->wrong.fetch_add(1);
  return 0;
}
}  // namespace

TEST(Concurrency, ProgressIsReportedOnTheCallingThread) {
  occseg_map* map = make_map(7);
  std::vector<std::thread> pool;
  std::vector<Calls> calls(4);
  for (int i = 0; i < 4; ++i)
    pool.emplace_back([&, i] {
      calls[i].caller = std::this_thread::get_id();
      occseg_params* p = nullptr;
      EXPECT_EQ(occseg_params_create(&p), OCCSEG_OK);
      EXPECT_EQ(occseg_params_set_int(p, "threads", 3), OCCSEG_OK);
      EXPECT_EQ(occseg_params_set_progress(p, on_progress, &calls[i]), OCCSEG_OK);
      occseg_result* r = nullptr;
      EXPECT_EQ(occseg_segment(&r, map, p), OCCSEG_OK);
      occseg_result_free(r);
      occseg_params_free(p);
    });
  for (auto& t : pool) t.join();
  for (const Calls& c : calls) {
    EXPECT_GE(c.calls.load(), 10);  // five stages, each begun and ended
    EXPECT_EQ(c.wrong.load(), 0);
  }
  occseg_map_free(map);
}

TEST(Concurrency, WritersOfOnePathNeverMixTheirFiles) {
  // Eight threads write eight different maps to one path at once: the file that remains is
  // exactly one of them, never a mixture, and no temporary file is left.
  const std::string dir = scratch("same_path");
  const std::string path = dir + "/map.npy";
  std::vector<occseg_map*> maps;
  for (int i = 0; i < kThreads; ++i) maps.push_back(make_map(100 + i));
  for (int round = 0; round < 3; ++round) {
    std::vector<std::thread> pool;
    for (int i = 0; i < kThreads; ++i)
      pool.emplace_back([&, i] { EXPECT_EQ(occseg_map_write(maps[i], path.c_str()), OCCSEG_OK) << occseg_last_error(); });
    for (auto& t : pool) t.join();
    occseg_map* back = nullptr;
    ASSERT_EQ(occseg_map_read(&back, path.c_str()), OCCSEG_OK) << occseg_last_error();
    std::vector<float> got(kN * kN * kN), want(kN * kN * kN);
    ASSERT_EQ(occseg_map_values(back, got.data(), got.size()), OCCSEG_OK);
    int matches = 0;
    for (occseg_map* m : maps) {
      ASSERT_EQ(occseg_map_values(m, want.data(), want.size()), OCCSEG_OK);
      matches += got == want;
    }
    EXPECT_EQ(matches, 1) << "round " << round;
    occseg_map_free(back);
    EXPECT_EQ(entries(dir), std::vector<std::string>{"map.npy"});
  }
  for (occseg_map* m : maps) occseg_map_free(m);
}

#ifdef OCCSEG_BROKEN_PLUGINS
TEST(Concurrency, PluginsLoadWhileOtherThreadsSegmentAndEnumerate) {
  // Loading is documented as safe while other threads segment and enumerate: one thread loads
  // plugins (broken ones, which must fail and leave the registry unchanged, and a working
  // reader plugin where this build has one) while four threads segment and one enumerates.
  occseg_map* map = make_map(3);
  const Output want = segment(map, 1);
  const std::uint32_t before = occseg_plugin_count();
  std::atomic<bool> done{false};
  std::vector<std::thread> pool;
  std::vector<Output> got(4);
  for (int i = 0; i < 4; ++i) pool.emplace_back([&, i] { got[i] = segment(map, 2); });
  pool.emplace_back([&] {
    while (!done.load()) {
      const std::uint32_t n = occseg_plugin_count();
      for (std::uint32_t k = 0; k < n; ++k) EXPECT_NE(occseg_plugin_name(k), nullptr);
      for (std::uint32_t k = 0; k < occseg_param_count(); ++k) EXPECT_NE(occseg_param_name(k), nullptr);
    }
  });
  int failures = 0;
  for (const char* b : {"register_fails", "duplicate_stage", "abi_major", "no_entry"}) {
    const std::string path = std::string(OCCSEG_BROKEN_PLUGINS) + "/" + b + ".so";
    const int rc = occseg_plugins_load(path.c_str());
    failures += rc == OCCSEG_EPLUGIN;
    EXPECT_NE(std::string(occseg_last_error()).find(b), std::string::npos) << occseg_last_error();
  }
  std::uint32_t loaded = 0;
#ifdef OCCSEG_READER_PLUGIN
  EXPECT_EQ(occseg_plugins_load(OCCSEG_READER_PLUGIN), OCCSEG_OK) << occseg_last_error();
  loaded = 1;
#endif
  for (int i = 0; i < 4; ++i) pool[i].join();
  done = true;
  pool[4].join();
  EXPECT_EQ(failures, 4);
  EXPECT_GE(occseg_plugin_count(), before + loaded);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(got[i] == want) << "thread " << i;
  occseg_map_free(map);
}
#endif

#ifdef OCCSEG_BROKEN_PLUGINS
TEST(Concurrency, FirstReadsRacingToLoadTheSearchPathAllFindItsReader) {
  // The same race in every build (the ThreadSanitizer one has no OctoMap): the search path is the
  // folder of broken plugins, where only "misbehaving" loads; its reader of .nomap returns no
  // map. Eight threads' first reads of a .nomap start at once: each must reach that reader (the
  // load finished before any of them looked again), and the plugin is registered once.
  const int rc = in_child([&] {
    ::setenv("OCCSEG_PLUGIN_PATH", OCCSEG_BROKEN_PLUGINS, 1);
    ::unsetenv("OCCSEG_NO_DEFAULT_PLUGINS");
    std::atomic<int> ready{0}, wrong{0};
    std::vector<std::thread> pool;
    for (int i = 0; i < kThreads; ++i)
      pool.emplace_back([&] {
        ready.fetch_add(1);
        while (ready.load() < kThreads) {
        }
        occseg_map* m = nullptr;
        const int status = occseg_map_read(&m, "whatever.nomap");
        if (status != OCCSEG_EPLUGIN || !std::strstr(occseg_last_error(), "the reader returned no map") || m)
          wrong.fetch_add(1);
        occseg_map_free(m);
      });
    for (auto& t : pool) t.join();
    int copies = 0;
    for (std::uint32_t k = 0; k < occseg_plugin_count(); ++k)
      copies += std::strcmp(occseg_plugin_name(k), "misbehaving") == 0;
    return wrong.load() ? 1 : copies != 1 ? 2 : 0;
  });
  EXPECT_EQ(rc, 0) << "1: a read did not reach the plugin's reader, 2: the plugin is not registered exactly once";
}
#endif

#ifdef OCCSEG_READER_PLUGIN
TEST(Concurrency, FirstReadsOfAPluginFormatLoadTheSearchPathOnce) {
  // No load call: the first reads of .bt load the default search path (here the folder of the
  // OctoMap reader plugin, on OCCSEG_PLUGIN_PATH). Eight threads of a fresh child process start
  // their first read at once: every read succeeds and the plugin is registered once. Run alone
  // (as ctest runs each test), the child starts with no reader plugin loaded.
  const std::string plugin = OCCSEG_READER_PLUGIN;
  const std::string dir = plugin.substr(0, plugin.find_last_of('/'));
  const std::string bt = std::string(OCCSEG_SHARED_DATA) + "/geb079.bt";
  const int rc = in_child([&] {
    ::setenv("OCCSEG_PLUGIN_PATH", dir.c_str(), 1);
    ::unsetenv("OCCSEG_NO_DEFAULT_PLUGINS");
    std::atomic<int> ready{0}, failed{0};
    std::vector<std::thread> pool;
    for (int i = 0; i < kThreads; ++i)
      pool.emplace_back([&] {
        const char* opts[] = {"bbox=-1,-1,0,1,1,1", nullptr};
        ready.fetch_add(1);
        while (ready.load() < kThreads) {
        }
        occseg_map* m = nullptr;
        if (occseg_map_read_options(&m, bt.c_str(), opts) != OCCSEG_OK || !m) failed.fetch_add(1);
        occseg_map_free(m);
      });
    for (auto& t : pool) t.join();
    int copies = 0;
    for (std::uint32_t k = 0; k < occseg_plugin_count(); ++k)
      copies += std::strcmp(occseg_plugin_name(k), "octomap_reader") == 0;
    return failed.load() ? 1 : copies != 1 ? 2 : 0;
  });
  EXPECT_EQ(rc, 0) << "1: a read failed, 2: the reader plugin is not registered exactly once";
}
#endif

TEST(Concurrency, TheFirstSegmentationsOfAProcessMayStartTogether) {
  // Lazily set-up state must survive first calls made at once. Each round is a fresh child
  // process (forked before this process segments anything) whose eight threads are released
  // together into occseg_segment on a tiny map, so their first calls coincide. Under ASan this
  // catches the threads setting up glibc's unused malloc in malloc_trim at the same time.
  int crashed = 0;
  for (int round = 0; round < 40; ++round) {
    const int rc = in_child([] {
      const float p[8] = {0.1f, 0.9f, 0.1f, 0.9f, 0.9f, 0.1f, 0.9f, 0.1f};
      const std::size_t d[3] = {2, 2, 2};
      occseg_map* map = nullptr;
      if (occseg_map_from_buffer(&map, p, OCCSEG_F32, d, nullptr, 1.0) != OCCSEG_OK) return 2;
      std::atomic<int> ready{0}, failed{0};
      std::vector<std::thread> pool;
      for (int i = 0; i < kThreads; ++i)
        pool.emplace_back([&] {
          ready.fetch_add(1);
          while (ready.load() < kThreads) {
          }
          occseg_result* r = nullptr;
          if (occseg_segment(&r, map, nullptr) != OCCSEG_OK) failed.fetch_add(1);
          occseg_result_free(r);
        });
      for (auto& t : pool) t.join();
      occseg_map_free(map);
      return failed.load() ? 1 : 0;
    });
    crashed += rc != 0;
  }
  EXPECT_EQ(crashed, 0) << "of 40 processes";
}

TEST(Concurrency, RuleElevenSearchesSideBySideMatchOneThread) {
  // Four rooms (a 3.6 m floor, a 2.6 m wall, a box against both; 10 cm voxels) 2 x 2 across,
  // 1.2 m apart, under a tall free volume: four structure candidates small against the map, whose
  // plane searches run side by side on 2 threads (rules/structure.cpp). Under TSan this checks
  // those searches share nothing they write; everywhere, that labels and kinds match one thread's.
  const std::size_t d[3] = {96, 96, 192};
  const std::vector<float> p = values_of(d, [](std::size_t x, std::size_t y, std::size_t z) {
    const std::size_t rx = x % 48, ry = y % 48;
    const bool floor = z == 2 && rx >= 2 && rx <= 37 && ry >= 2 && ry <= 37;
    const bool wall = rx == 2 && ry >= 2 && ry <= 37 && z >= 2 && z <= 27;
    const bool box = rx >= 3 && rx <= 8 && ry >= 15 && ry <= 20 && z >= 3 && z <= 9;
    return floor || wall || box ? 0.9f : (z < 2 || rx < 2 ? 0.5f : 0.1f);
  });
  std::array<Output, 2> out;
  ASSERT_NO_FATAL_FAILURE(on_one_and_two_threads(p, d, 0.1, out));
  const auto kinds = [&](occseg_kind k) {
    return std::count_if(out[0].segments.begin(), out[0].segments.end(),
                         [k](const occseg_segment_info& s) { return s.kind == k; });
  };
  EXPECT_EQ(kinds(OCCSEG_KIND_STRUCTURE), 4);
  EXPECT_EQ(kinds(OCCSEG_KIND_OBJECT), 4);
  EXPECT_TRUE(out[0] == out[1]);  // labels, and every field of every segment
}

TEST(Concurrency, RuleSixSearchesOnThreadsMatchOneThread) {
  // Four occupied walls x = 10, 13, 20 and 25 (64 x 64 voxels each) in a map never observed
  // elsewhere: rule 6 finds its seeds from the occupied side (far fewer voxels than the unknown)
  // and searches the unknown gaps with layers of thousands of voxels, in pieces on 2 threads,
  // marking labels by compare-and-swap (rules/objects.cpp). Walls 2 and 4 unknown voxels apart
  // are one object, walls 6 apart are not (object_gap 4). Under TSan this checks the marking;
  // everywhere, that labels and segments match one thread's.
  const std::size_t d[3] = {40, 64, 64};
  const std::vector<float> p = values_of(d, [](std::size_t x, std::size_t, std::size_t) {
    return x == 10 || x == 13 || x == 20 || x == 25 ? 0.9f : 0.5f;
  });
  std::array<Output, 2> out;
  ASSERT_NO_FATAL_FAILURE(on_one_and_two_threads(p, d, 0.1, out));
  const auto at = [&](std::size_t x) { return out[0].labels[x + d[0] * (d[1] / 2 + d[1] * (d[2] / 2))]; };
  EXPECT_EQ(at(10), at(13));
  EXPECT_EQ(at(20), at(25));
  EXPECT_NE(at(13), at(20));
  EXPECT_EQ(std::count_if(out[0].segments.begin(), out[0].segments.end(),
                          [](const occseg_segment_info& s) { return s.state == OCCSEG_OCCUPIED; }),
            2);
  EXPECT_TRUE(out[0] == out[1]);  // labels, and every field of every segment
}

TEST(Concurrency, GapFloodOnThreadsMatchesOneThread) {
  // An occupied floor under a 2-voxel layer of ray gaps (0.5) and a sheet of gaps standing on it
  // up to the top of the map, in free space: rule 3's flood of the gaps climbs from the floor's
  // 5,120 seeds through every plane, on 2 threads slab by slab (rules/departures.cpp; each slab's
  // voxels written by one thread, steps into another slab handed on). Under TSan this checks
  // that handing on; everywhere, that labels and segments match one thread's.
  const std::size_t d[3] = {64, 80, 48};
  const std::vector<float> p = values_of(d, [](std::size_t x, std::size_t, std::size_t z) {
    return z == 0 ? 0.9f : z <= 2 || x == 20 || x == 21 ? 0.5f : 0.1f;
  });
  std::array<Output, 2> out;
  ASSERT_NO_FATAL_FAILURE(on_one_and_two_threads(p, d, 0.1, out));
  const auto at = [&](std::size_t x, std::size_t y, std::size_t z) { return out[0].labels[x + d[0] * (y + d[1] * z)]; };
  // The standing sheet's top is not free: the flood reached it.
  EXPECT_NE(out[0].segments[at(20, 40, 47)].state, OCCSEG_FREE);
  EXPECT_EQ(out[0].segments[at(40, 40, 30)].state, OCCSEG_FREE);
  EXPECT_TRUE(out[0] == out[1]);  // labels, and every field of every segment
}
