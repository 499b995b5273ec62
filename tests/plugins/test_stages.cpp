// The built-in stages as registered plugins: hand-computed lbp8 codes and contrasts, chi2 values,
// lbp6's generic callback against its fast path, 2D segmentation with lbp8, parameters naming
// stages, readers/writers by extension, and registration racing with segmentation.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <sys/stat.h>
#include <thread>

#include "builtin_io.hpp"
#include "occseg/error.hpp"
#include "stages/histogram.hpp"
#include "occseg/plugin_host.hpp"
#include "occseg/registry.hpp"
#include "occseg/segment.hpp"
#include "stages/texture.hpp"
#include "stages/texture2d.hpp"

using namespace occseg;

namespace {

Grid random_grid(Dims d, unsigned seed) {
  Grid g(d);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> level(0, 10);  // coarse values: ties happen, as in real maps
  for (float& v : g.p) v = static_cast<float>(level(rng) / 10.0);
  return g;
}

// Ojala, Pietikainen and Harwood's example unit (scaled to probabilities) at (1, 1), and a
// second unit at (2, 1) with a larger contrast:
//   y=0: 0.6 0.5 0.2 0.0
//   y=1: 0.7 0.6 0.1 0.9
//   y=2: 0.9 0.3 0.7 0.0
Grid ojala_grid() {
  Grid g(Dims{4, 3, 1});
  const float v[12] = {0.6f, 0.5f, 0.2f, 0.0f, 0.7f, 0.6f, 0.1f, 0.9f, 0.9f, 0.3f, 0.7f, 0.0f};
  std::copy(v, v + 12, g.p.begin());
  return g;
}

Grid square_map_2d() {
  // 64 x 64 x 1: free with a checker texture, an occupied square [16, 48)^2 with another.
  Grid g(Dims{64, 64, 1});
  for (std::size_t y = 0; y < 64; ++y)
    for (std::size_t x = 0; x < 64; ++x) {
      const bool in = x >= 16 && x < 48 && y >= 16 && y < 48;
      g.at(x, y, 0) = (in ? 0.85f : 0.15f) + (((x + y) % 2) ? 0.05f : 0.0f);
    }
  return g;
}

// The host table, as a plugin receives it: captured by a plugin registered for the purpose.
const occseg_plugin_host* g_host = nullptr;
int capture(const occseg_plugin_host* host, occseg_plugin_registrar*) {
  g_host = host;
  return 0;
}
const occseg_plugin_host* captured_host() {
  if (!g_host) {
    static const occseg_plugin_descriptor d{OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, sizeof d, "capture_host",
                                            "1", "test", capture};
    register_static_plugin(&d);
  }
  return g_host;
}

}  // namespace

TEST(Lbp8, HandComputedUnit) {
  // Neighbours in weight order 1, 2, 4, 8, 16, 32, 64, 128 of the centre 0.6.
  const double n[8] = {0.6, 0.5, 0.2, 0.7, 0.1, 0.9, 0.3, 0.7};
  const TextureUnit8 u = texture_unit8(0.6, n);
  EXPECT_EQ(u.lbp, 1 + 8 + 32 + 128);  // 169, as in the original figure
  EXPECT_NEAR(u.contrast, (0.6 + 0.7 + 0.9 + 0.7) / 4 - (0.5 + 0.2 + 0.1 + 0.3) / 4, 1e-15);
  EXPECT_NEAR(u.contrast, 0.45, 1e-12);
  const double flat[8] = {0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5};
  EXPECT_EQ(texture_unit8(0.5, flat).lbp, 255);
  EXPECT_EQ(texture_unit8(0.5, flat).contrast, 0.0);  // one-sided: no contrast
}

TEST(Lbp8, CodesOfAMapByHand) {
  Params p;
  p.texture = "lbp8";
  p.contrast_bins = 8;
  const Grid g = ojala_grid();
  const TextureMap tm = run_texture(g, p);
  EXPECT_EQ(tm.code_count(), 256 * 8);
  // (1,1): LBP 169, C = 0.45; (2,1): LBP 1+2+8+16+32+64 = 123, C = 3.2/6 - 0 = 0.533. Two
  // non-zero contrasts in 7 equal-frequency levels: cuts 1..3 at the first, 4..6 at the second,
  // so the levels are 1 and 4.
  EXPECT_EQ(tm.codes[1 + 4 * 1], 169 * 8 + 1);
  EXPECT_EQ(tm.codes[2 + 4 * 1], 123 * 8 + 4);
  for (std::size_t i : {0, 1, 2, 3, 4, 7, 8, 9, 10, 11}) EXPECT_EQ(tm.codes[i], kNoTexture) << i;
  p.contrast_bins = 3;  // two levels: the smaller contrast 1, the larger 2
  const TextureMap t3 = run_texture(g, p);
  EXPECT_EQ(t3.codes[5], 169 * 3 + 1);
  EXPECT_EQ(t3.codes[6], 123 * 3 + 2);
}

TEST(Lbp8, RefusesA3DMap) {
  Params p;
  p.texture = "lbp8";
  try {
    run_texture(Grid(Dims{8, 8, 2}, 0.5f), p);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::bad_dims);
    EXPECT_NE(std::string(e.what()).find("lbp8 is the 2D operator: the map has nz = 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("texture operator 'lbp8' (plugin 'builtin')"), std::string::npos);
  }
}

TEST(Lbp8, Segments2DMap) {
  const Grid g = square_map_2d();
  for (const char* tex : {"lbp8", "lbp6"}) {
    Params p;
    set_param(p, "texture", tex);
    set_param(p, "smax", "32");
    set_param(p, "smin", "4");
    const Result r = segment(g, p, true);
    std::size_t occupied = 0, free_ = 0;
    for (const Segment& s : r.segments) {
      if (s.state == State::occupied) {
        ++occupied;
        EXPECT_EQ(s.voxels, 32u * 32u) << tex;
        EXPECT_EQ(s.bbox_min[0], 16u);
        EXPECT_EQ(s.bbox_max[1], 47u);
      }
      free_ += s.state == State::free;
    }
    EXPECT_EQ(occupied, 1u) << tex;
    EXPECT_EQ(free_, 1u) << tex;
    EXPECT_GT(r.blocks.size(), 4u) << tex;  // the division did split at the square's edges
  }
}

TEST(Lbp6, GenericCallbackMatchesFastPath) {
  const TextureOperator* op = find_texture("lbp6");
  ASSERT_NE(op, nullptr);
  ASSERT_NE(op->native, nullptr);
  for (Dims d : {Dims{21, 17, 9}, Dims{30, 20, 1}}) {
    const Grid g = random_grid(d, 7);
    const TextureMap fast = compute_texture(g, 8, 2);
    Params p;
    p.threads = 2;
    const TextureMap generic = op->compute(g, p);  // the C callback, through the plugin host
    EXPECT_EQ(generic.codes_total, 64 * 8);
    EXPECT_EQ(generic.codes, fast.codes);
  }
}

TEST(ContrastLevels, HostQuantiserMatchesLbp6) {
  // The host's contrast_levels, fed lbp6's own contrasts, gives lbp6's levels.
  const Grid g = random_grid(Dims{16, 14, 12}, 3);
  const TextureMap tm = compute_texture(g, 8, 1);
  std::vector<double> c(g.dims.count(), std::nan(""));
  const std::ptrdiff_t off[6] = {-1, 1, -16, 16, -16 * 14, 16 * 14};
  for (std::size_t z = 1; z + 1 < 12; ++z)
    for (std::size_t y = 1; y + 1 < 14; ++y)
      for (std::size_t x = 1; x + 1 < 16; ++x) {
        const std::size_t i = g.index(x, y, z);
        double n[6];
        for (int k = 0; k < 6; ++k) n[k] = g.p[static_cast<std::size_t>(static_cast<std::ptrdiff_t>(i) + off[k])];
        c[i] = texture_unit(g.p[i], n).contrast;
      }
  const occseg_plugin_host* host = captured_host();
  ASSERT_NE(host, nullptr);
  std::vector<std::uint16_t> levels(c.size(), 999);
  ASSERT_EQ(host->contrast_levels(c.data(), c.size(), 8, levels.data()), 0);
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (tm.codes[i] == kNoTexture) {
      EXPECT_EQ(levels[i], kNoTexture) << i;
    } else {
      EXPECT_EQ(levels[i], tm.codes[i] % 8) << i;
      nonzero += levels[i] != 0;
    }
  }
  EXPECT_GT(nonzero, 100u);  // the comparison covered real levels, not only flat units
  EXPECT_NE(host->contrast_levels(c.data(), c.size(), 1, levels.data()), 0);  // bins outside [2, 64]
}

TEST(Similarity, Chi2ByHand) {
  const Similarity* s = find_similarity("chi2");
  ASSERT_NE(s, nullptr);
  auto chi2 = [&](std::vector<std::uint32_t> a, std::vector<std::uint32_t> b) {
    return compare_histograms(*s, a.data(), b.data(), a.size());
  };
  EXPECT_DOUBLE_EQ(chi2({1, 0}, {0, 1}), 2.0);           // (1-0)^2/1 + (0-1)^2/1
  EXPECT_DOUBLE_EQ(chi2({2, 0}, {1, 1}), 1.0 / 3 + 1.0);  // Na = Nb = 2: (2-1)^2/3 + (0-1)^2/1
  EXPECT_EQ(chi2({1, 2, 0}, {3, 6, 0}), 0.0);             // proportional
  // Na = 1, Nb = 4: k_a = 2, k_b = 1/2: (2*1 - 0.5*0)^2/1 + (0 - 0.5*4)^2/4 = 4 + 1
  EXPECT_DOUBLE_EQ(chi2({1, 0}, {0, 4}), 5.0);
  const Similarity* g = find_similarity("g");
  ASSERT_NE(g, nullptr);
  const std::uint32_t a[3] = {5, 1, 0}, b[3] = {2, 2, 2};
  EXPECT_EQ(compare_histograms(*g, a, b, 3), g_statistic(a, b, 3));
}

TEST(Similarity, DivisionUsesTheNamedOne) {
  Params p;
  EXPECT_EQ(division_similarity(p), nullptr);  // g: the division's own fast G
  p.similarity = "chi2";
  ASSERT_NE(division_similarity(p), nullptr);
  EXPECT_EQ(division_similarity(p)->name, "chi2");
  // A cube map segments the same with chi2 as with g.
  Grid g(Dims{32, 32, 32}, 0.1f);
  for (std::size_t z = 8; z < 24; ++z)
    for (std::size_t y = 8; y < 24; ++y)
      for (std::size_t x = 8; x < 24; ++x) g.at(x, y, z) = 0.9f;
  const Result rg = segment(g, Params());
  const Result rc = segment(g, p);
  EXPECT_EQ(rg.labels, rc.labels);
  ASSERT_EQ(rc.segments.size(), 2u);
}

bool same_blocks(const Result& a, const Result& b) {
  if (a.blocks.size() != b.blocks.size()) return false;
  for (std::size_t i = 0; i < a.blocks.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (a.blocks[i].lo[k] != b.blocks[i].lo[k] || a.blocks[i].hi[k] != b.blocks[i].hi[k]) return false;
  return true;
}

// Issue 26: a 2D map (nz = 1) gets lbp8, the operator of the authors' 2D method, unless the
// texture is set; 3D maps keep lbp6. The division (its blocks) shows which operator ran.
TEST(Lbp8, IsTheDefaultTextureOfA2DMapInBothPresets) {
  // Coarse noise with two patches of other textures: a denser one and a two-level one.
  Grid flat = random_grid(Dims{64, 64, 1}, 7);
  std::mt19937 rng(11);
  for (std::size_t y = 0; y < 64; ++y)
    for (std::size_t x = 0; x < 64; ++x) {
      float& v = flat.at(x, y, 0);
      v = v * 0.4f;
      if (y >= 10 && y < 20 && x >= 10 && x < 30) v = 0.6f + 0.4f * v;
      if (y >= 40 && y < 55 && x >= 30 && x < 50) v = rng() % 2 ? 0.3f : 0.7f;
    }
  for (const char* preset : {"default", "paper"}) {
    Params automatic;
    set_param(automatic, "preset", preset);
    EXPECT_EQ(automatic.texture, "auto") << preset;
    EXPECT_EQ(resolved_texture(automatic, flat.dims), "lbp8");
    EXPECT_EQ(resolved_texture(automatic, Dims{64, 64, 2}), "lbp6");
    Params lbp8 = automatic, lbp6 = automatic;
    set_param(lbp8, "texture", "lbp8");
    set_param(lbp6, "texture", "lbp6");
    EXPECT_EQ(resolved_texture(lbp6, flat.dims), "lbp6");  // set explicitly: kept
    const Result ra = segment(flat, automatic, true), r8 = segment(flat, lbp8, true), r6 = segment(flat, lbp6, true);
    EXPECT_TRUE(same_blocks(ra, r8)) << preset;
    EXPECT_EQ(ra.labels, r8.labels) << preset;
    EXPECT_FALSE(same_blocks(ra, r6) && ra.labels == r6.labels)
        << preset << ": lbp6 and lbp8 segment this map alike; the test proves nothing";
  }
  // A 3D map: "auto" is lbp6 (lbp8 would refuse it).
  const Grid cube = random_grid(Dims{16, 16, 16}, 3);
  Params lbp6;
  set_param(lbp6, "texture", "lbp6");
  const Result ra = segment(cube, Params(), true), r6 = segment(cube, lbp6, true);
  EXPECT_TRUE(same_blocks(ra, r6));
  EXPECT_EQ(ra.labels, r6.labels);
}

TEST(Params, StageNames) {
  Params p;
  EXPECT_EQ(get_param(p, "texture"), "auto");
  EXPECT_EQ(get_param(p, "similarity"), "g");
  set_param(p, "texture", "lbp8");
  set_param(p, "similarity", "chi2");
  EXPECT_EQ(p.texture, "lbp8");
  EXPECT_EQ(get_param(p, "similarity"), "chi2");
  try {
    set_param(p, "texture", "lbp7");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("parameter 'texture': 'lbp7' is not a registered texture operator (registered: lbp6, lbp8"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(p.texture, "lbp8");  // unchanged by the failure
  EXPECT_THROW(set_param(p, "similarity", "G"), Error);
  set_param(p, "preset", "paper");  // resets stage names too
  EXPECT_EQ(p.texture, "auto");
  set_param(p, "texture", "auto");  // the default can be asked for by name
  p.similarity = "nope";  // set directly: validate() catches it
  EXPECT_THROW(p.validate(), Error);
  EXPECT_THROW(segment(Grid(Dims{4, 4, 4}), p), Error);
  const ParamInfo* t = find_param("texture");
  ASSERT_NE(t, nullptr);
  EXPECT_STREQ(t->kind, "string");
  EXPECT_EQ(param_owner("texture"), "builtin");
  EXPECT_EQ(param_default("similarity"), "g");
  EXPECT_EQ(find_param("no_such"), nullptr);
}

TEST(Registry, BuiltinsAndExtensions) {
  const auto plugins = loaded_plugins();
  ASSERT_GE(plugins.size(), 2u);
  EXPECT_EQ(plugins[0]->name, "builtin");
  EXPECT_EQ(plugins[1]->name, "builtin_io");
  EXPECT_EQ(plugins[0]->textures, (std::vector<std::string>{"lbp6", "lbp8"}));
  EXPECT_EQ(plugins[0]->similarities, (std::vector<std::string>{"g", "chi2"}));
  EXPECT_NE(find_reader(".NPY"), nullptr);  // case-insensitive
  EXPECT_EQ(find_reader(".bmp"), nullptr);
  EXPECT_EQ(file_extension("dir.d/map.BT"), ".bt");
  EXPECT_EQ(file_extension("dir.d/map"), "");
  EXPECT_EQ(file_extension("map."), "");
  EXPECT_EQ(file_extension("a.tar.nrrd"), ".nrrd");
}

TEST(Registry, ReadWriteByExtension) {
  ::mkdir(OCCSEG_TEST_TMP, 0777);
  Grid g = random_grid(Dims{5, 4, 3}, 11);
  g.voxel_size = 0.25;
  g.origin = {1, 2, 3};
  const std::string nrrd = std::string(OCCSEG_TEST_TMP) + "/map.NRRD", npy = std::string(OCCSEG_TEST_TMP) + "/map.npy";
  write_map(nrrd, g);
  const Grid a = read_map(nrrd);
  EXPECT_EQ(a.p, g.p);
  EXPECT_EQ(a.voxel_size, 0.25);
  EXPECT_EQ(a.origin, g.origin);
  write_map(npy, g);
  const Grid b = read_map(npy, {"voxel_size=0.5"});
  EXPECT_EQ(b.p, g.p);
  EXPECT_EQ(b.voxel_size, 0.5);
  try {
    read_map(npy, {"colour=red"});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("unknown option 'colour=red'"), std::string::npos) << e.what();
  }
  try {
    write_map(std::string(OCCSEG_TEST_TMP) + "/map.xyz", g);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::unsupported);
    EXPECT_NE(std::string(e.what()).find("no writer for extension '.xyz' (writers: .npy, .nrrd"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(read_map(std::string(OCCSEG_TEST_TMP) + "/noext"), Error);
}

namespace {

// A plugin compiled into the test, registered under a fresh name each time (for the race test).
std::atomic<int> g_next{0};
thread_local std::string t_name;
double zero_similarity(const occseg_plugin_call*, const std::uint32_t*, const std::uint32_t*, std::size_t) { return 0; }
int register_one(const occseg_plugin_host* host, occseg_plugin_registrar* r) {
  const occseg_plugin_similarity s{sizeof s, t_name.c_str(), "test", zero_similarity, nullptr};
  return host->register_similarity(r, &s);
}

}  // namespace

TEST(Registry, RegistrationWhileSegmenting) {
  // Registering plugins on one thread while another segments and enumerates: the segmentation
  // is unaffected and every registration becomes visible whole (run under TSan in reliability builds).
  Grid g(Dims{32, 32, 32}, 0.1f);
  for (std::size_t z = 4; z < 20; ++z)
    for (std::size_t y = 4; y < 20; ++y)
      for (std::size_t x = 4; x < 20; ++x) g.at(x, y, z) = 0.9f;
  Params p;
  p.threads = 2;
  const Result ref = segment(g, p);
  const std::size_t before = similarities().size();
  std::thread loader([] {
    for (int i = 0; i < 40; ++i) {
      t_name = "race_" + std::to_string(g_next++);
      const std::string plugin = "race_plugin_" + std::to_string(i);
      const occseg_plugin_descriptor d{OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, sizeof d, plugin.c_str(),
                                       "1", "race test", register_one};
      register_static_plugin(&d);
    }
  });
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(segment(g, p).labels, ref.labels);
    for (const Similarity* s : similarities()) EXPECT_FALSE(s->name.empty());
  }
  loader.join();
  EXPECT_EQ(similarities().size(), before + 40);
  ASSERT_NE(find_similarity("race_39"), nullptr);
  EXPECT_EQ(find_similarity("race_39")->plugin, "race_plugin_39");
}

// As the occseg command: the built-in readers and writers are registered before any test registers
// a plugin of its own, so they are the plugin after "builtin" (Registry.BuiltinsAndExtensions).
int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  occseg::capi::register_builtin_io();
  return RUN_ALL_TESTS();
}
