// The default preset's object rules (rules/objects.hpp: proximity across unknown gaps, speckles,
// pockets) and the scene table's kinds, on hand-built state maps whose answer is known voxel by
// voxel, and through the whole pipeline (thread counts, noise-free maps).
#include <gtest/gtest.h>

#include <functional>
#include <set>

#include "occseg/error.hpp"

#include "occseg/segment.hpp"
#include "rules/objects.hpp"
#include "rules/planes.hpp"
#include "stages/label.hpp"
#include "state_scene.hpp"

using namespace occseg;

namespace {

constexpr int F = 0, U = 1, O = 2;

// A map of three states given by a function of the voxel, labelled as the pipeline's labelling
// makes it, then grouped by the rules.
struct Scene : testing_scene::StateScene {
  Scene(Dims d, const std::function<int(int, int, int)>& state) : StateScene(d, 1.0, state) {}
  void group(const Params& p) {
    label_components(states, grid, labels, segments, 1, true);
    group_objects(grid, labels, segments, p);
    assign_kinds(segments, p, grid.dims);
  }
  std::size_t count(State s) const {
    std::size_t n = 0;
    for (const Segment& seg : segments) n += seg.state == s;
    return n;
  }
  // Every segment's statistics are those of its voxels, ids are dense and in order of first voxel.
  void expect_consistent_table() const {
    std::vector<std::uint64_t> n(segments.size(), 0);
    std::vector<std::size_t> first(segments.size(), ~std::size_t(0));
    for (std::size_t i = 0; i < labels.size(); ++i) {
      ASSERT_LT(labels[i], segments.size());
      if (!n[labels[i]]++) first[labels[i]] = i;
    }
    for (std::size_t s = 0; s < segments.size(); ++s) {
      EXPECT_EQ(segments[s].id, s);
      EXPECT_EQ(segments[s].voxels, n[s]) << "segment " << s;
      if (s > 0) {
        EXPECT_LT(first[s - 1], first[s]);
      }
    }
  }
};

bool in_box(int x, int y, int z, int x0, int y0, int z0, int x1, int y1, int z1) {
  return x >= x0 && x <= x1 && y >= y0 && y <= y1 && z >= z0 && z <= z1;
}

Params rules(int gap, int min_object, int min_pocket) {
  Params p;
  p.object_gap = gap;
  p.min_object_voxels = min_object;
  p.min_pocket_voxels = min_pocket;
  return p;
}

// Two 4 x 4 x 4 occupied blobs along x, `between` voxels of state `gap_state` between them (a
// 4 x 4 slab of them), free all around.
std::function<int(int, int, int)> two_blobs(int between, int gap_state) {
  return [=](int x, int y, int z) {
    if (!in_box(x, y, z, 0, 3, 3, 30, 6, 6)) return F;
    if (x >= 2 && x <= 5) return O;
    if (x >= 6 + between && x <= 9 + between) return O;
    if (x >= 6 && x < 6 + between) return gap_state;
    return F;
  };
}

}  // namespace

TEST(Objects, BlobsAcrossTwoUnknownVoxelsAreOneSegment) {
  Scene s({20, 10, 10}, two_blobs(2, U));
  s.group(rules(3, 0, 0));
  EXPECT_EQ(s.at(2, 3, 3), s.at(11, 6, 6));
  EXPECT_EQ(s.count(State::occupied), 1u);
  EXPECT_EQ(s.segments[s.at(2, 3, 3)].voxels, 128u);
  EXPECT_EQ(s.segments[s.at(6, 4, 4)].state, State::unknown);  // the gap stays unknown
  s.expect_consistent_table();
}

TEST(Objects, GapWiderThanObjectGapKeepsBlobsApart) {
  Scene s({20, 10, 10}, two_blobs(2, U));
  s.group(rules(1, 0, 0));
  EXPECT_NE(s.at(2, 3, 3), s.at(8, 3, 3));
  EXPECT_EQ(s.count(State::occupied), 2u);
  Scene t({20, 10, 10}, two_blobs(4, U));
  t.group(rules(3, 0, 0));
  EXPECT_EQ(t.count(State::occupied), 2u);
}

TEST(Objects, OneFreeVoxelBetweenKeepsBlobsApart) {
  Scene s({20, 10, 10}, two_blobs(1, F));
  s.group(rules(3, 0, 0));
  EXPECT_NE(s.at(2, 3, 3), s.at(7, 3, 3));
  EXPECT_EQ(s.count(State::occupied), 2u);
}

// Both blobs sit in one unknown region cut by a free wall one voxel thick: the way through the
// unknown around the wall is far longer than the gap, so free space keeps them apart however
// close they are; without the wall they are one object.
TEST(Objects, FreeWallBetweenObjectsInUnknownSpaceKeepsThemApart) {
  const auto scene = [](bool wall) {
    return [=](int x, int y, int z) {
      if (in_box(x, y, z, 2, 3, 3, 5, 6, 6) || in_box(x, y, z, 7, 3, 3, 10, 6, 6)) return O;
      if (wall && x == 6) return F;
      return U;
    };
  };
  Scene s({16, 12, 12}, scene(true));
  s.group(rules(3, 0, 0));
  EXPECT_EQ(s.count(State::occupied), 2u);
  Scene t({16, 12, 12}, scene(false));
  t.group(rules(3, 0, 0));
  EXPECT_EQ(t.count(State::occupied), 1u);
}

// A surface scanned in rings: occupied layers z = 2, 5, 8 with two unknown layers between each
// (the rays' gaps) are one segment, however many rings.
TEST(Objects, RingsOfAScannedSurfaceAreOneSegment) {
  Scene s({12, 12, 12}, [](int x, int y, int z) {
    if (!in_box(x, y, z, 2, 2, 2, 9, 9, 9)) return F;
    if (x == 2 && z % 3 == 2) return O;
    return x == 2 ? U : (x > 2 ? U : F);
  });
  s.group(rules(2, 0, 0));
  EXPECT_EQ(s.count(State::occupied), 1u);
  s.expect_consistent_table();
}

TEST(Objects, SpeckleNextToAnObjectJoinsIt) {
  // A 6 x 6 x 6 object and a 3-voxel speckle one free voxel away from its face.
  Scene s({20, 12, 12}, [](int x, int y, int z) {
    if (in_box(x, y, z, 2, 3, 3, 7, 8, 8)) return O;
    if (x == 9 && y == 5 && z >= 4 && z <= 6) return O;
    return F;
  });
  s.group(rules(3, 27, 0));
  EXPECT_EQ(s.count(State::occupied), 1u);
  EXPECT_EQ(s.at(9, 5, 5), s.at(2, 3, 3));
  EXPECT_EQ(s.segments[s.at(9, 5, 5)].voxels, 219u);
  EXPECT_EQ(s.segments[s.at(9, 5, 5)].kind, Kind::object);
  EXPECT_EQ(s.segments[s.at(9, 5, 5)].state, State::occupied);
  EXPECT_EQ(s.segments[s.at(8, 5, 5)].state, State::free);  // the voxel between stays free
  s.expect_consistent_table();
}

TEST(Objects, IsolatedSpeckleStaysOccupiedAsClutter) {
  Scene s({24, 12, 12}, [](int x, int y, int z) {
    if (in_box(x, y, z, 2, 3, 3, 7, 8, 8)) return O;
    if (x == 18 && y == 5 && z >= 4 && z <= 6) return O;
    return F;
  });
  s.group(rules(3, 27, 0));
  ASSERT_EQ(s.count(State::occupied), 2u);
  const Segment& speck = s.segments[s.at(18, 5, 5)];
  EXPECT_EQ(speck.state, State::occupied);
  EXPECT_EQ(speck.kind, Kind::clutter);
  EXPECT_EQ(speck.voxels, 3u);
  EXPECT_EQ(s.segments[s.at(2, 3, 3)].kind, Kind::object);
}

// Two speckles, each nearer a different object: each joins its own, so a speckle never bridges.
TEST(Objects, SpecklesJoinTheNearestObjectOnly) {
  Scene s({30, 12, 12}, [](int x, int y, int z) {
    if (in_box(x, y, z, 2, 3, 3, 7, 8, 8) || in_box(x, y, z, 14, 3, 3, 19, 8, 8)) return O;
    if (x == 10 && y == 5 && z == 5) return O;  // 3 from the first, 4 from the second
    return F;
  });
  s.group(rules(3, 27, 0));
  EXPECT_EQ(s.count(State::occupied), 2u);
  EXPECT_EQ(s.at(10, 5, 5), s.at(2, 3, 3));
  EXPECT_NE(s.at(10, 5, 5), s.at(14, 3, 3));
}

TEST(Objects, FreePocketEnclosedByUnknownBecomesUnknown) {
  // Free space with an unknown 7 x 7 x 7 cube holding a free pocket of 5 voxels in a row.
  Scene s({20, 20, 20}, [](int x, int y, int z) {
    if (!in_box(x, y, z, 5, 5, 5, 11, 11, 11)) return F;
    if (y == 8 && z == 8 && x >= 6 && x <= 10) return F;
    return U;
  });
  s.group(rules(3, 27, 64));
  EXPECT_EQ(s.segments.size(), 2u);
  EXPECT_EQ(s.segments[s.at(8, 8, 8)].state, State::unknown);
  EXPECT_EQ(s.at(8, 8, 8), s.at(5, 5, 5));
  EXPECT_EQ(s.segments[s.at(0, 0, 0)].state, State::free);
  EXPECT_EQ(s.segments[s.at(5, 5, 5)].voxels, 343u);
  s.expect_consistent_table();
}

TEST(Objects, LargeFreeRegionsStayFree) {
  Scene s({20, 20, 20}, [](int x, int y, int z) {
    if (!in_box(x, y, z, 3, 3, 3, 16, 16, 16)) return F;
    if (in_box(x, y, z, 6, 6, 6, 13, 13, 13)) return F;  // 512 voxels inside the unknown shell
    return U;
  });
  s.group(rules(3, 27, 64));
  EXPECT_EQ(s.count(State::free), 2u);
}

TEST(Objects, SmallUnknownPocketTouchingAnObjectJoinsIt) {
  // An 8 x 8 x 8 object with a 2 x 2 x 2 unknown dent in its free-facing face.
  Scene s({20, 20, 20}, [](int x, int y, int z) {
    if (in_box(x, y, z, 10, 8, 8, 11, 9, 9)) return U;
    if (in_box(x, y, z, 4, 5, 5, 11, 12, 12)) return O;
    return F;
  });
  s.group(rules(3, 27, 64));
  EXPECT_EQ(s.segments.size(), 2u);
  EXPECT_EQ(s.at(10, 8, 8), s.at(4, 5, 5));
  EXPECT_EQ(s.segments[s.at(10, 8, 8)].state, State::occupied);
  EXPECT_EQ(s.segments[s.at(4, 5, 5)].voxels, 512u);
  s.expect_consistent_table();
}

// A speckle too far from the object for rules 6 and 7 (4 unknown voxels between them, gap 3),
// whose pocket then joins the object: the speckle would lie against the object as clutter of its
// own, so it joins with the pocket (found by fuzz_buffer).
TEST(Objects, SpeckleBesideAPocketThatJoinsAnObjectJoinsItToo) {
  const auto state = [](int x, int y, int z) {
    if (in_box(x, y, z, 12, 8, 8, 15, 9, 9)) return U;  // 16 unknown voxels against the object
    if (in_box(x, y, z, 16, 8, 8, 16, 9, 8)) return O;  // 2 occupied voxels beyond them
    if (in_box(x, y, z, 4, 5, 5, 11, 12, 12)) return O;
    return F;
  };
  Scene s({24, 20, 20}, state);
  s.group(rules(3, 27, 64));
  EXPECT_EQ(s.count(State::occupied), 1u);
  EXPECT_EQ(s.segments.size(), 2u);
  EXPECT_EQ(s.at(16, 8, 8), s.at(4, 5, 5));
  EXPECT_EQ(s.at(13, 8, 8), s.at(4, 5, 5));
  EXPECT_EQ(s.segments[s.at(4, 5, 5)].voxels, 512u + 16u + 2u);
  EXPECT_EQ(s.segments[s.at(4, 5, 5)].kind, Kind::object);
  s.expect_consistent_table();
  // Without the pocket rule the speckle stays apart, as clutter: the join above is rule 8's.
  Scene t({24, 20, 20}, state);
  t.group(rules(3, 27, 0));
  EXPECT_EQ(t.count(State::occupied), 2u);
  EXPECT_EQ(t.segments[t.at(16, 8, 8)].kind, Kind::clutter);
}

// A pocket between two objects joins the one it shares the most faces with; the other stays an
// object of its own (two objects touching are not merged through a dent).
TEST(Objects, PocketBetweenTwoObjectsJoinsOneOfThem) {
  Scene s({30, 20, 20}, [](int x, int y, int z) {
    if (in_box(x, y, z, 12, 7, 7, 13, 10, 10)) return U;  // 32 unknown voxels, 16 faces each side
    if (in_box(x, y, z, 4, 5, 5, 11, 12, 12)) return O;   // 512 voxels
    if (in_box(x, y, z, 14, 8, 8, 17, 9, 9)) return O;    // 16 voxels, 4 faces with the pocket
    return F;
  });
  s.group(rules(0, 8, 64));
  EXPECT_EQ(s.count(State::occupied), 2u);
  EXPECT_EQ(s.at(12, 7, 7), s.at(4, 5, 5));
  EXPECT_NE(s.at(14, 8, 8), s.at(4, 5, 5));
  EXPECT_EQ(s.segments[s.at(14, 8, 8)].kind, Kind::object);
}

TEST(Objects, KindsFollowStatesAndSupportPlanes) {
  // A 30 x 30 floor with a box standing on it, free above: the floor is structure, the box an
  // object.
  Scene s({30, 30, 12}, [](int x, int y, int z) {
    if (z < 2) return U;
    if (z == 2) return O;
    if (in_box(x, y, z, 10, 10, 3, 13, 13, 7)) return O;
    return F;
  });
  s.group(rules(3, 27, 64));
  split_support_planes(s.grid, s.labels, s.segments, 256, true);
  assign_kinds(s.segments, rules(3, 27, 64), s.grid.dims);
  EXPECT_EQ(s.segments[s.at(0, 0, 2)].kind, Kind::structure);
  EXPECT_EQ(s.segments[s.at(11, 11, 5)].kind, Kind::object);
  EXPECT_EQ(s.segments[s.at(0, 0, 0)].kind, Kind::unknown);
  EXPECT_EQ(s.segments[s.at(0, 0, 9)].kind, Kind::free);
  EXPECT_STREQ(kind_name(Kind::clutter), "clutter");
}

// The paper preset has no object rules: its occupied segments are all objects, whatever their size.
TEST(Objects, PaperPresetLeavesTheRulesOff) {
  const Params p = Params::paper();
  EXPECT_EQ(p.object_gap, 0);
  EXPECT_EQ(p.min_object_voxels, 0);
  EXPECT_EQ(p.min_pocket_voxels, 0);
  Scene s({20, 10, 10}, two_blobs(2, U));
  s.group(p);
  EXPECT_EQ(s.count(State::occupied), 2u);
  for (const Segment& seg : s.segments)
    if (seg.state == State::occupied) {
      EXPECT_EQ(seg.kind, Kind::object);
    }
}

namespace {

// A noisy map: free space with rings of occupied voxels (gaps of 0.5 between them), speckles and
// free and unknown crumbs, deterministic.
Grid noisy_map() {
  Grid g({64, 48, 40}, 0.2f, 0.05);
  std::uint64_t h = 12345;
  const auto next = [&] {
    h ^= h << 13;
    h ^= h >> 7;
    h ^= h << 17;
    return h;
  };
  for (std::size_t z = 0; z < 40; ++z)
    for (std::size_t y = 0; y < 48; ++y)
      for (std::size_t x = 0; x < 64; ++x) {
        float& v = g.p[g.index(x, y, z)];
        const std::uint64_t r = next() % 1000;
        const bool shell = (x == 20 || x == 21) && y > 8 && y < 40 && z > 4 && z < 36;
        const bool behind = x > 21 && y > 8 && y < 40 && z > 4 && z < 36;
        if (shell) v = z % 3 == 0 ? 0.5f : 0.9f;        // rings with gaps
        else if (behind) v = r < 20 ? 0.3f : 0.5f;     // the shadow: unknown with free crumbs
        else if (r < 8) v = 0.8f;                      // speckles in free space
        else if (r < 30) v = 0.5f;                     // gaps between rays
      }
  return g;
}

}  // namespace

TEST(Objects, ResultsIdenticalForAnyThreadCount) {
  const Grid g = noisy_map();
  Params p;
  p.threads = 1;
  const Result one = segment(g, p);
  Params off = p;
  off.object_gap = off.min_object_voxels = off.min_pocket_voxels = 0;
  const Result without = segment(g, off);
  ASSERT_LT(one.segments.size(), without.segments.size());  // the rules did something here
  for (int t : {2, 3, 4}) {
    p.threads = t;
    const Result r = segment(g, p);
    ASSERT_EQ(r.segments.size(), one.segments.size()) << t << " threads";
    EXPECT_TRUE(std::equal(r.labels.begin(), r.labels.end(), one.labels.begin())) << t << " threads";
    for (std::size_t s = 0; s < r.segments.size(); ++s) {
      EXPECT_EQ(r.segments[s].voxels, one.segments[s].voxels);
      EXPECT_EQ(r.segments[s].mop, one.segments[s].mop);
      EXPECT_EQ(r.segments[s].kind, one.segments[s].kind);
      EXPECT_EQ(r.segments[s].centroid, one.segments[s].centroid);
    }
  }
}

// A noise-free piecewise-constant map whose regions are larger than the rules' minimum sizes:
// free space, an unknown cube, two boxes 3 voxels apart with free space between and a box
// touching the unknown cube. Every voxel keeps its state and each region is one segment.
TEST(Objects, NoiseFreeMapsStayVoxelExact) {
  const Dims d{72, 56, 40};
  Grid g(d, 0.1f, 0.05);
  const auto truth = [](int x, int y, int z) {
    if (in_box(x, y, z, 5, 5, 5, 14, 14, 14)) return O;
    if (in_box(x, y, z, 18, 5, 5, 27, 14, 14)) return O;   // 3 free voxels from the first
    if (in_box(x, y, z, 40, 20, 10, 60, 45, 30)) return U; // an unknown region...
    if (in_box(x, y, z, 34, 24, 12, 39, 30, 20)) return O; // ...and a box against it
    return F;
  };
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t y = 0; y < d.ny; ++y)
      for (std::size_t x = 0; x < d.nx; ++x) {
        const int t = truth(int(x), int(y), int(z));
        g.p[g.index(x, y, z)] = t == O ? 0.9f : (t == U ? 0.5f : 0.1f);
      }
  const Result r = segment(g, Params());
  ASSERT_EQ(r.segments.size(), 5u);
  std::set<std::uint32_t> ids;
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t y = 0; y < d.ny; ++y)
      for (std::size_t x = 0; x < d.nx; ++x) {
        const Segment& s = r.segments[r.labels[g.index(x, y, z)]];
        ASSERT_EQ(static_cast<int>(s.state), truth(int(x), int(y), int(z))) << x << " " << y << " " << z;
      }
  EXPECT_NE(r.labels[g.index(5, 5, 5)], r.labels[g.index(18, 5, 5)]);
  EXPECT_EQ(r.segments[r.labels[g.index(5, 5, 5)]].kind, Kind::object);
  EXPECT_EQ(r.segments[r.labels[g.index(34, 24, 12)]].kind, Kind::object);
}

TEST(Objects, MinimumSizesAreAreasOnOneLayerMaps) {
  EXPECT_EQ(minimum_size(27, Dims{10, 10, 2}), 27u);
  EXPECT_EQ(minimum_size(27, Dims{10, 10, 1}), 9u);
  EXPECT_EQ(minimum_size(64, Dims{10, 10, 1}), 16u);
  EXPECT_EQ(minimum_size(1, Dims{10, 10, 1}), 1u);
  EXPECT_EQ(minimum_size(0, Dims{10, 10, 1}), 0u);
  // A 2D room: a 24-cell box 3 free cells from the wall stays an object of its own.
  Scene s({40, 30, 1}, [](int x, int y, int) {
    if (y == 27 && x >= 3 && x <= 36) return O;
    if (x >= 10 && x < 16 && y >= 20 && y < 24) return O;
    return F;
  });
  s.group(rules(3, 27, 64));
  EXPECT_EQ(s.count(State::occupied), 2u);
  EXPECT_EQ(s.segments[s.at(10, 20, 0)].kind, Kind::object);
}

TEST(Objects, ParametersAreSetByNameAndChecked) {
  Params p;
  EXPECT_EQ(get_param(p, "object_gap"), "4");
  EXPECT_EQ(get_param(p, "min_object_voxels"), "64");
  EXPECT_EQ(get_param(p, "min_pocket_voxels"), "64");
  set_param(p, "object_gap", "2");
  set_param(p, "min_object_voxels", "10");
  set_param(p, "min_pocket_voxels", "0");
  EXPECT_EQ(p.object_gap, 2);
  EXPECT_EQ(p.min_object_voxels, 10);
  EXPECT_EQ(p.min_pocket_voxels, 0);
  const auto message = [&](const char* name, const char* value) {
    try {
      set_param(p, name, value);
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::invalid_argument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("object_gap", "17").find("parameter 'object_gap': 17 is outside [0, 16]"), std::string::npos);
  EXPECT_NE(message("min_object_voxels", "-1").find("'min_object_voxels'"), std::string::npos);
  EXPECT_NE(message("min_pocket_voxels", "2.5").find("not an integer"), std::string::npos);
  EXPECT_NE(message("min_pocket_voxels", "nan").find("not a number"), std::string::npos);
  Params q;
  q.object_gap = 99;
  EXPECT_THROW(q.validate(), Error);
  set_param(p, "preset", "paper");
  EXPECT_EQ(get_param(p, "object_gap"), "0");
}
