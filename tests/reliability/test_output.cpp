// Output that cannot be written: an unwritable directory, a missing parent, a full disk or
// quota (RLIMIT_FSIZE), a rename that fails. Each is OCCSEG_EIO naming the file, and leaves no
// partial file, no temporary file and no mismatched labels.npy / segments.json pair, and a
// failed rewrite leaves the earlier files exactly as they were; the same for the command.
// Temporaries never follow a planted symbolic link.
#include <algorithm>
#include <fcntl.h>
#include <linux/fs.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/stat.h>

#include <cstring>
#include <map>

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
    // The object rules off: they would make the checkerboard's small cells one object.
    occseg_params* params = nullptr;
    EXPECT_EQ(occseg_params_create(&params), OCCSEG_OK);
    for (const char* name : {"object_gap", "min_object_voxels", "min_pocket_voxels"})
      EXPECT_EQ(occseg_params_set(params, name, "0"), OCCSEG_OK);
    EXPECT_EQ(occseg_segment(&result, map, params), OCCSEG_OK) << occseg_last_error();
    occseg_params_free(params);
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
      ::execl(OCCSEG_CLI, OCCSEG_CLI, "segment", in.c_str(), "--out", out.c_str(), "--outputs", "all", "--param",
              "object_gap=0", "--param", "min_object_voxels=0", "--param", "min_pocket_voxels=0",
              static_cast<char*>(nullptr));  // as Segmented
      return 97;
    });
  };
  ASSERT_EQ(run_cli(dir + "/ok", 0, false), 0);  // the command works here at all
  const std::vector<std::string> written = entries(dir + "/ok");
  ASSERT_GE(written.size(), 3u);
  EXPECT_EQ(written.front(), "labels.npy");
  EXPECT_NE(std::find(written.begin(), written.end(), "segments.json"), written.end());
  // (--outputs all: labels.nrrd (gzip), segments.json, segmentation.png, scene.png, labels.npy of
  // 55 kB, segments.ot, segments.ply.)
  // Fail at an early, a middle and a late file.
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

namespace {

// Writes as a new-file-creating program would see it: the permission bits of `path`.
unsigned mode_of(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 ? static_cast<unsigned>(st.st_mode & 07777) : 0u;
}

bool is_regular(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// Sets or clears the immutable attribute (as chattr +i / -i); false where this file system or
// this user cannot (it needs CAP_LINUX_IMMUTABLE).
bool set_immutable(const std::string& path, bool on) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  int flags = 0;
  bool ok = ::ioctl(fd, FS_IOC_GETFLAGS, &flags) == 0;
  flags = on ? (flags | FS_IMMUTABLE_FL) : (flags & ~FS_IMMUTABLE_FL);
  ok = ok && ::ioctl(fd, FS_IOC_SETFLAGS, &flags) == 0;
  ::close(fd);
  return ok;
}

// Runs the command `occseg segment IN --out OUT` in a child limited to `bytes` per written
// file, with SIGXFSZ at its default action (as a shell's `ulimit -f` leaves it), stderr to
// `err`. Returns the exit status (128 + signal when a signal ended it).
int run_cli_sigxfsz_default(const std::string& in, const std::string& out, rlim_t bytes, const std::string& err) {
  return in_child([&] {
    ::signal(SIGXFSZ, SIG_DFL);
    const rlimit r{bytes, bytes};
    if (::setrlimit(RLIMIT_FSIZE, &r) != 0) return 90;
    const int null = ::open("/dev/null", O_WRONLY);
    const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(null, 1);
    ::dup2(e, 2);
      ::execl(OCCSEG_CLI, OCCSEG_CLI, "segment", in.c_str(), "--out", out.c_str(), "--outputs", "all", "--param",
              "object_gap=0", "--param", "min_object_voxels=0", "--param", "min_pocket_voxels=0",
              static_cast<char*>(nullptr));  // as Segmented
    return 97;
  });
}

std::map<std::string, std::string> contents(const std::string& dir) {
  std::map<std::string, std::string> m;
  for (const std::string& f : entries(dir)) m[f] = slurp(dir + "/" + f);
  return m;
}

}  // namespace

// A rewrite that fails (here: a file-size limit) leaves the earlier pair exactly as it was:
// until both new files are complete, no old file is touched.
TEST(Output, AFailedRewriteOfTheResultKeepsTheOldPairWhole) {
  Segmented first(16), second(20);  // second: labels.npy 32128 bytes, segments.json > 100 kB
  const std::string dir = scratch("rewrite");
  ASSERT_EQ(occseg_result_write(first.result, dir.c_str()), OCCSEG_OK);
  const auto old = contents(dir);
  ASSERT_EQ(old.size(), 2u);
  for (rlim_t limit : {rlim_t(4096), rlim_t(40000)}) {  // within labels.npy, within segments.json
    const char* failing = limit == 4096 ? "labels.npy" : "segments.json";
    EXPECT_EQ(limited(limit, false, [&] { return expect_eio(occseg_result_write(second.result, dir.c_str()), failing); }),
              0)
        << limit;
    EXPECT_TRUE(contents(dir) == old) << limit << ": the old pair changed; left: " << entries(dir).size() << " files";
  }
  ASSERT_EQ(occseg_result_write(second.result, dir.c_str()), OCCSEG_OK);  // and without a limit, it is replaced
  EXPECT_EQ(entries(dir), (std::vector<std::string>{"labels.npy", "segments.json"}));
  EXPECT_NE(slurp(dir + "/labels.npy"), old.at("labels.npy"));
}

// A symbolic link planted in a shared output folder under a name the writer might pick as its
// temporary must never be followed: the file it points to stays as it was. The names planted
// are those that a predictable scheme (PATH.tmp-PID-N, the scheme of an earlier version) gives.
// The new files get the mode of any newly created file, 0666 less the umask.
TEST(Output, TemporariesNeverFollowAPlantedLinkAndGetTheModeOfANewFile) {
  Segmented s(8);
  const std::string dir = scratch("planted");
  const std::string victim = scratch("planted_elsewhere") + "/victim";
  put(victim, "precious");
  const int rc = in_child([&] {
    for (const char* name : {"out.bin", "labels.npy", "segments.json"})
      for (int n = 0; n < 1024; ++n) {
        const std::string link = dir + "/" + name + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(n);
        if (::symlink(victim.c_str(), link.c_str()) != 0) return 20;
      }
    ::umask(027);
    occseg::write_file_atomically(dir + "/out.bin", [](std::ostream& o) { o << "new"; });
    return occseg_result_write(s.result, dir.c_str()) == OCCSEG_OK ? 0 : 21;
  });
  ASSERT_EQ(rc, 0);
  EXPECT_EQ(slurp(victim), "precious");
  for (const char* name : {"out.bin", "labels.npy", "segments.json"}) {
    EXPECT_TRUE(is_regular(dir + "/" + name)) << name << " is not a regular file (a link renamed into place?)";
    EXPECT_EQ(mode_of(dir + "/" + name), 0640u) << name;
  }
  EXPECT_EQ(slurp(dir + "/out.bin"), "new");
  EXPECT_EQ(entries(dir).size(), 3u + 3u * 1024u);  // the planted links, untouched, and nothing else
}

// A rename that fails in the middle of the final step (here: the old segments.json is
// immutable, so it cannot be replaced) puts back the files replaced before it.
TEST(Output, ARenameThatFailsHalfwayPutsTheOldFilesBack) {
  Segmented first(16), second(20);
  const std::string dir = scratch("halfway");
  ASSERT_EQ(occseg_result_write(first.result, dir.c_str()), OCCSEG_OK);
  const auto old = contents(dir);
  if (!set_immutable(dir + "/segments.json", true)) GTEST_SKIP() << "cannot make a file immutable here";
  const int rc = occseg_result_write(second.result, dir.c_str());
  const std::string message = occseg_last_error();
  set_immutable(dir + "/segments.json", false);
  EXPECT_EQ(rc, OCCSEG_EIO);
  EXPECT_NE(message.find("segments.json"), std::string::npos) << message;
  EXPECT_TRUE(contents(dir) == old) << "left: " << entries(dir).size() << " files; labels.npy "
                                    << (slurp(dir + "/labels.npy") == old.at("labels.npy") ? "old" : "not the old one");
  // The same through the helper: a new file added before the failing one is taken away again.
  {
    ASSERT_TRUE(set_immutable(dir + "/segments.json", true));
    occseg::StagedFiles files;
    files.stage(dir + "/labels.npy", [](std::ostream& o) { o << "new labels"; });
    files.stage(dir + "/added.txt", [](std::ostream& o) { o << "new file"; });
    files.stage(dir + "/segments.json", [](std::ostream& o) { o << "new json"; });
    EXPECT_THROW(files.commit(), occseg::Error);
    set_immutable(dir + "/segments.json", false);
  }
  EXPECT_TRUE(contents(dir) == old) << "left: " << entries(dir).size() << " files";
}

// Under a file-size limit (ulimit -f) with SIGXFSZ at its default action, as a shell leaves it,
// the command reports a write error naming the file (exit 2) instead of being killed by the
// signal (exit 153), and a failed re-run leaves the earlier run's files exactly as they were.
TEST(Output, TheCommandReportsAFileSizeLimitAndKeepsTheEarlierRun) {
  Segmented a(24), b(26);  // b: labels.npy and labels.nrrd of 70 kB, segments.json of over 300 kB
  const std::string dir = scratch("cli_rerun");
  const std::string in_a = dir + "/a.npy", in_b = dir + "/b.npy", out = dir + "/out", err = dir + "/err.txt";
  ASSERT_EQ(occseg_map_write(a.map, in_a.c_str()), OCCSEG_OK);
  ASSERT_EQ(occseg_map_write(b.map, in_b.c_str()), OCCSEG_OK);
  ASSERT_EQ(run_cli_sigxfsz_default(in_a, out, RLIM_INFINITY, err), 0) << slurp(err);
  const auto old = contents(out);
  ASSERT_GE(old.size(), 4u);
  // Fail at an early file, a middle and a late one (--outputs all: labels.nrrd gzip-encoded, then
  // segments.json of over 300 kB, segmentation.png, labels.npy of 70 kB).
  const std::size_t npy = 128 + 4 * 26 * 26 * 26;
  for (rlim_t limit : {rlim_t(1000), rlim_t(npy / 2), rlim_t(npy + 1000)}) {
    EXPECT_EQ(run_cli_sigxfsz_default(in_b, out, limit, err), 2) << limit;
    const std::string message = slurp(err);
    EXPECT_NE(message.find("occseg: error: cannot write '" + out + "/"), std::string::npos) << message;
    EXPECT_NE(message.find("File too large"), std::string::npos) << message;
    EXPECT_TRUE(contents(out) == old) << limit << ": the earlier run's files changed; now " << entries(out).size();
  }
  EXPECT_EQ(run_cli_sigxfsz_default(in_b, out, RLIM_INFINITY, err), 0) << slurp(err);
  EXPECT_NE(slurp(out + "/labels.npy"), old.at("labels.npy"));
}
