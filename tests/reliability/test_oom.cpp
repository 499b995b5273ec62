// Out of memory is OCCSEG_ENOMEM, not a crash: children with an address-space limit
// (RLIMIT_AS) segment a map they cannot afford. Not under sanitizers, whose shadow memory needs
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

// In a child: a 96^3 map, then `extra` bytes of address space beyond what is in use, then
// occseg_segment with 2 threads. Exit 0: OK, 1: ENOMEM with the message, 2+: anything else.
int segment_with_headroom(std::size_t extra) {
  return in_child([extra] {
    const std::size_t n = 96;
    const std::vector<float> p = box_map(n);
    const std::size_t d[3] = {n, n, n};
    occseg_map* m = nullptr;
    occseg_params* params = nullptr;
    if (occseg_map_from_buffer(&m, p.data(), OCCSEG_F32, d, nullptr, 1.0) || occseg_params_create(&params) ||
        occseg_params_set_int(params, "threads", 2))
      return 5;
    const rlimit r{address_space() + extra, address_space() + extra};
    if (::setrlimit(RLIMIT_AS, &r) != 0) return 6;
    occseg_result* res = nullptr;
    const int rc = occseg_segment(&res, m, params);
    if (rc == OCCSEG_OK) return res ? 0 : 7;
    if (rc == OCCSEG_ENOMEM && !res && std::strstr(occseg_last_error(), "occseg_segment: out of memory")) return 1;
    std::fprintf(stderr, "status %d: %s\n", rc, occseg_last_error());
    return 8;
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
