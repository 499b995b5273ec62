// Scan fusion (occseg/fusion.hpp): the inverse sensor model, clipping, threads, cancelling, and
// every level's ray walk against a plain walk.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "isa_levels.hpp"
#include "occseg/error.hpp"
#include "occseg/fusion.hpp"

using namespace occseg;
using occseg::testing_isa::for_each_isa;

namespace {
GridFrame frame(std::size_t nx, std::size_t ny, std::size_t nz, double vs = 0.1) {
  GridFrame f;
  f.dims = Dims{nx, ny, nz};
  f.voxel_size = vs;
  return f;
}
}  // namespace

TEST(Fusion, OneRayAlongX) {
  OccupancyFusion fu(frame(10, 3, 3));
  // From the centre of voxel (0,1,1) to the centre of voxel (6,1,1).
  fu.insert_scan({0.05, 0.15, 0.15}, std::vector<Vec3>{{0.65, 0.15, 0.15}}, 1);
  const Grid g = fu.grid();
  for (int x = 0; x < 6; ++x) EXPECT_NEAR(g.at(x, 1, 1), 0.4, 1e-6) << x;
  EXPECT_NEAR(g.at(6, 1, 1), 0.7, 1e-6);
  for (int x = 7; x < 10; ++x) EXPECT_EQ(g.at(x, 1, 1), 0.5f) << "nothing beyond the return";
  EXPECT_EQ(g.at(3, 0, 1), 0.5f) << "never observed: exactly 0.5";
  EXPECT_EQ(fu.rays(), 1u);
}

TEST(Fusion, RepeatedHitsTendToTheClampingValues) {
  OccupancyFusion fu(frame(8, 1, 1));
  for (int k = 0; k < 30; ++k) fu.insert_scan({0.05, 0.05, 0.05}, std::vector<Vec3>{{0.55, 0.05, 0.05}}, 1);
  const Grid g = fu.grid();
  EXPECT_NEAR(g.at(5, 0, 0), 0.97, 1e-5);
  EXPECT_NEAR(g.at(2, 0, 0), 0.12, 1e-5);
  // After exactly two scans the log-odds add: logit^-1(2 logit 0.7).
  OccupancyFusion two(frame(8, 1, 1));
  for (int k = 0; k < 2; ++k) two.insert_scan({0.05, 0.05, 0.05}, std::vector<Vec3>{{0.55, 0.05, 0.05}}, 1);
  const double l = 2 * std::log(0.7 / 0.3);
  EXPECT_NEAR(two.grid().at(5, 0, 0), 1 / (1 + std::exp(-l)), 1e-6);
}

TEST(Fusion, HitWinsOverMissWithinAScanAndNaNIsSkipped) {
  OccupancyFusion fu(frame(8, 1, 1));
  const float nan = std::nanf("");
  // Ray 1 passes through voxel 3, ray 2 ends in it: hit, once.
  const float xyz[9] = {0.65f, 0.05f, 0.05f, 0.35f, 0.05f, 0.05f, nan, 0.0f, 0.0f};
  fu.insert_scan({0.05, 0.05, 0.05}, xyz, 3, 3, 2);
  const Grid g = fu.grid();
  EXPECT_NEAR(g.at(3, 0, 0), 0.7, 1e-6);
  EXPECT_NEAR(g.at(2, 0, 0), 0.4, 1e-6);
  EXPECT_EQ(fu.rays(), 2u);
}

TEST(Fusion, MaxRangeMarksFreeSpaceOnly) {
  SensorModel m;
  m.max_range = 0.3;
  OccupancyFusion fu(frame(10, 1, 1), m);
  fu.insert_scan({0.05, 0.05, 0.05}, std::vector<Vec3>{{0.85, 0.05, 0.05}}, 1);
  const Grid g = fu.grid();
  EXPECT_NEAR(g.at(0, 0, 0), 0.4, 1e-6);
  EXPECT_NEAR(g.at(3, 0, 0), 0.4, 1e-6);  // truncated at 0.35 m: voxel 3 is the last one crossed
  EXPECT_EQ(g.at(4, 0, 0), 0.5f);
  EXPECT_EQ(g.at(8, 0, 0), 0.5f) << "no hit at a max-range return";
}

TEST(Fusion, SensorOutsideTheGridIsClipped) {
  OccupancyFusion fu(frame(5, 5, 1));
  fu.insert_scan({-1.0, 0.25, 0.05}, std::vector<Vec3>{{0.25, 0.25, 0.05}}, 1);
  const Grid g = fu.grid();
  EXPECT_NEAR(g.at(0, 2, 0), 0.4, 1e-6);
  EXPECT_NEAR(g.at(1, 2, 0), 0.4, 1e-6);
  EXPECT_NEAR(g.at(2, 2, 0), 0.7, 1e-6);
  EXPECT_EQ(g.at(3, 2, 0), 0.5f);
  // A ray that misses the box entirely changes nothing.
  OccupancyFusion miss(frame(5, 5, 1));
  miss.insert_scan({-1.0, 5.0, 0.05}, std::vector<Vec3>{{-0.5, 6.0, 0.05}}, 1);
  for (float v : miss.grid().p) EXPECT_EQ(v, 0.5f);
}

TEST(Fusion, DiagonalRayIsFaceConnected) {
  OccupancyFusion fu(frame(20, 20, 20));
  fu.insert_scan({0.01, 0.02, 0.03}, std::vector<Vec3>{{1.93, 1.71, 1.55}}, 1);
  const Grid g = fu.grid();
  int touched = 0;
  for (float v : g.p) touched += v != 0.5f;
  // A 6-connected walk from voxel (0,0,0) to (19,17,15) visits 19+17+15+1 voxels.
  EXPECT_EQ(touched, 19 + 17 + 15 + 1);
  EXPECT_NEAR(g.at(19, 17, 15), 0.7, 1e-6);
}

TEST(Fusion, ThreadsDoNotChangeTheMap) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 2000; ++i)
    pts.push_back({2.0 + std::cos(i * 0.01) * 1.5, 2.0 + std::sin(i * 0.01) * 1.5, 0.2 + (i % 7) * 0.3});
  OccupancyFusion a(frame(40, 40, 30)), b(frame(40, 40, 30));
  a.insert_scan({2.0, 2.0, 1.0}, pts, 1);
  b.insert_scan({2.0, 2.0, 1.0}, pts, 4);
  EXPECT_EQ(a.log_odds(), b.log_odds());
}

TEST(Fusion, FitFrameAndBadInput) {
  const GridFrame f = fit_frame({{0.01, 0.02, 0.03}, {0.29, -0.11, 0.03}}, 0.1);
  EXPECT_EQ(f.dims, (Dims{3, 3, 1}));
  EXPECT_NEAR(f.origin[1], -0.2, 1e-12);
  EXPECT_THROW(fit_frame({}, 0.1), Error);
  SensorModel bad;
  bad.p_hit = 0.3;
  EXPECT_THROW(OccupancyFusion(frame(2, 2, 2), bad), Error);
  OccupancyFusion fu(frame(2, 2, 2));
  EXPECT_THROW(fu.insert_scan({NAN, 0, 0}, std::vector<Vec3>{{0, 0, 0}}, 1), Error);
}

// Progress (the `occseg` progress bar and Ctrl-C hang on it): reports after every 65536 rays,
// changes nothing in the map, and a cancel leaves the grid as the earlier scans made it.
namespace {
std::vector<Vec3> ring(std::size_t n, double z) {
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < n; ++i)
    pts.push_back({2.0 + std::cos(i * 1e-4) * 1.5, 2.0 + std::sin(i * 1e-4) * 1.5, z + (i % 5) * 0.2});
  return pts;
}
}  // namespace

TEST(Fusion, ProgressReportsEveryChunkAndChangesNothing) {
  const std::vector<Vec3> pts = ring(200000, 0.3);
  OccupancyFusion plain(frame(40, 40, 30)), watched(frame(40, 40, 30));
  std::vector<std::size_t> done;
  watched.set_progress([&](std::size_t d, std::size_t count) {
    EXPECT_EQ(count, pts.size());
    done.push_back(d);
    return true;
  });
  plain.insert_scan({2.0, 2.0, 1.0}, pts, 2);
  watched.insert_scan({2.0, 2.0, 1.0}, pts, 2);
  EXPECT_EQ(done, (std::vector<std::size_t>{65536, 131072, 196608, 200000}));
  EXPECT_EQ(plain.log_odds(), watched.log_odds());
}

TEST(Fusion, CancelledScanLeavesTheEarlierOnes) {
  OccupancyFusion fu(frame(40, 40, 30)), once(frame(40, 40, 30));
  fu.insert_scan({2.0, 2.0, 1.0}, ring(1000, 0.3), 1);
  once.insert_scan({2.0, 2.0, 1.0}, ring(1000, 0.3), 1);
  int calls = 0;
  fu.set_progress([&](std::size_t, std::size_t) { return ++calls < 2; });
  try {
    fu.insert_scan({2.0, 2.0, 1.0}, ring(150000, 0.5), 2);
    FAIL() << "no cancel";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::cancelled);
  }
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(fu.scans(), 1u);
  EXPECT_EQ(fu.log_odds(), once.log_odds());
  // Usable afterwards: the same scan again, now to the end, gives what a fresh fusion gives.
  fu.set_progress({});
  fu.insert_scan({2.0, 2.0, 1.0}, ring(150000, 0.5), 2);
  once.insert_scan({2.0, 2.0, 1.0}, ring(150000, 0.5), 2);
  EXPECT_EQ(fu.log_odds(), once.log_odds());
}

// The traversal is optimised (strided index, branch-free axis choice, check-then-set marks,
// apply pass limited to the touched box). This is the first implementation's walk, written
// plainly; random rays (inside, outside, clipped, axis-aligned, on voxel faces, zero length,
// near voxel faces, beyond max range) must give the same log-odds bit for bit.
namespace {
// GCC 12 at -O2/-O3 picks different voxels in this copy of the walk than in the library on a few
// rays (the choice at near-ties of tmax), depending on how it is inlined here; the library's walk
// is the same at -O0, -O2 and -O3. So the reference is compiled without optimisation.
#if defined(__GNUC__) && !defined(__clang__)
#define OCCSEG_PLAIN __attribute__((optimize("O0"), noinline))
#else
#define OCCSEG_PLAIN
#endif
OCCSEG_PLAIN void reference_trace(const GridFrame& f, const Vec3& from, const Vec3& to, bool hit, std::vector<std::uint8_t>& marks) {
  const double n[3] = {double(f.dims.nx), double(f.dims.ny), double(f.dims.nz)};
  double a[3], b[3], d[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = (from[k] - f.origin[k]) / f.voxel_size;
    b[k] = (to[k] - f.origin[k]) / f.voxel_size;
    d[k] = b[k] - a[k];
  }
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (a[k] < 0 || a[k] >= n[k]) return;
      continue;
    }
    double ta = (0 - a[k]) / d[k], tb = (n[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return;
  const bool end_inside = hit && t1 >= 1.0;
  long c[3], last[3];
  int step[3];
  double tmax[3], tdelta[3];
  for (int k = 0; k < 3; ++k) {
    c[k] = std::clamp(static_cast<long>(std::floor(a[k] + t0 * d[k])), 0L, static_cast<long>(n[k]) - 1);
    last[k] = std::clamp(static_cast<long>(std::floor(a[k] + t1 * d[k])), 0L, static_cast<long>(n[k]) - 1);
    if (d[k] > 0) {
      step[k] = 1;
      tmax[k] = (c[k] + 1 - a[k]) / d[k];
      tdelta[k] = 1 / d[k];
    } else if (d[k] < 0) {
      step[k] = -1;
      tmax[k] = (c[k] - a[k]) / d[k];
      tdelta[k] = -1 / d[k];
    } else {
      step[k] = 0;
      tmax[k] = tdelta[k] = std::numeric_limits<double>::infinity();
    }
  }
  long budget = std::labs(last[0] - c[0]) + std::labs(last[1] - c[1]) + std::labs(last[2] - c[2]) + 1;
  for (; budget > 0; --budget) {
    const std::size_t i = c[0] + f.dims.nx * (c[1] + f.dims.ny * c[2]);
    const bool at_end = c[0] == last[0] && c[1] == last[1] && c[2] == last[2];
    marks[i] |= at_end && end_inside ? 2 : 1;
    if (at_end) break;
    int k = tmax[0] < tmax[1] ? (tmax[0] < tmax[2] ? 0 : 2) : (tmax[1] < tmax[2] ? 1 : 2);
    c[k] += step[k];
    tmax[k] += tdelta[k];
    if (c[k] < 0 || c[k] >= static_cast<long>(n[k])) break;
  }
}

void reference_scan(const GridFrame& f, const SensorModel& m, const Vec3& s, const std::vector<Vec3>& pts,
                    std::vector<float>& lo) {
  std::vector<std::uint8_t> marks(f.dims.count(), 0);
  for (const Vec3& q : pts) {
    // insert_scan(vector) hands the endpoints on as floats.
    Vec3 end{static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2])};
    if (!std::isfinite(end[0]) || !std::isfinite(end[1]) || !std::isfinite(end[2])) continue;
    bool hit = true;
    if (m.max_range >= 0) {
      const double dx = end[0] - s[0], dy = end[1] - s[1], dz = end[2] - s[2];
      const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (len > m.max_range) {
        const double r = m.max_range / len;
        end = {s[0] + dx * r, s[1] + dy * r, s[2] + dz * r};
        hit = false;
      }
    }
    reference_trace(f, s, end, hit, marks);
  }
  auto logit = [](double p) { return static_cast<float>(std::log(p / (1 - p))); };
  for (std::size_t i = 0; i < marks.size(); ++i)
    if (marks[i])
      lo[i] = std::clamp(lo[i] + ((marks[i] & 2) ? logit(m.p_hit) : logit(m.p_miss)), logit(m.clamp_min),
                         logit(m.clamp_max));
}
}  // namespace

// Every level's walk: the plain one, SSE2, and AVX2 lanes where the processor has AVX2.
class FusionWalk : public occseg::testing_isa::IsaTest {};
OCCSEG_INSTANTIATE_ISA_LEVELS(FusionWalk);

TEST_P(FusionWalk, OptimisedWalkMatchesThePlainWalkOnRandomRays) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(-0.5, 2.5);
  std::uniform_int_distribution<int> face(-3, 25);
  std::uniform_int_distribution<int> kind(0, 5);
  for (int trial = 0; trial < 12; ++trial) {
    GridFrame f = frame(13 + trial % 5, 17 - trial % 3, 9 + trial % 4, 0.1);
    f.origin = {0.05 * (trial % 3), -0.1 * (trial % 2), 0.0};
    SensorModel m;
    if (trial % 3 == 2) m.max_range = 0.8;
    OccupancyFusion fu(f, m);
    std::vector<float> expect(f.dims.count(), 0.0f);
    for (int scan = 0; scan < 3; ++scan) {
      // Sensor inside the box in most scans, outside (rays clipped on entry) in some.
      const Vec3 s = scan == 2 ? Vec3{-0.7, u(rng), u(rng)} : Vec3{u(rng) * 0.5 + 0.3, u(rng) * 0.5 + 0.3, 0.45};
      std::vector<Vec3> pts;
      for (int r = 0; r < 3000; ++r) {
        Vec3 p{u(rng), u(rng), u(rng)};
        switch (kind(rng)) {
          case 0:  // 1e-7 m off voxel faces (exactly on a face, where the walk ends depends on the
                   // last bit of a + t1 (b - a), which GCC's -O2 vectoriser changes in this copy)
            for (int k = 0; k < 3; ++k) p[k] = f.origin[k] + 0.1 * face(rng) + ((r >> k) & 1 ? 1e-7 : -1e-7);
            break;
          case 1:  // axis-aligned
            p = s;
            p[r % 3] += u(rng);
            break;
          case 2:  // zero length
            if (r % 50 == 0) p = s;
            break;
          default:
            break;
        }
        pts.push_back(p);
      }
      pts.push_back({NAN, 0, 0});
      reference_scan(f, m, s, pts, expect);
      fu.insert_scan(s, pts, 1 + scan % 2);
      for (std::size_t i = 0, shown = 0; i < expect.size() && shown < 5; ++i)
        if (fu.log_odds()[i] != expect[i]) {
          ++shown;
          ADD_FAILURE() << "voxel " << i << " = (" << i % f.dims.nx << ", " << i / f.dims.nx % f.dims.ny << ", "
                        << i / (f.dims.nx * f.dims.ny) << "): " << fu.log_odds()[i] << " expected " << expect[i];
        }
      ASSERT_EQ(fu.log_odds(), expect) << "trial " << trial << " scan " << scan;
    }
  }
}

// Exact ties in the axis choice (rays through voxel edges and corners), where the plain walk above
// is not a reliable judge (see docs/performance.md): every level's walk must agree with the
// scalar kernel's, which makes the same IEEE operations one ray at a time.
TEST(Fusion, EveryLevelsWalkAgreesOnTies) {
  std::mt19937_64 rng(777);
  std::uniform_int_distribution<int> cell(-12, 12);
  const GridFrame f = frame(24, 24, 24, 0.125);  // origin 0, power-of-two voxel: exact offsets
  const Vec3 s{1.5 + 0.0625, 1.5 + 0.0625, 1.5 + 0.0625};
  std::vector<Vec3> pts;
  for (int r = 0; r < 6000; ++r) {
    const double t = 0.125 * cell(rng) + 0.03125, q = 0.125 * cell(rng) + 0.03125;
    Vec3 p = s;
    p[r % 3] += t;
    p[(r + 1) % 3] += (r / 3) % 2 ? t : -t;
    if ((r / 6) % 2) p[(r + 2) % 3] += (r / 12) % 2 ? t : q;
    pts.push_back(p);
  }
  std::vector<float> scalar;
  {
    kernels::ScopedIsa plain(kernels::Isa::scalar);
    OccupancyFusion fu(f);
    fu.insert_scan(s, pts, 1);
    scalar = fu.log_odds();
  }
  std::size_t touched = 0;
  for (float l : scalar) touched += l != 0.0f;
  EXPECT_GT(touched, 1000u);
  const int levels = for_each_isa([&](kernels::Isa) {
    for (int threads : {1, 2}) {
      OccupancyFusion fu(f);
      fu.insert_scan(s, pts, threads);
      EXPECT_EQ(fu.log_odds(), scalar) << threads << " threads";
    }
  });
  EXPECT_GE(levels, 2);
}

// Marks set before a cancel must not leak into the next scan (marks are cleared per scan only
// where a scan touched them, so the cancel has to clear its own).
TEST(Fusion, CancelledScanLeavesNoMarksForTheNextScan) {
  OccupancyFusion fu(frame(40, 40, 30)), fresh(frame(40, 40, 30));
  int calls = 0;
  fu.set_progress([&](std::size_t, std::size_t) { return ++calls < 2; });
  EXPECT_THROW(fu.insert_scan({2.0, 2.0, 1.0}, ring(150000, 0.5), 1), Error);
  fu.set_progress({});
  const std::vector<Vec3> other{{0.3, 0.3, 0.3}, {3.5, 0.5, 2.5}};
  fu.insert_scan({2.0, 2.0, 1.0}, other, 1);
  fresh.insert_scan({2.0, 2.0, 1.0}, other, 1);
  EXPECT_EQ(fu.log_odds(), fresh.log_odds());
  int touched = 0;
  for (float v : fu.log_odds()) touched += v != 0.0f;
  EXPECT_LT(touched, 200) << "only the two rays' voxels";
}

// Threads take blocks of 2048 rays from a shared counter: many blocks, uneven ray lengths, any
// thread count, same map.
TEST(Fusion, BlockScheduledThreadsDoNotChangeTheMap) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 20000; ++i) {
    const double r = 0.3 + (i / 2048 % 3) * 0.6;  // ray lengths change from block to block
    pts.push_back({2.0 + std::cos(i * 0.013) * r, 2.0 + std::sin(i * 0.013) * r, 0.2 + (i % 11) * 0.25});
  }
  OccupancyFusion one(frame(40, 40, 30)), three(frame(40, 40, 30));
  one.insert_scan({2.0, 2.0, 1.0}, pts, 1);
  three.insert_scan({2.0, 2.0, 1.0}, pts, 3);
  EXPECT_EQ(one.log_odds(), three.log_odds());
  std::vector<float> expect(one.log_odds().size(), 0.0f);
  reference_scan(one.frame(), SensorModel(), {2.0, 2.0, 1.0}, pts, expect);
  EXPECT_EQ(three.log_odds(), expect);
}
