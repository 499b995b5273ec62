// The idle thread pools that calls without a context lease (libseg/src/pipeline/shared_pools.cpp),
// through the C ABI: many one-shot calls at once from many threads (each lease its own pool, no
// call waits for another's), borrowed maps segmented concurrently, and a fork()ed child whose
// copies of the parent's pools have no threads.
#include <atomic>
#include <csignal>
#include <cstring>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "support.hpp"

namespace {

constexpr std::size_t kN = 36;

std::vector<float> room(unsigned seed) {
  std::vector<float> p(kN * kN * kN);
  std::uint32_t s = seed * 2654435761u + 7;
  for (std::size_t z = 0; z < kN; ++z)
    for (std::size_t y = 0; y < kN; ++y)
      for (std::size_t x = 0; x < kN; ++x) {
        s = s * 1664525u + 1013904223u;
        const bool box = x > 6 && x < 6 + seed % 17 && y > 5 && y < 20 && z < 12;
        p[x + kN * (y + kN * z)] = box ? 0.92f : (y > 30 ? 0.5f : 0.08f + float(s >> 24) / 4000.0f);
      }
  return p;
}

// Labels of a one-shot occseg_segment with `threads` threads; empty on failure.
std::vector<std::uint32_t> labels_of(const occseg_map* map, int threads) {
  occseg_params* params = nullptr;
  occseg_result* r = nullptr;
  std::vector<std::uint32_t> out;
  if (occseg_params_create(&params) == OCCSEG_OK && occseg_params_set_int(params, "threads", threads) == OCCSEG_OK &&
      occseg_segment(&r, map, params) == OCCSEG_OK) {
    const std::uint32_t* l = nullptr;
    std::size_t n = 0;
    if (occseg_result_labels_view(r, &l, &n) == OCCSEG_OK) out.assign(l, l + n);
  }
  occseg_result_free(r);
  occseg_params_free(params);
  return out;
}

const std::size_t kDims[3] = {kN, kN, kN};

TEST(SharedPools, OneShotCallsFromManyThreadsAtOnceOnBorrowedMaps) {
  constexpr int kThreads = 6, kCalls = 6;
  std::vector<std::vector<float>> maps;
  std::vector<std::vector<std::uint32_t>> expected;
  for (int t = 0; t < kThreads; ++t) {
    maps.push_back(room(static_cast<unsigned>(t)));
    occseg_map* m = nullptr;
    ASSERT_EQ(occseg_map_from_buffer(&m, maps.back().data(), OCCSEG_F32, kDims, nullptr, 0.05), OCCSEG_OK);
    expected.push_back(labels_of(m, 1));  // one thread: no pool at all
    occseg_map_free(m);
    ASSERT_EQ(expected.back().size(), kN * kN * kN);
  }
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      occseg_map* m = nullptr;  // each thread its own view of its own buffer
      if (occseg_map_view_buffer(&m, maps[t].data(), OCCSEG_F32, kDims, nullptr, 0.05, 0) != OCCSEG_OK) {
        ++wrong;
        return;
      }
      for (int c = 0; c < kCalls; ++c)
        if (labels_of(m, 2 + (c + t) % 3) != expected[t]) ++wrong;
      occseg_map_free(m);
    });
  for (auto& th : threads) th.join();
  EXPECT_EQ(wrong.load(), 0);
}

#if !defined(__SANITIZE_THREAD__)  // ThreadSanitizer ends a child that starts threads after a fork
TEST(SharedPools, AForkedChildSegmentsOnPoolsOfItsOwn) {
  const std::vector<float> p = room(3);
  occseg_map* m = nullptr;
  ASSERT_EQ(occseg_map_from_buffer(&m, p.data(), OCCSEG_F32, kDims, nullptr, 0.05), OCCSEG_OK);
  const std::vector<std::uint32_t> expected = labels_of(m, 2);  // leaves an idle pool with a worker
  ASSERT_EQ(expected.size(), kN * kN * kN);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // A call on the parent's pool would wait for its worker, which is not in this process,
    // forever: the alarm ends such a hang with SIGALRM.
    alarm(60);
    const bool same = labels_of(m, 2) == expected && labels_of(m, 2) == expected;
    _exit(same ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status)) << "the child ended by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 0);
  EXPECT_EQ(labels_of(m, 2), expected);  // the parent's pools still work
  occseg_map_free(m);
}
#endif

}  // namespace
