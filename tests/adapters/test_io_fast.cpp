// The fast readers and writers of issue 27 against the slow ways they replace: .bt read from its
// checked bytes against the tree liboctomap builds, .npy read straight into the grid against
// read_npy + grid_from_npy, gzip NRRD written and read back, and the removals of StagedFiles.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "occseg/gzip.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/octomap_tree.hpp"

using namespace occseg;
namespace fs = std::filesystem;

namespace {

const std::string kBt = std::string(OCCSEG_SHARED_DATA) + "/geb079.bt";

std::string tmp(const std::string& name) {
  fs::create_directories(std::string(OCCSEG_TEST_TMP) + "/io_fast");
  return std::string(OCCSEG_TEST_TMP) + "/io_fast/" + name;
}

void expect_same(const Grid& a, const Grid& b) {
  ASSERT_EQ(a.dims.nx, b.dims.nx);
  ASSERT_EQ(a.dims.ny, b.dims.ny);
  ASSERT_EQ(a.dims.nz, b.dims.nz);
  EXPECT_EQ(a.voxel_size, b.voxel_size);
  EXPECT_EQ(a.origin, b.origin);
  ASSERT_EQ(a.p.size(), b.p.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.p.size(); ++i) differ += a.p[i] != b.p[i];
  EXPECT_EQ(differ, 0u);
}

std::string message_of(const std::function<void()>& f, Status* status = nullptr) {
  try {
    f();
  } catch (const Error& e) {
    if (status) *status = e.status();
    return e.what();
  }
  if (status) *status = Status::ok;
  return "";
}

}  // namespace

// The .bt reader makes the leaves from the bytes it checked and never builds liboctomap's tree:
// the grid must be the one of the tree liboctomap reads, at the resolution, coarsened both ways
// and in a box.
TEST(FastReaders, BtFromItsBytesIsTheGridOfTheTreeOctomapReads) {
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(kBt));
  std::vector<OctreeOptions> cases(4);
  cases[1].voxel_size = 2 * tree.getResolution();
  cases[2].voxel_size = 3 * tree.getResolution();
  cases[2].coarsen = Coarsen::mean;
  cases[3].bbox = Box{{-2, -3, -1}, {5, 2, 1.5}};
  for (const OctreeOptions& o : cases) expect_same(read_octree_file(kBt, o), grid_from_octree(tree, o));
}

// A .bt whose inner node has no children (code 11 over 00 00: liboctomap keeps it as an occupied
// leaf) and whose root has one free and one occupied child.
TEST(FastReaders, BtInnerNodesWithoutChildrenAreOccupiedLeavesAsInOctomap) {
  const std::string f = tmp("childless.bt");
  std::string body;
  body += char(0x01 | 0x08 | 0x30);  // child 0 free, child 1 occupied, child 2 inner
  body += char(0x00);
  body += std::string(2, '\0');  // child 2: no children
  {
    std::ofstream out(f, std::ios::binary);
    out << "# Octomap OcTree binary file\nid OcTree\nsize 4\nres 0.5\ndata\n" << body;
  }
  octomap::OcTree tree(0.5);
  ASSERT_TRUE(tree.readBinary(f));
  ASSERT_EQ(tree.size(), 4u);
  OctreeOptions o;
  o.bbox = Box{{-4, -4, -4}, {4, 4, 4}};
  expect_same(read_octree_file(f, o), grid_from_octree(tree, o));
}

TEST(FastReaders, NpyStraightIntoTheGridIsReadNpyPlusGridFromNpy) {
  Grid g(Dims{13, 7, 5}, 0.5f, 0.2);
  std::mt19937 rng(3);
  for (float& v : g.p) v = std::uniform_real_distribution<float>(0, 1)(rng);
  for (const char* descr : {"<f4", "<f8", "|u1", "<u2"}) {
    const std::string f = tmp(std::string("map_") + (descr[1] == 'u' ? "u" : "f") + descr[2] + ".npy");
    write_grid_npy_as(f, g, descr);
    NpyArray header;
    const Grid fast = read_npy_grid(f, 0.2, &header);
    expect_same(fast, grid_from_npy(read_npy(f), 0.2, f));
    EXPECT_EQ(header.descr, std::string(descr) == "|u1" ? "|u1" : descr);
  }
  // Truncated data and a bad value: the messages of read_npy + grid_from_npy.
  const std::string f = tmp("cut.npy");
  write_grid_npy(f, g);
  fs::resize_file(f, fs::file_size(f) - 4);
  EXPECT_NE(message_of([&] { read_npy_grid(f, 1.0); }).find("truncated data"), std::string::npos);
  g.p[17] = 2.0f;
  write_grid_npy(f, g);
  Status s;
  EXPECT_NE(message_of([&] { read_npy_grid(f, 1.0); }, &s).find("outside [0, 1]"), std::string::npos);
  EXPECT_EQ(s, Status::bad_value);
}

TEST(GzipNrrd, LabelsWrittenGzipReadBackEqualOnAnyThreadCount) {
  Grid g(Dims{300, 200, 90}, 0.5f, 0.05);  // 5.4 M labels: two pieces and a part
  LabelArray labels(g.dims.count());
  for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = static_cast<std::uint32_t>(i / 1000 + (i % 7 == 0));
  std::string first;
  for (int threads : {1, 2, 5}) {
    const std::string f = tmp("labels_" + std::to_string(threads) + ".nrrd");
    NrrdWriteOptions w;
    w.gzip = true;
    w.threads = threads;
    write_labels_nrrd(f, g, labels, "", nullptr, w);
    std::ifstream in(f, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(bytes.find("encoding: gzip\n"), std::string::npos);
    EXPECT_LT(bytes.size(), labels.size() * 4 / 20);
    if (first.empty()) first = bytes;
    EXPECT_EQ(bytes, first) << "the file depends on the thread count";
    const NrrdVolume v = read_nrrd(f);
    ASSERT_EQ(v.data.size(), labels.size() * 4);
    EXPECT_EQ(std::memcmp(v.data.data(), labels.data(), v.data.size()), 0);
  }
}

// A removal staged with the new files: done by the commit, undone when the commit fails, and
// nothing removed by a set that is discarded.
TEST(StagedRemovals, RemovedAtTheCommitKeptWhenDiscarded) {
  // A folder of its own: the other tests of this binary, run in parallel, stage files beside theirs.
  fs::create_directories(tmp("staged"));
  auto tmp = [](const std::string& name) { return ::tmp("staged/" + name); };
  const std::string old_file = tmp("old_output.npy"), keep = tmp("mine.txt");
  fs::remove(tmp("new.json"));
  std::ofstream(old_file) << "old";
  std::ofstream(keep) << "mine";
  {
    StagedFiles s;
    s.stage(tmp("new.json"), [](std::ostream& o) { o << "{}"; });
    s.remove_on_commit(old_file);
  }  // discarded
  EXPECT_TRUE(fs::exists(old_file));
  EXPECT_FALSE(fs::exists(tmp("new.json")));
  StagedFiles s;
  s.stage(tmp("new.json"), [](std::ostream& o) { o << "{}"; });
  s.remove_on_commit(old_file);
  s.remove_on_commit(tmp("never_there.npy"));
  s.commit();
  EXPECT_FALSE(fs::exists(old_file));
  EXPECT_TRUE(fs::exists(tmp("new.json")));
  EXPECT_TRUE(fs::exists(keep));
  for (const auto& e : fs::directory_iterator(fs::path(keep).parent_path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}
