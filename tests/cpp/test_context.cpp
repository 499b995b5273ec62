// occseg::Context: a persistent pool that takes the parallel loops of calls made through it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include "occseg/context.hpp"
#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
#include "random_maps.hpp"

using namespace occseg;

namespace {
// Calls served by the current thread so far: a thread that serves several calls is a pool thread
// (threads started per call serve exactly one).
thread_local int served = 0;

std::vector<std::pair<std::size_t, std::size_t>> chunks_of(const std::function<void(const std::function<void(std::size_t, std::size_t)>&)>& loop) {
  std::mutex m;
  std::vector<std::pair<std::size_t, std::size_t>> out;
  loop([&](std::size_t b, std::size_t e) {
    std::lock_guard<std::mutex> g(m);
    out.emplace_back(b, e);
  });
  std::sort(out.begin(), out.end());
  return out;
}

void expect_same(const Result& a, const Result& b) {
  EXPECT_EQ(a.labels, b.labels);
  ASSERT_EQ(a.segments.size(), b.segments.size());
  for (std::size_t i = 0; i < a.segments.size(); ++i) {
    EXPECT_EQ(a.segments[i].voxels, b.segments[i].voxels);
    EXPECT_EQ(a.segments[i].state, b.segments[i].state);
    EXPECT_EQ(a.segments[i].mop, b.segments[i].mop);
    EXPECT_EQ(a.segments[i].centroid, b.segments[i].centroid);
  }
}
}  // namespace

TEST(Context, SameChunksAsParallelForAndEveryIndexOnce) {
  Context ctx(3);
  ASSERT_EQ(ctx.threads(), 3);
  const auto pooled = chunks_of([&](const auto& fn) { ctx.parallel_for(1000, fn); });
  const auto plain = chunks_of([&](const auto& fn) { parallel_for(1000, 3, fn); });
  EXPECT_EQ(pooled, plain);
  ASSERT_EQ(pooled.size(), 3u);
  std::size_t next = 0;
  for (const auto& c : pooled) {
    EXPECT_EQ(c.first, next);
    next = c.second;
  }
  EXPECT_EQ(next, 1000u);
  // Fewer indices than threads: one chunk per index.
  EXPECT_EQ(chunks_of([&](const auto& fn) { ctx.parallel_for(2, fn); }).size(), 2u);
}

TEST(Context, ThreadsPersistAcrossCalls) {
  Context ctx(2);
  std::atomic<int> worker_most{0};
  served = 0;
  const std::thread::id caller = std::this_thread::get_id();
  auto count_workers = [&](std::size_t, std::size_t) {
    if (std::this_thread::get_id() == caller) return;
    const int s = ++served;
    int m = worker_most.load();
    while (s > m && !worker_most.compare_exchange_weak(m, s)) {
    }
  };
  for (int call = 0; call < 4; ++call) ctx.parallel_for(2, count_workers);
  EXPECT_EQ(worker_most.load(), 4) << "one worker thread served every call";
  // Without a context, each call starts a new thread: no worker serves two calls.
  worker_most = 0;
  for (int call = 0; call < 4; ++call) parallel_for(2, 2, count_workers);
  EXPECT_EQ(worker_most.load(), 1);
  // Through run(), the library's parallel_for uses the pool.
  worker_most = 0;
  ctx.run([&] {
    for (int call = 0; call < 3; ++call) parallel_for(2, 0, count_workers);
  });
  EXPECT_EQ(worker_most.load(), 4 + 3) << "the same worker thread as before, 4 + 3 calls";
}

TEST(Context, SegmentAndFusionGiveTheSameResults) {
  Context ctx(2);
  for (std::uint64_t seed : {1u, 7u}) {
    const Grid g = test::random_map(Dims{37, 29, 21}, seed, 0.3);
    expect_same(segment(ctx, g), segment(g));
    Params p = Params::defaults();
    p.threads = 1;
    expect_same(segment(ctx, g, p), segment(g, p));
  }
  GridFrame f;
  f.dims = Dims{40, 40, 30};
  f.voxel_size = 0.1;
  std::vector<float> xyz;
  for (int i = 0; i < 5000; ++i) {
    xyz.push_back(static_cast<float>(2.0 + std::cos(i * 0.01) * 1.5));
    xyz.push_back(static_cast<float>(2.0 + std::sin(i * 0.01) * 1.5));
    xyz.push_back(static_cast<float>(0.2 + (i % 7) * 0.3));
  }
  OccupancyFusion a(f), b(f);
  insert_scan(ctx, a, {2.0, 2.0, 1.0}, xyz.data(), 5000, 3, 0);
  b.insert_scan({2.0, 2.0, 1.0}, xyz.data(), 5000, 3, 1);
  EXPECT_EQ(a.log_odds(), b.log_odds());
  EXPECT_NE(std::count(a.log_odds().begin(), a.log_odds().end(), 0.0f), static_cast<long>(a.log_odds().size()));
}

// A recycled result's label array is the next call's (same storage, no fresh memory), written
// over completely; a map with more voxels than it holds gets fresh storage; results always
// equal the plain call's.
TEST(Context, RecycledLabelArrayIsReusedAndRewritten) {
  Context ctx(2);
  const Grid a = test::random_map(Dims{37, 29, 21}, 3, 0.3), b = test::random_map(Dims{37, 29, 21}, 4, 0.3);
  const Grid small = test::random_map(Dims{20, 9, 5}, 5, 0.3), big = test::random_map(Dims{37, 29, 22}, 6, 0.3);
  Result r = segment(ctx, a);
  expect_same(r, segment(a));
  const std::uint32_t* storage = r.labels.data();
  ctx.recycle(std::move(r));
  EXPECT_TRUE(r.labels.empty());
  EXPECT_TRUE(r.segments.empty());
  Result s = segment(ctx, b);
  EXPECT_EQ(s.labels.data(), storage);
  expect_same(s, segment(b));
  ctx.recycle(std::move(s));
  Result t = segment(ctx, small);  // fewer voxels: the same storage
  EXPECT_EQ(t.labels.data(), storage);
  expect_same(t, segment(small));
  ctx.recycle(std::move(t));
  Result u = segment(ctx, big);  // more voxels than it holds: fresh storage
  expect_same(u, segment(big));
  Result v = segment(ctx, a);  // nothing recycled since: fresh storage too
  EXPECT_NE(v.labels.data(), u.labels.data());
  expect_same(v, segment(a));
}

TEST(Context, ExceptionsNestingAndBadCounts) {
  Context ctx(2);
  EXPECT_THROW(ctx.parallel_for(10, [](std::size_t b, std::size_t) {
    if (b > 0) throw std::runtime_error("worker chunk");
  }),
               std::runtime_error);
  EXPECT_THROW(ctx.parallel_for(10, [](std::size_t b, std::size_t) {
    if (b == 0) throw std::runtime_error("caller chunk");
  }),
               std::runtime_error);
  // Still usable, and a parallel loop nested in a pool task completes (its own threads).
  std::atomic<std::size_t> sum{0};
  ctx.run([&] {
    parallel_for(4, 0, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        parallel_for(100, 2, [&](std::size_t bb, std::size_t ee) { sum += (ee - bb) * (i + 1); });
    });
  });
  EXPECT_EQ(sum.load(), 100u * (1 + 2 + 3 + 4));
  EXPECT_THROW(Context(-1), Error);
}
