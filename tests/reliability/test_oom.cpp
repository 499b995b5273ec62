// Out of memory is OCCSEG_ENOMEM, not a crash: children with an address-space limit
// (RLIMIT_AS) segment a map they cannot afford (occseg_oom_child, a fresh process each time). Not under sanitizers, whose shadow memory needs
// the address space and whose allocators abort instead of throwing.
#include <cstdio>
#include <cstring>

#include "support.hpp"

using namespace occseg::reliability;

namespace {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

// Bytes of address space this process uses now.
std::size_t address_space() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  unsigned long pages = 0;
  if (!f || std::fscanf(f, "%lu", &pages) != 1) pages = 0;
  if (f) std::fclose(f);
  return pages * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

// occseg_oom_child (oom_child.c) with `extra` bytes of address space beyond what it uses after
// making its map: a fresh process, forked and exec'd, so that nothing this process allocated and
// freed before can serve its call. Its exit status: 0 OK, 1 ENOMEM with the message, 2+ anything else.
int segment_with_headroom(std::size_t extra) {
  const std::string bytes = std::to_string(extra);
  return in_child([&bytes] {
    ::execl(OCCSEG_OOM_CHILD, OCCSEG_OOM_CHILD, bytes.c_str(), static_cast<char*>(nullptr));
    return 97;  // not started
  });
}

}  // namespace

TEST(OutOfMemory, SegmentReportsEnomemAtEveryLimitAndSucceedsWithEnough) {
  if (kSanitized) GTEST_SKIP() << "RLIMIT_AS and sanitizer shadow memory do not mix";
  int enomem = 0, ok = 0;
  // From far too little to plenty; a thread that cannot get its stack must not crash either.
  for (std::size_t mb : {1, 4, 8, 16, 24, 32, 48, 64, 96, 128, 512}) {
    const int rc = segment_with_headroom(mb << 20);
    EXPECT_TRUE(rc == 0 || rc == 1) << mb << " MiB headroom: child ended with " << rc;
    enomem += rc == 1;
    ok += rc == 0;
  }
  EXPECT_GT(enomem, 0);  // the limit did bite
  EXPECT_GT(ok, 0);      // and enough memory works
}

TEST(OutOfMemory, ImportAndReadReportEnomem) {
  if (kSanitized) GTEST_SKIP() << "RLIMIT_AS and sanitizer shadow memory do not mix";
  const int rc = in_child([] {
    const rlimit r{address_space() + (64 << 20), address_space() + (64 << 20)};
    if (::setrlimit(RLIMIT_AS, &r) != 0) return 6;
    // 512^3 voxels need 512 MiB of floats. The map is allocated before the caller's data is
    // read, so one byte of data is enough to show that the failed allocation is reported.
    const std::size_t d[3] = {512, 512, 512};
    const std::uint8_t one = 0;
    occseg_map* m = nullptr;
    const int s = occseg_map_from_buffer(&m, &one, OCCSEG_U8, d, nullptr, 1.0);
    return s == OCCSEG_ENOMEM && !m && std::strstr(occseg_last_error(), "out of memory") ? 0 : 1;
  });
  EXPECT_EQ(rc, 0);
}
