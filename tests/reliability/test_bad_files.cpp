// The bad-input table of docs/reliability.md, file rows: truncated, corrupted, wrong-magic and
// absurd-header files of every format give a pinned status and a message naming the file, never
// a crash and never an attempt to allocate what the header claims.
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <random>

#include "occseg/error.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/octomap_file.hpp"
#include "occseg/pcd.hpp"
#include "support.hpp"

using namespace occseg;
using namespace occseg::reliability;

namespace {

const std::string kData = OCCSEG_SHARED_DATA;
const std::string kCorpus = OCCSEG_FUZZ_CORPUS;

struct Outcome {
  Status status = Status::ok;
  std::string message;
};

// Reads `path` as a map with the reader of `format`. npy goes through the C ABI, so the rows
// pin the OCCSEG_E* code a C caller sees.
Outcome read_as(const std::string& format, const std::string& path) {
  Outcome o;
  try {
    if (format == "npy") {
      occseg_map* m = nullptr;
      o.status = static_cast<Status>(occseg_map_read(&m, path.c_str()));
      o.message = occseg_last_error();
      EXPECT_EQ(m == nullptr, o.status != Status::ok);
      occseg_map_free(m);
      return o;
    }
    ScanOptions scan;
    scan.voxel_size = 0.1;
    scan.threads = 1;
    if (format == "nrrd") grid_from_nrrd(read_nrrd(path), path);
    else if (format == "pcd") read_pcd(path, scan);
    else if (format == "graph") read_scan_graph(path, scan);
    else read_octree_file(path);
  } catch (const Error& e) {
    o.status = e.status();
    o.message = e.what();
  }
  return o;
}

// A small .ot (OcTree) written by OctoMap, as base for the .ot rows. Several tests use it, and
// ctest runs them as separate processes at once: each writes its own (a shared directory was
// emptied by one while another wrote into it).
std::string small_ot() {
  static const std::string path = [] {
    const std::string p = scratch("ot_base_" + std::to_string(getpid())) + "/small.ot";
    octomap::OcTree t(0.1);
    for (int i = -5; i <= 5; ++i) t.updateNode(octomap::point3d(0.1f * i, 0.05f, 0.3f), float(0.4 * i));
    t.write(p);
    return p;
  }();
  return path;
}

struct Base {
  std::string format, path;
};
std::vector<Base> bases() {
  return {{"npy", kCorpus + "/npy/c_f4_4x5x6.npy"},
          {"npy", kCorpus + "/npy/fortran_f8_3x4x5.npy"},
          {"nrrd", kCorpus + "/nrrd/raw_float_le.nrrd"},
          {"nrrd", kCorpus + "/nrrd/ascii_double.nrrd"},
          {"pcd", kData + "/table_scene_mug_stereo_textured.pcd"},  // binary_compressed
          {"bt", kData + "/geb079.bt"},
          {"ot", small_ot()},
          {"graph", kData + "/spherical_scan.graph"}};
}

std::string name_of(const std::string& path) { return fs::path(path).filename().string(); }

}  // namespace

TEST(BadFiles, TheRealBasesReadCleanly) {
  for (const Base& b : bases()) EXPECT_EQ(read_as(b.format, b.path).status, Status::ok) << b.path;
}

TEST(BadFiles, MissingDirectoryAndUnreadablePathsAreIoErrorsNamingThePath) {
  const std::string dir = scratch("unreadable");
  for (const char* format : {"npy", "nrrd", "pcd", "bt", "ot", "graph"}) {
    const std::string missing = dir + "/missing." + format;
    Outcome o = read_as(format, missing);
    EXPECT_EQ(o.status, Status::io) << format << ": " << o.message;
    EXPECT_NE(o.message.find(missing), std::string::npos) << o.message;
    // A path through a regular file: ENOTDIR.
    const std::string through = kCorpus + "/npy/c_f4_4x5x6.npy/x." + format;
    o = read_as(format, through);
    EXPECT_EQ(o.status, Status::io) << format << ": " << o.message;
    EXPECT_NE(o.message.find("Not a directory"), std::string::npos) << o.message;
    // A directory is not a file.
    const std::string is_dir = dir + "/dir." + std::string(format);
    fs::create_directories(is_dir);
    o = read_as(format, is_dir);
    EXPECT_EQ(o.status, Status::io) << format << ": " << o.message;
    EXPECT_NE(o.message.find("it is a directory"), std::string::npos) << format << ": " << o.message;
  }
}

// A FIFO blocked every reader in open() (waiting for a writer, forever), and a link to
// /dev/zero was read until memory ran out before any magic was checked. Only regular files are
// read now: the others are EIO naming the file and its kind, with nothing read. Each read runs
// in a child with an alarm, so that a regression fails this test instead of hanging it, and
// (outside sanitizer builds) with an address-space limit for the endless /dev/zero.
TEST(BadFiles, FifosAndDevicesAreRefusedWithoutReadingOrBlocking) {
  const std::string dir = scratch("special");
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  const bool limit_memory = false;  // RLIMIT_AS and sanitizer shadow memory do not mix
#else
  const bool limit_memory = true;
#endif
  struct Case {
    std::string path, kind;
  };
  for (const char* format : {"npy", "nrrd", "pcd", "bt", "ot", "graph"}) {
    const std::string fifo = dir + "/fifo." + format, null = dir + "/null." + format, zero = dir + "/zero." + format;
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << fifo;
    fs::create_symlink("/dev/null", null);
    fs::create_symlink("/dev/zero", zero);
    for (const Case& c : {Case{fifo, "FIFO"}, Case{null, "character device"}, Case{zero, "character device"}}) {
      const std::string report = dir + "/report";
      const int rc = in_child([&] {
        ::alarm(60);  // a hang is a failure (SIGALRM: 128 + 14), not a stuck test
        if (limit_memory) {  // what is in use plus 512 MiB
          std::FILE* f = std::fopen("/proc/self/statm", "r");
          unsigned long pages = 0;
          if (!f || std::fscanf(f, "%lu", &pages) != 1) return 5;
          std::fclose(f);
          const rlim_t bytes = pages * static_cast<rlim_t>(::sysconf(_SC_PAGESIZE)) + (rlim_t(1) << 29);
          const rlimit r{bytes, bytes};
          if (::setrlimit(RLIMIT_AS, &r) != 0) return 6;
        }
        const Outcome o = read_as(format, c.path);
        put(report, o.message);
        return o.status == Status::io ? 0 : 1;
      });
      const std::string message = slurp(report);
      EXPECT_EQ(rc, 0) << c.path << ": " << message;
      EXPECT_NE(message.find(c.path), std::string::npos) << message;
      EXPECT_NE(message.find("not a regular file but a " + c.kind), std::string::npos) << message;
    }
  }
  // A FIFO named *.so: the plugin loader refused it only after dlopen() had waited for a writer.
  const std::string so = dir + "/fifo.so";
  ASSERT_EQ(::mkfifo(so.c_str(), 0600), 0);
  const int rc = in_child([&] {
    ::alarm(60);
    const int s = occseg_plugins_load(so.c_str());
    return s == OCCSEG_EPLUGIN && std::strstr(occseg_last_error(), "FIFO") ? 0 : 1;
  });
  EXPECT_EQ(rc, 0);
}

TEST(BadFiles, FilesWithoutReadPermissionAreIoErrors) {
  // root reads anything, so the check runs in a child that has dropped to an unprivileged user.
  const std::string dir = scratch("no_permission");
  const std::string f = dir + "/locked.npy";
  fs::copy_file(kCorpus + "/npy/c_f4_4x5x6.npy", f);
  fs::permissions(f, fs::perms::none);
  fs::permissions(dir, fs::perms::all);
  const int rc = in_child([&] {
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) return 3;
    occseg_map* m = nullptr;
    const int s = occseg_map_read(&m, f.c_str());
    return s == OCCSEG_EIO && m == nullptr && std::strstr(occseg_last_error(), "Permission denied") ? 0 : 1;
  });
  EXPECT_EQ(rc, 0);
}

TEST(BadFiles, TruncatedFilesOfEveryFormatAreFormatErrors) {
  const std::string dir = scratch("truncated");
  for (const Base& b : bases()) {
    const std::string bytes = slurp(b.path);
    ASSERT_GT(bytes.size(), 64u) << b.path;
    // The last byte matters in the exactly-sized formats; text and PCD files may end in slack
    // (a newline, padding after the compressed block), so there the cut goes deeper.
    const bool slack = b.format == "pcd" || b.path.find("ascii") != std::string::npos;
    for (std::size_t cut : {std::size_t(0), std::size_t(1), std::size_t(9), std::size_t(40), bytes.size() / 2,
                            slack ? bytes.size() * 9 / 10 : bytes.size() - 1}) {
      const std::string f = dir + "/cut" + std::to_string(cut) + "_" + name_of(b.path);
      put(f, bytes.substr(0, cut));
      const Outcome o = read_as(b.format, f);
      EXPECT_EQ(o.status, Status::format) << f << ": " << o.message;
      EXPECT_NE(o.message.find(f), std::string::npos) << o.message;
    }
  }
}

TEST(BadFiles, WrongMagicIsAFormatErrorSayingSo) {
  const std::string dir = scratch("magic");
  const std::vector<std::pair<std::string, std::string>> expect = {
      {"npy", "wrong magic"}, {"nrrd", "does not start with NRRD"}, {"pcd", "is not a PCD header field"},
      {"bt", "not an OctoMap header"}, {"ot", "not an OctoMap header"}, {"graph", "scan graph"}};
  for (const Base& b : bases()) {
    std::string bytes = slurp(b.path);
    bytes[0] = b.format == "graph" ? '\x7f' : 'X';  // a graph has no magic: its node count changes
    const std::string f = dir + "/magic_" + name_of(b.path);
    put(f, bytes);
    const Outcome o = read_as(b.format, f);
    std::string phrase;
    for (const auto& e : expect)
      if (e.first == b.format) phrase = e.second;
    EXPECT_EQ(o.status, Status::format) << f << ": " << o.message;
    EXPECT_NE(o.message.find(phrase), std::string::npos) << o.message;
  }
}

TEST(BadFiles, RandomlyCorruptedFilesNeverCrashAndFailWithAFileStatus) {
  const std::string dir = scratch("corrupt");
  std::mt19937 rng(2024);
  for (const Base& b : bases()) {
    const std::string bytes = slurp(b.path);
    // Headers are where corruption hurts most: half the flips land in the first 256 bytes.
    for (int k = 0; k < 24; ++k) {
      std::string c = bytes;
      for (int flips = 0; flips < 1 + k % 4; ++flips) {
        const std::size_t at = (k % 2 ? rng() % std::min<std::size_t>(256, c.size()) : rng() % c.size());
        c[at] = static_cast<char>(rng());
      }
      const std::string f = dir + "/c" + std::to_string(k) + "_" + name_of(b.path);
      put(f, c);
      const Outcome o = read_as(b.format, f);
      if (o.status == Status::ok) continue;  // a flip in the values can leave a valid file
      EXPECT_TRUE(o.status == Status::format || o.status == Status::bad_value || o.status == Status::unsupported ||
                  o.status == Status::bad_dims)
          << f << ": " << static_cast<int>(o.status) << " " << o.message;
      EXPECT_NE(o.message.find(f), std::string::npos) << o.message;
    }
  }
}

TEST(AbsurdHeaders, NpyClaimingTrillionsOfElementsIsRefusedWithoutAllocating) {
  const std::string dir = scratch("absurd_npy");
  auto npy = [&](const std::string& name, const std::string& shape) {
    std::string h = "{'descr': '<f4', 'fortran_order': False, 'shape': " + shape + ", }";
    h.append((64 - (10 + h.size() + 1) % 64) % 64, ' ');
    h.push_back('\n');
    std::string b = std::string("\x93NUMPY\x01\x00", 8) + char(h.size() & 0xff) + char(h.size() >> 8) + h +
                    std::string(64, '\0');  // 16 float zeros
    put(dir + "/" + name, b);
    return read_as("npy", dir + "/" + name);
  };
  // 10^12 elements (below the 2^40 voxel limit): 4 TB promised, 4 bytes present.
  Outcome o = npy("tera.npy", "(10000, 10000, 10000)");
  EXPECT_EQ(o.status, Status::format);
  EXPECT_NE(o.message.find("header promises 4000000000000 bytes, file has 64"), std::string::npos) << o.message;
  o = npy("peta.npy", "(100000, 100000, 100000)");
  EXPECT_EQ(o.status, Status::format);
  EXPECT_NE(o.message.find("more than 2^40 elements"), std::string::npos) << o.message;
  o = npy("overflow.npy", "(18446744073709551615, 18446744073709551615)");
  EXPECT_EQ(o.status, Status::format);
  EXPECT_NE(o.message.find("absurdly large"), std::string::npos) << o.message;
  o = npy("zero.npy", "(0, 4, 4)");
  EXPECT_EQ(o.status, Status::bad_dims);
  EXPECT_NE(o.message.find("have a zero"), std::string::npos) << o.message;
  o = npy("one_dim.npy", "(4,)");
  EXPECT_EQ(o.status, Status::bad_dims);
  EXPECT_NE(o.message.find("has 1 dimensions"), std::string::npos) << o.message;
}

TEST(AbsurdHeaders, NrrdClaimingTrillionsOfSamplesIsRefusedWithoutAllocating) {
  const std::string dir = scratch("absurd_nrrd");
  // Raw and ascii alike: 10^12 samples promised, a handful present.
  for (const char* enc : {"raw", "ascii"}) {
    const std::string f = dir + "/tera_" + enc + ".nrrd";
    put(f, std::string("NRRD0004\ntype: float\ndimension: 3\nsizes: 10000 10000 10000\nendian: little\nencoding: ") +
               enc + "\n\n0.5 0.5 0.5 0.5\n");
    const Outcome o = read_as("nrrd", f);
    EXPECT_EQ(o.status, Status::format) << enc << ": " << o.message;
    EXPECT_NE(o.message.find(f), std::string::npos) << o.message;
  }
  const std::string f = dir + "/negative.nrrd";
  put(f, "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 -4 4\nendian: little\nencoding: raw\n\n");
  const Outcome o = read_as("nrrd", f);
  EXPECT_NE(o.status, Status::ok);
  EXPECT_NE(o.message.find(f), std::string::npos) << o.message;
}

TEST(AbsurdHeaders, PcdBodyThatPclWouldReadAsHeaderIsRefused) {
  // PCL's header loop reads on past DATA while lines start with a header keyword: a binary body
  // beginning with "COLUMNS" redefined the fields, and PCL read past its arrays (a crash found by
  // fuzzing; tests/reliability/fuzz/regressions/pcd/pcl-body-read-as-header).
  const std::string dir = scratch("pcd_body_header");
  const std::string header = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n";
  for (const std::string body : {"COLUMNS a b c d e f g h i j k l\n", "\n# c\nSIZE 8 8 8 8 8 8 8 8 8 8 8 8\n"}) {
    std::string data = body;
    data.resize(24, '\0');
    put(dir + "/body.pcd", header + data);
    const Outcome o = read_as("pcd", dir + "/body.pcd");
    EXPECT_EQ(o.status, Status::format) << o.message;
    EXPECT_NE(o.message.find("which PCL would read as a header line"), std::string::npos) << o.message;
  }
  // A body that starts otherwise is data: the same file with other bytes reads.
  put(dir + "/fine.pcd", header + std::string(24, '\0'));
  EXPECT_EQ(read_as("pcd", dir + "/fine.pcd").status, Status::ok) << read_as("pcd", dir + "/fine.pcd").message;
}

TEST(AbsurdHeaders, PcdBtAndGraphCountsBeyondTheFileAreRefused) {
  const std::string dir = scratch("absurd_other");
  std::string pcd = slurp(kData + "/office1.pcd");
  {
    const std::size_t w = pcd.find("WIDTH 640"), p = pcd.find("POINTS 307200");
    ASSERT_NE(w, std::string::npos);
    ASSERT_NE(p, std::string::npos);
    std::string c = pcd;
    c.replace(p, 13, "POINTS 999999999999");
    c.replace(w, 9, "WIDTH 999999999999");  // WIDTH x HEIGHT != POINTS: refused at the header
    put(dir + "/huge.pcd", c);
    const Outcome o = read_as("pcd", dir + "/huge.pcd");
    EXPECT_EQ(o.status, Status::format) << o.message;
  }
  std::string bt = slurp(kData + "/geb079.bt");
  {
    const std::size_t s = bt.find("size ");
    ASSERT_NE(s, std::string::npos);
    const std::size_t e = bt.find('\n', s);
    bt.replace(s, e - s, "size 1000000000000");
    put(dir + "/huge.bt", bt);
    const Outcome o = read_as("bt", dir + "/huge.bt");
    EXPECT_EQ(o.status, Status::format) << o.message;
    EXPECT_NE(o.message.find("promises 1000000000000 nodes"), std::string::npos) << o.message;
  }
  std::string graph = slurp(kData + "/spherical_scan.graph");
  {
    const std::uint32_t huge = 0xffffffffu;
    std::memcpy(&graph[4], &huge, 4);  // the first node's point count
    put(dir + "/huge.graph", graph);
    const Outcome o = read_as("graph", dir + "/huge.graph");
    EXPECT_EQ(o.status, Status::format) << o.message;
    EXPECT_NE(o.message.find("truncated in points"), std::string::npos) << o.message;
  }
}
