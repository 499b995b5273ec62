// The bad-input table of docs/reliability.md, file rows: truncated, corrupted, wrong-magic and
// absurd-header files of every format give a pinned status and a message naming the file, never
// a crash and never an attempt to allocate what the header claims.
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <sstream>
#include <thread>

#include "occseg/error.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/octomap_file.hpp"
#include "occseg/octomap_tree.hpp"
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

template <class F>
Status status_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.status();
  }
  return Status::ok;
}

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

TEST(AbsurdHeaders, PcdHeaderKeysGivenTwiceAreRefused) {
  // PCL acts on each header line as it comes. Fields listed again after WIDTH, one with COUNT 0
  // (which PCL drops), left rows of 6 x 13 bytes over points of 12, and pcl::fromPCLPointCloud2
  // read past the data (a heap overflow); a first POINTS line of 3333333333 made PCL allocate
  // 40 GB before a second one said 24 (both found by fuzz_pcd;
  // tests/reliability/fuzz/regressions/pcd/fields-again-after-width, points-twice).
  const std::string dir = scratch("pcd_keys_twice");
  const std::string fields = "FIELDS x y z i\nSIZE 4 4 4 1\nTYPE F F F U\n";
  const std::string body(24 * 13, '\0');
  const struct {
    std::string name, text, key;
    int line;
  } cases[] = {
      {"again.pcd", "VERSION 0.7\n" + fields + "COUNT 1 1 1 1\nWIDTH 6\nHEIGHT 4\n" + fields +
                        "COUNT 1 1 1 0\nPOINTS 24\nDATA binary\n" + body, "FIELDS", 8},
      {"points.pcd", "VERSION 0.7\n" + fields + "COUNT 1 1 1 1\nPOINTS 3333333333\nWIDTH 6\nHEIGHT 4\nPOINTS 24\n"
                         "DATA binary\n" + body, "POINTS", 9},
  };
  for (const auto& c : cases) {
    put(dir + "/" + c.name, c.text);
    const Outcome o = read_as("pcd", dir + "/" + c.name);
    EXPECT_EQ(o.status, Status::format) << c.name << ": " << o.message;
    EXPECT_NE(o.message.find("header field " + c.key + " is given twice (line " + std::to_string(c.line) + ")"),
              std::string::npos) << o.message;
    EXPECT_NE(o.message.find(dir + "/" + c.name), std::string::npos) << o.message;
  }
  // Each key once: the file reads.
  put(dir + "/once.pcd", "VERSION 0.7\n" + fields + "COUNT 1 1 1 1\nWIDTH 6\nHEIGHT 4\nPOINTS 24\nDATA binary\n" + body);
  EXPECT_EQ(read_as("pcd", dir + "/once.pcd").status, Status::ok) << read_as("pcd", dir + "/once.pcd").message;
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
    // PCL holds the counts in 32 bits: a larger one is refused before any product can wrap.
    EXPECT_NE(o.message.find("is not a count (0 to 4294967295)"), std::string::npos) << o.message;
  }
  std::string bt = slurp(kData + "/geb079.bt");
  {
    const std::size_t s = bt.find("size ");
    ASSERT_NE(s, std::string::npos);
    const std::size_t e = bt.find('\n', s);
    // OctoMap reads the size as a 32-bit unsigned: the largest count it can be promised.
    bt.replace(s, e - s, "size 4000000000");
    put(dir + "/huge.bt", bt);
    const Outcome o = read_as("bt", dir + "/huge.bt");
    EXPECT_EQ(o.status, Status::format) << o.message;
    EXPECT_NE(o.message.find("promises 4000000000 nodes"), std::string::npos) << o.message;
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

// ---- Hostile files: what occseg checks must be what the library reads (issue 24) -----------

namespace {

// A small OcTree written by OctoMap: header words and tree bytes apart, to rebuild files with
// other headers around the same tree bytes.
struct TreeBytes {
  std::string body;  // the tree data after the header
  unsigned size = 0;
};
TreeBytes tree_bytes(bool binary) {
  octomap::OcTree t(0.1);
  for (int i = -5; i <= 5; ++i) t.updateNode(octomap::point3d(0.1f * i, 0.05f, 0.3f), i % 2 == 0);
  t.updateInnerOccupancy();
  std::ostringstream o;
  if (binary) t.writeBinaryConst(o);
  else t.write(o);
  const std::string s = o.str();
  const std::size_t data = s.find("\ndata\n");
  return {s.substr(data + 6), static_cast<unsigned>(t.size())};
}

// What OctoMap itself makes of a file: the tree (nullptr when its reader refuses it).
std::unique_ptr<octomap::AbstractOcTree> octomap_reads(const std::string& bytes, bool binary) {
  std::istringstream in(bytes);
  if (binary) {
    auto t = std::make_unique<octomap::OcTree>(0.1);
    if (!t->readBinary(in)) return nullptr;
    return t;
  }
  return std::unique_ptr<octomap::AbstractOcTree>(octomap::AbstractOcTree::read(in));
}

// The file with the OctoMap payload of 0xff bytes of issue 24: liboctomap stops its header at the
// word "data" in the middle of line 2, reads the '#' line as the tree and recurses until the stack
// overflows; a line-by-line check found the second, harmless header and passed the file.
std::string hostile_tree_file(bool binary) {
  const std::string first = binary ? "# Octomap OcTree binary file\n" : "# Octomap OcTree file\n";
  const std::string harmless = binary ? std::string("id OcTree\nsize 1\nres 0.1\ndata\n") + std::string(2, '\0')
                                      : std::string("id OcTree\nsize 1\nres 0.1\ndata\n") + std::string(5, '\0');
  return first + "id OcTree size 5 res 0.1 data\n#" + std::string(200000, '\xff') + "\n" + harmless;
}

}  // namespace

TEST(HostileOctomap, DataWordInTheMiddleOfALineNeverReachesOctomapUnchecked) {
  const std::string dir = scratch("hostile_octomap");
  for (const bool binary : {true, false}) {
    const std::string f = dir + (binary ? "/hostile.bt" : "/hostile.ot");
    put(f, hostile_tree_file(binary));
    // In a child: without the check the reader does not return (stack overflow in liboctomap).
    const int rc = in_child([&] {
      const Outcome o = read_as(binary ? "bt" : "ot", f);
      const bool named = o.message.find(f) != std::string::npos;
      const bool why = o.message.find(binary ? "deeper than 16 levels" : "is not finite") != std::string::npos;
      return o.status == Status::format && named && why ? 0 : 1;
    });
    EXPECT_EQ(rc, 0) << f << (rc > 128 ? ": the reader crashed" : ": wrong status or message");
  }
}

TEST(HostileOctomap, EveryHeaderLayoutOctomapAcceptsGivesOctomapsTreeAndNoOther) {
  // Header variants around valid tree bytes; occseg must accept exactly the files OctoMap's own
  // reader accepts and give the map of the tree OctoMap builds from them.
  const std::string dir = scratch("octomap_headers");
  for (const bool binary : {true, false}) {
    const TreeBytes t = tree_bytes(binary);
    const std::string n = std::to_string(t.size);
    const std::vector<std::string> headers = {
        "# c\nid OcTree\nsize " + n + "\nres 0.1\ndata\n",
        "id OcTree size " + n + " res 0.1 data\n",                      // all on one line
        "id\nOcTree\nsize\n" + n + "\nres\n0.1\ndata\n",                  // values on the next line
        "id OcTree\nsize " + n + "\nres 0.1\ndata and more words\n",     // the rest of the data line
        "id OcTree #size 99\nsize " + n + "\nres 0.1\ndata\n",           // '#' word: rest of line
        "id OcTree\nfoo data\nsize " + n + "\nres 0.1\ndata\n",          // unknown word: rest of line
        "id OcTree\r\nsize " + n + "\r\nres 0.1\r\ndata\r\n",            // CRLF
        "id\tOcTree\tsize\t" + n + "\tres\t0.1\tdata\n",                  // tabs
        "id OcTree\nsize " + n + "\nres 0.1\ndatadata\ndata\n",          // "data" inside a word
        "id OcTree\nsize " + n + "\nres 0.1 data\n",                     // "data" after a value
        "id OcTree\nsize " + n + "\nres 0.1\n",                          // no "data"
        "id OcTree\nsize " + n + "\nres abc\ndata\n",                    // a value OctoMap cannot read
        "size " + n + "\nres 0.1\ndata\n",                               // no id
        "id OcTree\nsize -1\nres 0.1\ndata\n",                           // wraps to 2^32 - 1
        "id OcTree\nsize " + n + "\nres 0\ndata\n",                      // res <= 0
    };
    for (std::size_t i = 0; i < headers.size(); ++i) {
      const std::string bytes =
          (binary ? "# Octomap OcTree binary file\n" : "# Octomap OcTree file\n") + headers[i] + t.body;
      const std::string f = dir + "/h" + std::to_string(i) + (binary ? ".bt" : ".ot");
      put(f, bytes);
      const std::unique_ptr<octomap::AbstractOcTree> theirs = octomap_reads(bytes, binary);
      // readBinary compares the tree with the header's size; AbstractOcTree::read (.ot) does not,
      // occseg does for both (a size that does not match its tree is a corrupt file).
      const bool lying_size = headers[i].find("size -1") != std::string::npos;
      const bool octomap_ok = theirs && theirs->size() == t.size && !lying_size;
      std::string msg;
      Grid mine;
      Status s = Status::ok;
      try {
        mine = read_octree_file(f);
      } catch (const Error& e) {
        s = e.status();
        msg = e.what();
      }
      EXPECT_EQ(s == Status::ok, octomap_ok) << "header " << i << " of " << f << ": " << msg;
      if (s != Status::ok) {
        EXPECT_EQ(s, Status::format) << msg;
        EXPECT_NE(msg.find(f), std::string::npos) << msg;
        continue;
      }
      if (!octomap_ok) continue;
      const Grid expect = grid_from_octree(*dynamic_cast<const octomap::OcTree*>(theirs.get()));
      EXPECT_TRUE(mine.dims == expect.dims) << "header " << i;
      EXPECT_EQ(mine.origin, expect.origin) << "header " << i;
      EXPECT_EQ(mine.p, expect.p) << "header " << i;
    }
  }
}

TEST(HostileOctomap, ScanGraphDoublesBeyondTheFloatRangeAreRefused) {
  // OctoMap reads the graph's doubles into floats: a finite value beyond the float range is an
  // undefined conversion there (in practice infinity: the point silently became a hole).
  const std::string dir = scratch("graph_float_range");
  const std::string graph = slurp(kData + "/spherical_scan.graph");
  for (const std::size_t at : {std::size_t(4 + 4 + 4), graph.size() - 4 - 4 - 8 * 4 - 4 - 8 * 3}) {
    std::string c = graph;  // the first coordinate of the first point, then the pose's x
    const double huge = 1e300;
    std::memcpy(&c[at], &huge, 8);
    const std::string f = dir + "/far.graph";
    put(f, c);
    const Outcome o = read_as("graph", f);
    EXPECT_EQ(o.status, Status::format) << at << ": " << o.message;
    EXPECT_NE(o.message.find("beyond the range of a float"), std::string::npos) << o.message;
  }
}

namespace {

// An .npy file (format 1.0) with `dict` as its header and 256 zero bytes of data.
std::string npy_with_header(const std::string& dict) {
  std::string h = dict;
  h.append((64 - (10 + h.size() + 1) % 64) % 64, ' ');
  h.push_back('\n');
  return std::string("\x93NUMPY\x01\x00", 8) + char(h.size() & 0xff) + char(h.size() >> 8) + h + std::string(256, '\0');
}

}  // namespace

TEST(HostileNpy, HeadersNumpyRefusesOrReadsOtherwiseAreRefused) {
  // The header is a Python dict literal that NumPy evaluates (ast.literal_eval): a repeated key
  // keeps its last value, text in a string value is no key, "(8)" is an int. A text search for
  // "'shape'" read all of these, with a shape NumPy would not give or for a file it refuses.
  const std::string dir = scratch("hostile_npy");
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (2,2,2), 'shape': (4,4,4)}", "'shape' appears twice"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (4,4,4), 'shape': (2,2,2)}", "'shape' appears twice"},
      {"{'descr': '<f4', 'descr': '<f8', 'fortran_order': False, 'shape': (2,2,2)}", "'descr' appears twice"},
      {"{'descr': '<f4', 'fortran_order': False, 'note': \"'shape': (4,4,4)\", 'shape': (2,2,2)}",
       "header key 'note' is not one of"},
      {"{'descr': \"<f4', 'shape': (4,4,4), 'x': '\", 'fortran_order': False, 'shape': (2,2,2)}",
       "dtype '<f4', 'shape': (4,4,4), 'x': '' is not supported"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (64)}", "an integer in parentheses, not a tuple"},
      {"{'descr': '<f4', 'fortran_order': 0, 'shape': (4,4,4)}", "'fortran_order' is not True or False"},
      {"{'descr': '<f4', 'fortran_order': False}", "header has no 'shape'"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (4,4,4)} 'shape': (2,2,2)", "text after its dict"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (4,4,-4)}", "negative"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (4,4,4),, }", "a dict key is not a quoted string"},
      {"{'descr': '<f4' '<f8', 'fortran_order': False, 'shape': (4,4,4)}", "two adjacent strings"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 4.0)}", "not a plain decimal integer"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 04)}", "leading zero"},
      {"{'descr': '\\x1b[31m', 'fortran_order': False, 'shape': (4,4,4)}", "has an escape sequence"},
  };
  for (std::size_t i = 0; i < refused.size(); ++i) {
    const std::string f = dir + "/r" + std::to_string(i) + ".npy";
    put(f, npy_with_header(refused[i].first));
    const Outcome o = read_as("npy", f);
    EXPECT_EQ(o.status, Status::format) << refused[i].first << ": " << o.message;
    EXPECT_NE(o.message.find(refused[i].second), std::string::npos) << refused[i].first << ": " << o.message;
    EXPECT_NE(o.message.find(f), std::string::npos) << o.message;
  }
  // What NumPy reads, occseg reads with the same shape: either quote, comments, whitespace and a
  // trailing comma anywhere Python allows them.
  const std::vector<std::string> read = {
      "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 4), }",
      "{\"descr\": \"<f4\", \"fortran_order\": False, \"shape\": (4,4,4)}",
      "{'shape': (4, 4, 4), 'fortran_order': False, 'descr': '<f4'}",
      "  {'descr': '<f4', # a comment\n 'fortran_order': False,\n 'shape': (4,\n 4, 4,)}  # after",
  };
  for (std::size_t i = 0; i < read.size(); ++i) {
    const std::string f = dir + "/a" + std::to_string(i) + ".npy";
    put(f, npy_with_header(read[i]));
    const NpyArray a = read_npy(f);
    EXPECT_EQ(a.shape, (std::vector<std::size_t>{4, 4, 4})) << read[i];
  }
}

TEST(HostileMessages, FileBytesQuotedInMessagesAreEscapedAndCapped) {
  // A garbage header once came back in the message byte for byte: terminal control sequences
  // (here: set the window title, red text) reached whoever printed it. Every reader quotes file
  // bytes through printable(): \xNN for what is not printable ASCII, and at most a few dozen.
  const std::string dir = scratch("hostile_messages");
  const std::string evil = std::string("\x1b]0;owned\x07\x1b[31m\xff\xfe") + std::string(5000, 'A');
  const std::string pcd_head = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  const std::vector<std::pair<std::string, std::string>> files = {
      {"pcd", pcd_head + evil + "\nDATA ascii\n"},
      {"pcd", pcd_head + "WIDTH " + evil + "\nDATA ascii\n"},
      {"pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F " + evil + "\nCOUNT 1 1 1\nDATA ascii\n"},
      {"npy", npy_with_header("{'descr': '" + evil + "', 'fortran_order': False, 'shape': (4,4,4)}")},
      {"npy", npy_with_header("{'" + evil + "': '<f4', 'fortran_order': False, 'shape': (4,4,4)}")},
      {"npy", npy_with_header("{'descr': '<f4', 'fortran_order': False, 'shape': (4,4,4)} " + evil)},
      {"nrrd", "NRRD0004\n" + evil + "\n\n"},
      {"nrrd", "NRRD0004\n" + evil + ": x\n\n"},
      {"nrrd", "NRRD0004\ntype: " + evil + "\n\n"},
      {"nrrd", "NRRD0004\ntype: float\ndimension: 3\nspace: " + evil + "\n\n"},
      {"nrrd", "NRRD" + evil + "\n\n"},
      {"bt", "# Octomap OcTree binary file\nid " + evil + "\nsize 0\nres 0.1\ndata\n"},
      {"ot", "# Octomap OcTree file\nid " + evil + "\nsize 0\nres 0.1\ndata\n"},
  };
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::string f = dir + "/m" + std::to_string(i) + "." + files[i].first;
    put(f, files[i].second);
    const Outcome o = read_as(files[i].first, f);
    ASSERT_NE(o.status, Status::ok) << f;
    std::string raw;
    for (const char c : o.message)
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) raw += c;
    EXPECT_TRUE(raw.empty()) << f << ": the message carries raw bytes";
    EXPECT_NE(o.message.find("\\x1b"), std::string::npos) << f << ": " << o.message;
    EXPECT_LT(o.message.size(), f.size() + 300) << f << ": " << o.message;
  }
}

namespace {

// A FIFO whose first reader gets `first` and every later reader `later`: a file that changes
// between two reads, deterministically. Stopped (and joined) by the destructor.
class ChangingFile {
 public:
  ChangingFile(const std::string& path, std::string first, std::string later) : path_(path) {
    ::unlink(path.c_str());
    if (::mkfifo(path.c_str(), 0600) != 0) throw std::runtime_error("mkfifo failed");
    ::signal(SIGPIPE, SIG_IGN);  // a reader may close before the content is written
    // The writer never blocks: it polls for a reader and writes without blocking, so the
    // destructor can always stop it (a blocked open or write would hang the test).
    writer_ = std::thread([this, first = std::move(first), later = std::move(later)] {
      for (int k = 0; !stop_; ++k) {
        int fd = -1;
        while (!stop_ && (fd = ::open(path_.c_str(), O_WRONLY | O_NONBLOCK)) < 0) pause();
        if (fd < 0) return;
        const std::string& b = k == 0 ? first : later;
        for (std::size_t done = 0; done < b.size() && !stop_;) {
          const ssize_t n = ::write(fd, b.data() + done, b.size() - done);
          if (n > 0) done += static_cast<std::size_t>(n);
          else if (n < 0 && errno == EAGAIN) pause();
          else break;  // the reader closed (EPIPE)
        }
        ::close(fd);
        // The next content is for the next reader: wait until this one has closed the FIFO
        // (a non-blocking open for writing fails with ENXIO once no reader holds it).
        for (;;) {
          const int probe = ::open(path_.c_str(), O_WRONLY | O_NONBLOCK);
          if (probe < 0) break;
          ::close(probe);
          if (stop_) return;
          pause();
        }
      }
    });
  }
  ~ChangingFile() {
    stop_ = true;
    writer_.join();
    ::unlink(path_.c_str());
  }

 private:
  static void pause() { std::this_thread::sleep_for(std::chrono::milliseconds(1)); }

  std::string path_;
  std::atomic<bool> stop_{false};
  std::thread writer_;
};

}  // namespace

TEST(HostileFiles, TheLibraryReadsTheBytesThatWereCheckedNotTheFileAgain) {
  // The .pcd and .graph readers checked the file and then handed its path to PCL or OctoMap,
  // which opened it again: a file changed in between was read unchecked. Here the second read
  // gets another valid file; the map must still be the map of the first, checked, bytes.
  const std::string dir = scratch("changing_file");
  ScanOptions o;
  o.voxel_size = 0.1;
  o.bbox = Box{{-2, -2, -1}, {2, 2, 3}};
  o.threads = 1;
  const std::string head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                           "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n";
  const std::string pcd_a = head + "0.5 0.5 1.5\n-0.5 0.2 2.5\n", pcd_b = head + "1.5 -1.5 0.5\n1 1 1\n";
  put(dir + "/a.pcd", pcd_a);
  const Grid expect_pcd = read_pcd(dir + "/a.pcd", o);
  {
    // A pipe is no longer read at all (only regular files are: BadFiles.Fifos...); a file that
    // changes between two reads would now have to be a regular file rewritten in between.
    ChangingFile f(dir + "/changing.pcd", pcd_a, pcd_b);
    EXPECT_EQ(status_of([&] { read_pcd(dir + "/changing.pcd", o); }), Status::io);
  }
  std::string graph_a = slurp(kData + "/spherical_scan.graph"), graph_b = graph_a;
  const double moved = 0.7;
  std::memcpy(&graph_b[graph_b.size() - 4 - 4 - 32 - 4 - 24], &moved, 8);  // the node's pose x
  put(dir + "/a.graph", graph_a);
  const Grid expect_graph = read_scan_graph(dir + "/a.graph", o);
  {
    ChangingFile f(dir + "/changing.graph", graph_a, graph_b);
    EXPECT_EQ(status_of([&] { read_scan_graph(dir + "/changing.graph", o); }), Status::io);
  }
}
