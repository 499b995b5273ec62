// Output that cannot be written: an unwritable directory, a missing parent, a full disk or
// quota (RLIMIT_FSIZE). Each is OCCSEG_EIO naming the file, and leaves no partial file, no
// temporary file and no mismatched labels.npy / segments.json pair; the same for the command.
#include <fcntl.h>
#include <signal.h>

#include <cstring>

#include "occseg/error.hpp"
#include "occseg/file_write.hpp"
#include "support.hpp"

using namespace occseg::reliability;

namespace {

// A result with many segments (a 3D checkerboard of 2^3 cells): segments.json is much larger
// than labels.npy, so a file-size limit can fail the second file after the first succeeded.
struct Segmented {
  occseg_map* map = nullptr;
  occseg_result* result = nullptr;
  explicit Segmented(std::size_t n = 16) {
    std::vector<float> p(n * n * n);
    for (std::size_t z = 0; z < n; ++z)
      for (std::size_t y = 0; y < n; ++y)
        for (std::size_t x = 0; x < n; ++x) p[x + n * (y + n * z)] = ((x / 2 + y / 2 + z / 2) % 2) ? 0.95f : 0.05f;
    const std::size_t d[3] = {n, n, n};
    EXPECT_EQ(occseg_map_from_buffer(&map, p.data(), OCCSEG_F32, d, nullptr, 1.0), OCCSEG_OK);
    EXPECT_EQ(occseg_segment(&result, map, nullptr), OCCSEG_OK) << occseg_last_error();
  }
  ~Segmented() {
    occseg_result_free(result);
    occseg_map_free(map);
  }
};

// Runs `body` in a child limited to `bytes` per written file (a full disk or quota), as an
// unprivileged user when `drop` is set. SIGXFSZ is ignored so that write() fails with EFBIG.
int limited(rlim_t bytes, bool drop, const std::function<int()>& body) {
  return in_child([&] {
    ::signal(SIGXFSZ, SIG_IGN);
    if (bytes) {
      const rlimit r{bytes, bytes};
      if (::setrlimit(RLIMIT_FSIZE, &r) != 0) return 90;
    }
    if (drop && ::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) return 91;
    return body();
  });
}

int expect_eio(int rc, const char* text) {
  if (rc != OCCSEG_EIO) return 10;
  if (!std::strstr(occseg_last_error(), text)) {
    std::fprintf(stderr, "last error '%s' lacks '%s'\n", occseg_last_error(), text);
    return 11;
  }
  return 0;
}

}  // namespace

TEST(Output, ResultWriteIntoAnUnwritableDirectoryLeavesNothing) {
  Segmented s;
  const std::string dir = scratch("unwritable");
  fs::permissions(dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                           fs::perms::others_read | fs::perms::others_exec);  // 0755, owned by us
  // As root permissions do not apply, so the writer drops to an unprivileged user.
  EXPECT_EQ(limited(0, true, [&] { return expect_eio(occseg_result_write(s.result, dir.c_str()), "Permission denied"); }),
            0);
  EXPECT_EQ(limited(0, true, [&] { return expect_eio(occseg_map_write(s.map, (dir + "/m.npy").c_str()), "m.npy"); }), 0);
  EXPECT_TRUE(entries(dir).empty());
}

TEST(Output, ResultWriteBelowAMissingParentOrAFileFails) {
  Segmented s;
  const std::string dir = scratch("no_parent");
  EXPECT_STATUS(occseg_result_write(s.result, (dir + "/a/b").c_str()), OCCSEG_EIO, "cannot create");
  put(dir + "/file", "x");
  EXPECT_STATUS(occseg_result_write(s.result, (dir + "/file").c_str()), OCCSEG_EIO, "is not a directory");
  EXPECT_STATUS(occseg_result_write(s.result, (dir + "/file/sub").c_str()), OCCSEG_EIO, "Not a directory");
  EXPECT_EQ(entries(dir), std::vector<std::string>{"file"});
}

TEST(Output, AFullDiskDuringLabelsLeavesNoFile) {
  Segmented s(32);  // labels.npy: 128 + 4 * 32^3 bytes
  const std::string dir = scratch("full_labels");
  EXPECT_EQ(limited(4096, false, [&] { return expect_eio(occseg_result_write(s.result, dir.c_str()), "labels.npy"); }), 0);
  EXPECT_TRUE(entries(dir).empty()) << entries(dir).size();
}

TEST(Output, AFullDiskDuringSegmentsJsonRemovesTheLabelsToo) {
  Segmented s(16);  // labels.npy: 128 + 4 * 16^3 = 16512 bytes; segments.json: 512 segments
  const std::string dir = scratch("full_json");
  ASSERT_EQ(occseg_result_write(s.result, dir.c_str()), OCCSEG_OK);
  const std::uintmax_t labels = fs::file_size(dir + "/labels.npy"), json = fs::file_size(dir + "/segments.json");
  ASSERT_GT(json, labels + 1000);  // else this test would not fail where it means to
  fs::remove_all(dir);
  fs::create_directories(dir);
  const rlim_t limit = static_cast<rlim_t>(labels + 100);
  EXPECT_EQ(limited(limit, false, [&] { return expect_eio(occseg_result_write(s.result, dir.c_str()), "segments.json"); }),
            0);
  EXPECT_TRUE(entries(dir).empty()) << "left: " << (entries(dir).empty() ? "" : entries(dir)[0]);
}

TEST(Output, AtomicWriteKeepsTheOldFileWhenTheNewOneFails) {
  const std::string dir = scratch("keep_old");
  const std::string f = dir + "/out.bin";
  put(f, "old content");
  const int rc = limited(1000, false, [&] {
    try {
      occseg::write_file_atomically(f, [](std::ostream& o) { o << std::string(5000, 'n'); });
    } catch (const occseg::Error& e) {
      return e.status() == occseg::Status::io && std::strstr(e.what(), "out.bin") ? 0 : 1;
    }
    return 2;
  });
  EXPECT_EQ(rc, 0);
  EXPECT_EQ(slurp(f), "old content");
  EXPECT_EQ(entries(dir), std::vector<std::string>{"out.bin"});
}

TEST(Output, TheCommandLeavesNothingWhenTheDiskFillsOrTheDirectoryIsUnwritable) {
  Segmented s(24);
  const std::string dir = scratch("cli");
  const std::string in = dir + "/map.npy";
  ASSERT_EQ(occseg_map_write(s.map, in.c_str()), OCCSEG_OK);
  auto run_cli = [&](const std::string& out, rlim_t limit, bool drop) {
    return limited(limit, drop, [&] {
      // The unprivileged user may be unable to reach the build tree at all (a private
      // checkout): then this case cannot be run here.
      if (::access(OCCSEG_CLI, X_OK) != 0 || ::access(in.c_str(), R_OK) != 0) return 96;
      const int null = ::open("/dev/null", O_WRONLY);
      ::dup2(null, 1);
      ::dup2(null, 2);
      ::execl(OCCSEG_CLI, OCCSEG_CLI, "segment", in.c_str(), "--out", out.c_str(), static_cast<char*>(nullptr));
      return 97;
    });
  };
  ASSERT_EQ(run_cli(dir + "/ok", 0, false), 0);  // the command works here at all
  const std::vector<std::string> written = entries(dir + "/ok");
  ASSERT_GE(written.size(), 3u);
  EXPECT_EQ(written.front(), "labels.npy");
  EXPECT_EQ(written.back(), "segments.json");
  // labels.npy and labels.nrrd take 55 kB each: fail at the first, the second, a later file.
  for (rlim_t limit : {rlim_t(1000), rlim_t(60000), rlim_t(120000)}) {
    const std::string out = dir + "/full" + std::to_string(limit);
    EXPECT_EQ(run_cli(out, limit, false), 2) << limit;
    EXPECT_TRUE(entries(out).empty()) << limit << ": " << entries(out).size() << " files left";
  }
  const std::string locked = dir + "/locked";
  fs::create_directories(locked);
  const int rc = run_cli(locked + "/out", 0, true);
  if (rc == 96) GTEST_SKIP() << "an unprivileged user cannot reach " << OCCSEG_CLI;
  EXPECT_EQ(rc, 2);
  EXPECT_FALSE(fs::exists(locked + "/out"));
}
