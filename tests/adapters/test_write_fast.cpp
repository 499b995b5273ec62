// The fast writers of the default outputs (issue 27) against the slow ways they replace, bytes for
// bytes where the format allows: segments.ot written straight from the grid against the file
// liboctomap writes of the tree it builds; labels.nrrd's runs coded by hand against zlib's
// inflate (every gzip reader's), on any thread count; StagedFiles::adopt, which lets files be
// written at the same time and committed together.
#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "occseg/gzip.hpp"
#include "occseg/octomap_segments.hpp"
#include "occseg/octomap_tree.hpp"
#include "occseg/segment.hpp"

using namespace occseg;
namespace fs = std::filesystem;

namespace {

std::string tmp(const std::string& name) {
  fs::create_directories(std::string(OCCSEG_TEST_TMP) + "/write_fast");
  return std::string(OCCSEG_TEST_TMP) + "/write_fast/" + name;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// --- segments.ot ------------------------------------------------------------------------------

// What the writer wrote before it skipped the tree: liboctomap's own file of segments_octree's tree.
std::string octomap_file(const Grid& g, const Result& r) {
  const auto tree = segments_octree(g, r);
  std::ostringstream os;
  tree->write(os);
  return os.str();
}

void expect_same_ot(const Grid& g, const Result& r, const std::string& name) {
  const std::string f = tmp(name);
  write_segments_octree(f, g, r);
  const std::string mine = slurp(f), theirs = octomap_file(g, r);
  EXPECT_EQ(mine.size(), theirs.size()) << name;
  EXPECT_TRUE(mine == theirs) << name << ": the file differs from liboctomap's";
}

// Blobs of probabilities in free space: several segments, probabilities of all kinds.
Grid blobs(Dims d, double voxel, std::array<double, 3> origin, unsigned seed) {
  Grid g(d, 0.1f, voxel);
  g.origin = origin;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> p(0.6f, 1.0f);
  for (int b = 0; b < 6; ++b) {
    const std::size_t x0 = rng() % d.nx, y0 = rng() % d.ny, z0 = rng() % d.nz;
    const std::size_t w = 1 + rng() % 9, h = 1 + rng() % 9, t = 1 + rng() % 9;
    for (std::size_t z = z0; z < std::min(d.nz, z0 + t); ++z)
      for (std::size_t y = y0; y < std::min(d.ny, y0 + h); ++y)
        for (std::size_t x = x0; x < std::min(d.nx, x0 + w); ++x) g.at(x, y, z) = p(rng);
  }
  return g;
}

}  // namespace

TEST(DirectSegmentsOt, SameBytesAsLiboctomapsFile) {
  // On and off the lattice, negative and positive origins, odd sizes, a one-voxel map, and maps
  // whose keys straddle the tree's centre (where the top levels split).
  const struct {
    Dims d;
    double voxel;
    std::array<double, 3> origin;
  } cases[] = {{{37, 23, 11}, 0.1, {-1.2, 0.3, 0.0}},   {{16, 16, 16}, 0.05, {0.0, 0.0, 0.0}},
               {{29, 31, 7}, 0.08, {-0.07, 2.5, -0.33}}, {{1, 1, 1}, 0.2, {0.4, -0.2, 0.0}},
               {{64, 9, 40}, 0.25, {-8.0, -1.0, -5.0}},  {{50, 50, 20}, 0.1, {-2.55, -2.45, -1.0}}};
  unsigned seed = 1;
  for (const auto& c : cases) {
    const Grid g = blobs(c.d, c.voxel, c.origin, seed++);
    const Result r = segment(g, Params::defaults());
    expect_same_ot(g, r, "blobs" + std::to_string(seed) + ".ot");
  }
}

TEST(DirectSegmentsOt, NoOccupiedVoxelIsAnEmptyTreeAsLiboctomapWritesIt) {
  const Grid g(Dims{12, 10, 8}, 0.1f, 0.1);
  const Result r = segment(g, Params::defaults());
  expect_same_ot(g, r, "empty.ot");
}

// --- gzip with runs coded by hand -------------------------------------------------------------

namespace {

std::string gzip_of(const std::vector<std::uint32_t>& w, const GzipRuns& runs, int threads) {
  std::ostringstream os;
  write_gzip(os, w.data(), w.size() * 4, 1, threads, {}, runs);
  return os.str();
}

void expect_round_trip(const std::vector<std::uint32_t>& w, const GzipRuns& runs, const std::string& what) {
  const std::string one = gzip_of(w, runs, 1);
  for (int threads : {2, 5}) EXPECT_TRUE(gzip_of(w, runs, threads) == one) << what << ": depends on the thread count";
  std::vector<std::uint32_t> back(w.size() + 1, 0xdeadbeef);
  const std::string why = gunzip_exact(one.data(), one.size(), back.data(), w.size() * 4);
  ASSERT_EQ(why, "") << what;
  // (memcmp of no bytes still needs valid pointers: an empty vector's data() may be null.)
  EXPECT_TRUE(w.empty() || std::memcmp(back.data(), w.data(), w.size() * 4) == 0) << what << ": inflates to other bytes";
  EXPECT_EQ(back[w.size()], 0xdeadbeefu) << what;
}

}  // namespace

TEST(GzipRunsCoded, InflatesToTheSameBytesAnyRunAnyThreadCount) {
  std::mt19937 rng(7);
  // Runs of every length from 1 to 300 words (matches of 258 bytes and the remainders of 1 and 2
  // bytes that must borrow from the match before them), in one piece.
  std::vector<std::uint32_t> runs;
  for (std::uint32_t len = 1; len <= 300; ++len) runs.insert(runs.end(), len, len * 2654435761u);
  expect_round_trip(runs, {4, 0, 0}, "runs 1..300");
  // A volume whose rows and slices repeat (distances of a row and a slice), over several pieces,
  // with noise in its middle: pieces that go to zlib between pieces of runs that refer back into them.
  const std::size_t nx = 200, ny = 30, nz = 800;  // 4.8 M words: five pieces
  std::vector<std::uint32_t> v(nx * ny * nz);
  for (std::size_t z = 0; z < nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        std::uint32_t l = std::uint32_t((x / 37) + 3 * (z / 50));
        if (y % 7 == 3 && x % 11 == 0) l = 99;  // a row unlike the one before it
        if (z >= 300 && z < 420) l = rng();     // noise: a piece zlib takes
        v[x + nx * (y + ny * z)] = l;
      }
  expect_round_trip(v, {4, nx, nx * ny}, "volume");
  // A slice within the window (small maps), and a row too long for it (no row distance then).
  std::vector<std::uint32_t> small(9 * 8 * 40);
  for (std::size_t i = 0; i < small.size(); ++i) small[i] = std::uint32_t((i / 72) % 3 == 0 ? i % 72 : i / 500);
  expect_round_trip(small, {4, 9, 72}, "small slices");
  std::vector<std::uint32_t> wide(10000 * 20);
  for (std::size_t i = 0; i < wide.size(); ++i) wide[i] = std::uint32_t((i % 10000) / 1000);
  expect_round_trip(wide, {4, 10000, 200000}, "wide rows");
  // Nothing, one word, two.
  expect_round_trip({}, {4, 1, 1}, "empty");
  expect_round_trip({5}, {4, 1, 1}, "one word");
  expect_round_trip({5, 5}, {4, 1, 1}, "two words");
}

TEST(GzipRunsCoded, LabelsAreCodedAsRunsAndStayCompact) {
  // Labels in long runs: coded by hand (not zlib's bytes), at most a 16th of their size.
  std::vector<std::uint32_t> v(1 << 20);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = std::uint32_t(i / 3000);
  const std::string runs = gzip_of(v, {4, 512, 512 * 64}, 1), zlib = gzip_of(v, {}, 1);
  EXPECT_FALSE(runs == zlib) << "the runs went to zlib";
  EXPECT_LT(runs.size(), v.size() * 4 / 16);
}

// --- StagedFiles::adopt -----------------------------------------------------------------------

TEST(StagedAdopt, FilesOfSeveralSetsCommitTogetherOrNotAtAll) {
  fs::create_directories(tmp("adopt"));
  const std::string a = tmp("adopt/a.txt"), b = tmp("adopt/b.txt"), old = tmp("adopt/old.txt");
  fs::remove(b);  // from an earlier run
  std::ofstream(a) << "old a";
  std::ofstream(old) << "old";
  {
    StagedFiles all, one, two;
    one.stage(a, [](std::ostream& o) { o << "new a"; });
    two.stage(b, [](std::ostream& o) { o << "new b"; });
    two.remove_on_commit(old);
    all.adopt(one);
    all.adopt(two);
    EXPECT_TRUE(one.paths().empty() && two.paths().empty());
    EXPECT_EQ(all.paths(), (std::vector<std::string>{a, b}));
  }  // discarded: nothing changed, no temporary left
  EXPECT_EQ(slurp(a), "old a");
  EXPECT_FALSE(fs::exists(b));
  EXPECT_TRUE(fs::exists(old));
  StagedFiles all, one, two;
  one.stage(a, [](std::ostream& o) { o << "first a"; });
  two.stage(a, [](std::ostream& o) { o << "second a"; });  // the later set's version wins
  two.stage(b, [](std::ostream& o) { o << "new b"; });
  two.remove_on_commit(old);
  all.adopt(one);
  all.adopt(two);
  all.commit();
  EXPECT_EQ(slurp(a), "second a");
  EXPECT_EQ(slurp(b), "new b");
  EXPECT_FALSE(fs::exists(old));
  for (const auto& e : fs::directory_iterator(tmp("adopt")))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}
