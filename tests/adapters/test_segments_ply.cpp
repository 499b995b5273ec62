// segments.ply (occseg/voxel_mesh.hpp), read back with PCL's PLY readers: its generic parser
// (pcl::io::ply::ply_parser, every property, the per-face segment id included) and
// pcl::io::loadPLYFile into a PolygonMesh. Hand-computed counts for known shapes, bounds in
// metres, colours and segment ids.
#include <gtest/gtest.h>
#include <pcl/PolygonMesh.h>
#include <pcl/io/ply/ply_parser.h>
#include <pcl/io/ply_io.h>

#include <filesystem>
#include <set>

#include "occseg/segment.hpp"
#include "occseg/segment_colour.hpp"
#include "occseg/voxel_mesh.hpp"

using namespace occseg;
namespace fs = std::filesystem;
namespace ply = pcl::io::ply;

namespace {

std::string tmp(const std::string& name) {
  fs::create_directories(OCCSEG_TEST_TMP);
  return std::string(OCCSEG_TEST_TMP) + "/" + name;
}

struct ReadMesh {
  std::size_t declared_vertices = 0, declared_faces = 0;
  std::vector<std::array<float, 3>> xyz;
  std::vector<std::array<int, 3>> rgb;
  std::vector<std::vector<std::int32_t>> faces;
  std::vector<std::uint32_t> segment;
  bool binary_le = false;
};

// Every property of the file through PCL's PLY parser.
ReadMesh parse(const std::string& path) {
  ReadMesh m;
  ply::ply_parser p;
  std::string element;
  p.format_callback([&](ply::format_type f, const std::string&) { m.binary_le = f == ply::binary_little_endian_format; });
  p.element_definition_callback([&](const std::string& name, std::size_t count) {
    (name == "vertex" ? m.declared_vertices : m.declared_faces) = count;
    return ply::ply_parser::element_callbacks_type(
        [&, name] {
          element = name;
          if (name == "vertex") {
            m.xyz.push_back({0, 0, 0});
            m.rgb.push_back({-1, -1, -1});
          } else {
            m.faces.emplace_back();
            m.segment.push_back(~0u);
          }
        },
        [] {});
  });
  ply::ply_parser::scalar_property_definition_callbacks_type scalars;
  ply::ply_parser::at<ply::float32>(scalars) = [&](const std::string& e, const std::string& prop) -> std::function<void(float)> {
    if (e != "vertex") return {};
    const int k = prop == "x" ? 0 : prop == "y" ? 1 : 2;
    return [&, k](float v) { m.xyz.back()[k] = v; };
  };
  ply::ply_parser::at<ply::uint8>(scalars) = [&](const std::string&, const std::string& prop) -> std::function<void(std::uint8_t)> {
    const int k = prop == "red" ? 0 : prop == "green" ? 1 : 2;
    return [&, k](std::uint8_t v) { m.rgb.back()[k] = v; };
  };
  ply::ply_parser::at<ply::uint32>(scalars) = [&](const std::string& e, const std::string& prop) -> std::function<void(std::uint32_t)> {
    if (e != "face" || prop != "segment") return {};
    return [&](std::uint32_t v) { m.segment.back() = v; };
  };
  p.scalar_property_definition_callbacks(scalars);
  ply::ply_parser::list_property_definition_callbacks_type lists;
  ply::ply_parser::at<ply::uint8, ply::int32>(lists) = [&](const std::string&, const std::string&) {
    return std::make_tuple(std::function<void(std::uint8_t)>([](std::uint8_t) {}),
                           std::function<void(std::int32_t)>([&](std::int32_t v) { m.faces.back().push_back(v); }),
                           std::function<void()>([] {}));
  };
  p.list_property_definition_callbacks(lists);
  EXPECT_TRUE(p.parse(path)) << path;
  return m;
}

// A result over `labels` (0 free; 1, 2, ... occupied segments).
Result result_of(Dims d, const std::vector<std::uint32_t>& labels) {
  Result r;
  r.dims = d;
  r.labels.assign(labels.begin(), labels.end());
  std::uint32_t top = 0;
  for (const std::uint32_t l : labels) top = std::max(top, l);
  r.segments.resize(top + 1);
  for (std::uint32_t s = 0; s <= top; ++s) {
    r.segments[s].id = s;
    r.segments[s].state = s == 0 ? State::free : State::occupied;
  }
  return r;
}

// Writes, parses and checks what holds for every mesh: counts as declared, quads, valid ids,
// each vertex coloured as the segments of its faces, both readers agreeing.
ReadMesh write_and_read(const Result& r, double v, std::array<double, 3> origin, const std::string& name) {
  const std::string path = tmp(name);
  write_segments_ply(path, r, v, origin);
  ReadMesh m = parse(path);
  EXPECT_TRUE(m.binary_le);
  EXPECT_EQ(m.xyz.size(), m.declared_vertices);
  EXPECT_EQ(m.faces.size(), m.declared_faces);
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    EXPECT_EQ(m.faces[f].size(), 4u);
    const std::uint32_t s = m.segment[f];
    EXPECT_TRUE(s < r.segments.size() && r.segments[s].state == State::occupied) << "face " << f << " segment " << s;
    if (s >= r.segments.size()) continue;
    const Rgb c = segment_colour(s);
    for (const std::int32_t i : m.faces[f]) {
      EXPECT_TRUE(i >= 0 && std::size_t(i) < m.xyz.size());
      if (i >= 0 && std::size_t(i) < m.rgb.size()) {
        EXPECT_EQ(m.rgb[i], (std::array<int, 3>{c.r, c.g, c.b}));
      }
    }
  }
  pcl::PolygonMesh mesh;
  EXPECT_EQ(pcl::io::loadPLYFile(path, mesh), 0);
  EXPECT_EQ(mesh.polygons.size(), m.faces.size());
  EXPECT_EQ(std::size_t(mesh.cloud.width) * mesh.cloud.height, m.xyz.size());
  return m;
}

void expect_bounds(const ReadMesh& m, std::array<double, 3> lo, std::array<double, 3> hi) {
  for (int k = 0; k < 3; ++k) {
    float a = HUGE_VALF, b = -HUGE_VALF;
    for (const auto& p : m.xyz) {
      a = std::min(a, p[k]);
      b = std::max(b, p[k]);
    }
    EXPECT_FLOAT_EQ(a, float(lo[k])) << k;
    EXPECT_FLOAT_EQ(b, float(hi[k])) << k;
  }
}

}  // namespace

TEST(SegmentsPly, OneVoxelIsACubeOfSixFaces) {
  std::vector<std::uint32_t> labels(27, 0);
  labels[13] = 1;  // the middle of 3 x 3 x 3
  const ReadMesh m = write_and_read(result_of(Dims{3, 3, 3}, labels), 0.25, {1.0, -2.0, 0.5}, "one.ply");
  EXPECT_EQ(m.xyz.size(), 8u);
  EXPECT_EQ(m.faces.size(), 6u);
  expect_bounds(m, {1.25, -1.75, 0.75}, {1.5, -1.5, 1.0});
}

TEST(SegmentsPly, TwoVoxelsOfOneSegmentShareTheirFaceAway) {
  const ReadMesh m = write_and_read(result_of(Dims{2, 1, 1}, {1, 1}), 0.1, {0, 0, 0}, "two.ply");
  EXPECT_EQ(m.xyz.size(), 12u);
  EXPECT_EQ(m.faces.size(), 10u);
  expect_bounds(m, {0, 0, 0}, {0.2, 0.1, 0.1});
}

TEST(SegmentsPly, TwoTouchingSegmentsEachKeepAClosedSurface) {
  const ReadMesh m = write_and_read(result_of(Dims{2, 1, 1}, {1, 2}), 0.1, {0, 0, 0}, "touching.ply");
  EXPECT_EQ(m.xyz.size(), 16u);
  EXPECT_EQ(m.faces.size(), 12u);
  EXPECT_EQ(std::set<std::uint32_t>(m.segment.begin(), m.segment.end()), (std::set<std::uint32_t>{1, 2}));
}

// A 3 x 2 x 2 box found by segment(): 2 (3*2 + 3*2 + 2*2) = 32 faces; the 4 x 3 x 3 lattice
// points of its box less the 2 inside it = 34 vertices. Faces point outwards.
TEST(SegmentsPly, SegmentedBoxHasTheHandCountedSurface) {
  Grid g(Dims{9, 8, 8}, 0.12f, 0.05);
  g.origin = {-1.0, 2.0, 0.25};
  for (int z = 3; z < 5; ++z)
    for (int y = 2; y < 4; ++y)
      for (int x = 4; x < 7; ++x) g.at(x, y, z) = 0.97f;
  const Result r = segment(g, Params::defaults());
  const ReadMesh m = write_and_read(r, g.voxel_size, g.origin, "box.ply");
  EXPECT_EQ(m.faces.size(), 32u);
  EXPECT_EQ(m.xyz.size(), 34u);
  expect_bounds(m, {-1.0 + 0.2, 2.0 + 0.1, 0.25 + 0.15}, {-1.0 + 0.35, 2.0 + 0.2, 0.25 + 0.25});
  // Outward: each face's normal (corners counter-clockwise) points away from the box's centre.
  const std::array<float, 3> c{-1.0f + 0.275f, 2.0f + 0.15f, 0.25f + 0.2f};
  for (const auto& f : m.faces) {
    const auto &a = m.xyz[f[0]], &b = m.xyz[f[1]], &d = m.xyz[f[2]];
    const float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    const float n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    EXPECT_GT(n[0] * (a[0] - c[0]) + n[1] * (a[1] - c[1]) + n[2] * (a[2] - c[2]), 0.0f);
  }
}
