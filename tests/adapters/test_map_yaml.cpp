// 2D robot maps (issue 26): map_server / Nav2 .yaml + PGM maps read as map_server reads them
// (thresholds, negate, modes, the image's top row at the largest y), the trinary PGM/YAML pair
// written back, OccupancyGrid int8 buffers through the C ABI, and the bad inputs of
// docs/reliability.md's table (each a pinned status and a message naming the file and problem).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "occseg/error.hpp"
#include "occseg/map_yaml.hpp"
#include "occseg/occseg.h"
#include "occseg/params.hpp"

using namespace occseg;
namespace fs = std::filesystem;

namespace {

std::string dir(const std::string& name) {
  const fs::path p = fs::path(OCCSEG_TEST_TMP) / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}
void put(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}
std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

const char* kYaml =
    "image: room.pgm\n"
    "resolution: 0.05\n"
    "origin: [-1.5, 2.25, 0.0]\n"
    "negate: 0\n"
    "occupied_thresh: 0.65\n"
    "free_thresh: 0.196\n";

// A room of 24 x 16 pixels as map_saver writes one: unknown (205) outside, a wall (0) ring,
// free (254) inside and a 3 x 2 box (0) near the image's top-left corner (so near the map's
// largest y).
std::vector<unsigned> room_pixels(std::size_t& w, std::size_t& h) {
  w = 24;
  h = 16;
  std::vector<unsigned> px(w * h, 205);
  for (std::size_t r = 2; r <= 13; ++r)
    for (std::size_t c = 2; c <= 21; ++c)
      px[r * w + c] = (r == 2 || r == 13 || c == 2 || c == 21) ? 0 : 254;
  for (std::size_t r = 4; r < 6; ++r)
    for (std::size_t c = 5; c < 8; ++c) px[r * w + c] = 0;
  return px;
}

std::string p5(const std::vector<unsigned>& px, std::size_t w, std::size_t h, unsigned maxval = 255) {
  std::string s = "P5\n# CREATOR: test\n" + std::to_string(w) + " " + std::to_string(h) + "\n" + std::to_string(maxval) + "\n";
  for (unsigned v : px) {
    if (maxval > 255) s += static_cast<char>(v >> 8);
    s += static_cast<char>(v & 0xFF);
  }
  return s;
}

std::string p2(const std::vector<unsigned>& px, std::size_t w, std::size_t h, unsigned maxval = 255) {
  std::string s = "P2\n" + std::to_string(w) + " " + std::to_string(h) + "\n# comment\n" + std::to_string(maxval) + "\n";
  for (std::size_t k = 0; k < px.size(); ++k) s += std::to_string(px[k]) + ((k + 1) % w ? " " : "\n");
  return s;
}

// The room map written into `d` as room.yaml + room.pgm; returns the .yaml path.
std::string write_room(const std::string& d, const std::string& yaml = kYaml, const std::string& image = "") {
  std::size_t w, h;
  const auto px = room_pixels(w, h);
  put(d + "/room.pgm", image.empty() ? p5(px, w, h) : image);
  put(d + "/room.yaml", yaml);
  return d + "/room.yaml";
}

struct Outcome {
  int status = 0;
  std::string message;
};

// Reads through the C ABI, as a C or Python caller does: the pinned OCCSEG_E* code.
Outcome c_read(const std::string& path) {
  occseg_map* m = nullptr;
  Outcome o;
  o.status = occseg_map_read(&m, path.c_str());
  o.message = occseg_last_error();
  EXPECT_EQ(m == nullptr, o.status != OCCSEG_OK);
  occseg_map_free(m);
  return o;
}

}  // namespace

TEST(MapServer, CellsFollowNav2LoadMapFromFile) {
  MapYaml m;
  m.occupied_thresh = 0.65;
  m.free_thresh = 0.196;
  PgmImage img;
  img.width = 6;
  img.height = 1;
  img.maxval = 255;
  // occ = 1 - v / 255: 0 -> 1, 89 -> 0.651, 90 -> 0.647, 205 -> 0.196078 (not below 0.196), 206 -> 0.192, 254
  img.pixels = {0, 89, 90, 205, 206, 254};
  EXPECT_EQ(map_server_cells(m, img), (std::vector<std::int8_t>{100, 100, -1, -1, 0, 0}));
  m.negate = true;  // occ = v / 255
  EXPECT_EQ(map_server_cells(m, img), (std::vector<std::int8_t>{0, -1, -1, 100, 100, 100}));
  m.negate = false;
  m.mode = MapMode::scale;  // in between: rint(100 (occ - free) / (occupied - free))
  const double occ90 = 1 - 90 / 255.0;
  const auto scaled = map_server_cells(m, img);
  EXPECT_EQ(scaled[2], static_cast<std::int8_t>(std::rint((occ90 - 0.196) / (0.65 - 0.196) * 100.0)));
  EXPECT_EQ(scaled[3], 0);  // occ 0.196078 rounds to 0 %, a graded cell, not unknown
  EXPECT_EQ(scaled[0], 100);
  EXPECT_EQ(scaled[5], 0);
  m.mode = MapMode::raw;  // the value itself when in 0..100, else unknown; negate ignored
  img.pixels = {0, 37, 100, 101, 205, 254};
  EXPECT_EQ(map_server_cells(m, img), (std::vector<std::int8_t>{0, 37, 100, -1, -1, -1}));
  // 16-bit: shade = v / maxval.
  img.maxval = 65535;
  img.pixels = {0, 65535, 65535 / 2, 0, 0, 0};
  m.mode = MapMode::trinary;
  EXPECT_EQ(map_server_cells(m, img)[0], 100);
  EXPECT_EQ(map_server_cells(m, img)[1], 0);
  EXPECT_EQ(map_server_cells(m, img)[2], -1);
}

TEST(MapServer, FirstImageRowIsTheLargestY) {
  MapYaml m;
  m.occupied_thresh = 0.65;
  m.free_thresh = 0.196;
  PgmImage img;
  img.width = 2;
  img.height = 3;
  img.maxval = 255;
  img.pixels = {0, 254, 205, 205, 254, 254};  // top row: occupied, free
  EXPECT_EQ(map_server_cells(m, img), (std::vector<std::int8_t>{0, 0, -1, -1, 100, 0}));
}

TEST(MapServer, OccupancyGridCellsToProbabilities) {
  float p = -1;
  EXPECT_TRUE(occupancy_cell_probability(-1, p));
  EXPECT_EQ(p, 0.5f);
  EXPECT_TRUE(occupancy_cell_probability(0, p));
  EXPECT_EQ(p, 0.0f);
  EXPECT_TRUE(occupancy_cell_probability(100, p));
  EXPECT_EQ(p, 1.0f);
  EXPECT_TRUE(occupancy_cell_probability(65, p));
  EXPECT_EQ(p, static_cast<float>(0.65));
  EXPECT_FALSE(occupancy_cell_probability(101, p));
  EXPECT_FALSE(occupancy_cell_probability(-2, p));
  EXPECT_FALSE(occupancy_cell_probability(-128, p));
}

TEST(MapServer, ReadsTheHandMadeRoomWithItsResolutionAndOrigin) {
  const std::string d = dir("room");
  const Grid g = read_map_yaml(write_room(d));
  EXPECT_EQ(g.dims, (Dims{24, 16, 1}));
  EXPECT_EQ(g.voxel_size, 0.05);
  EXPECT_EQ(g.origin, (std::array<double, 3>{-1.5, 2.25, 0.0}));
  // Image pixel (c, r) is grid cell (c, 15 - r).
  EXPECT_EQ(g.at(0, 15, 0), 0.5f);   // unknown corner
  EXPECT_EQ(g.at(2, 13, 0), 1.0f);   // wall, image row 2
  EXPECT_EQ(g.at(10, 8, 0), 0.0f);   // free
  EXPECT_EQ(g.at(5, 11, 0), 1.0f);   // the box: image rows 4..5 are y 11..10
  EXPECT_EQ(g.at(5, 10, 0), 1.0f);
  EXPECT_EQ(g.at(5, 4, 0), 0.0f);    // its mirror image is free
  // The C ABI reads the same map, through the built-in ".yaml" reader.
  occseg_map* m = nullptr;
  ASSERT_EQ(occseg_map_read(&m, (d + "/room.yaml").c_str()), OCCSEG_OK) << occseg_last_error();
  std::vector<float> v(g.p.size());
  ASSERT_EQ(occseg_map_values(m, v.data(), v.size()), OCCSEG_OK);
  EXPECT_EQ(v, g.p);
  double origin[3], vs;
  occseg_map_origin(m, origin);
  occseg_map_voxel_size(m, &vs);
  EXPECT_EQ(origin[0], -1.5);
  EXPECT_EQ(origin[1], 2.25);
  EXPECT_EQ(vs, 0.05);
  occseg_map_free(m);
}

TEST(MapServer, Pgm16BitPlainAndNegatedImagesGiveTheSameMap) {
  const Grid ref = read_map_yaml(write_room(dir("ref")));
  std::size_t w, h;
  const auto px = room_pixels(w, h);
  std::vector<unsigned> wide(px), inverted(px);
  for (auto& v : wide) v *= 257;  // 255 -> 65535
  for (auto& v : inverted) v = 255 - v;
  EXPECT_EQ(read_map_yaml(write_room(dir("p5_16"), kYaml, p5(wide, w, h, 65535))).p, ref.p);
  EXPECT_EQ(read_map_yaml(write_room(dir("p2"), kYaml, p2(px, w, h))).p, ref.p);
  std::string negated = kYaml;
  negated.replace(negated.find("negate: 0"), 9, "negate: 1");
  EXPECT_EQ(read_map_yaml(write_room(dir("neg"), negated, p5(inverted, w, h))).p, ref.p);
  negated.replace(negated.find("negate: 1"), 9, "negate: true");
  EXPECT_EQ(read_map_yaml(write_room(dir("neg_bool"), negated, p5(inverted, w, h))).p, ref.p);
}

TEST(MapServer, YamlSubsetVariantsMapServerFilesUse) {
  const std::string d = dir("variants");
  const Grid ref = read_map_yaml(write_room(d));
  const std::string variants[] = {
      "---\n# a comment\nimage: \"room.pgm\"   # quoted\nresolution: 5e-2\norigin:\n  - -1.5\n  - 2.25\n  - 0\n"
      "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\nunused_key: [1, 2]\n",
      "image: 'room.pgm'\r\nresolution: 0.050000\r\norigin: [ -1.500000, 2.250000, 0.000000 ]\r\nnegate: false\r\n"
      "occupied_thresh: 0.65\r\nfree_thresh: 0.196\r\n...\n",
  };
  for (const std::string& text : variants) {
    put(d + "/room.yaml", text);
    EXPECT_EQ(read_map_yaml(d + "/room.yaml").p, ref.p) << text;
  }
  // A quote inside a plain scalar is an ordinary character, not an opening quote.
  fs::copy_file(d + "/room.pgm", d + "/o'room.pgm", fs::copy_options::overwrite_existing);
  put(d + "/q.yaml", "image: o'room.pgm  # it's ours\nresolution: 0.05\norigin: [-1.5, 2.25, 0]\nnegate: 0\n"
                     "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  EXPECT_EQ(read_map_yaml(d + "/q.yaml").p, ref.p);
  // An absolute image path is used as it is.
  put(d + "/abs.yaml", "image: " + fs::absolute(d + "/room.pgm").string() + "\nresolution: 0.05\norigin: [-1.5, 2.25, 0]\n"
                       "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  EXPECT_EQ(read_map_yaml(d + "/abs.yaml").p, ref.p);
}

TEST(MapServer, ScaleModeKeepsGradedValues) {
  const std::string d = dir("scale");
  put(d + "/g.pgm", std::string("P5 3 1 255 ") + char(0) + char(128) + char(254));
  put(d + "/g.yaml", "image: g.pgm\nmode: scale\nresolution: 1\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const Grid g = read_map_yaml(d + "/g.yaml");
  const int mid = static_cast<int>(std::rint(((1 - 128 / 255.0) - 0.196) / (0.65 - 0.196) * 100.0));
  EXPECT_EQ(g.p[0], 1.0f);
  EXPECT_EQ(g.p[1], static_cast<float>(mid / 100.0));
  EXPECT_EQ(g.p[2], 0.0f);
}

TEST(MapServer, SegmentationPairRoundTripsThroughTheReader) {
  const std::string d = dir("pair");
  Grid g(Dims{5, 3, 1}, 0.5f, 0.1);
  g.origin = {-2.0, 0.3, 0.0};
  std::vector<std::uint8_t> states = {0, 1, 2, 2, 0, 1, 1, 0, 2, 0, 2, 2, 2, 1, 0};
  write_state_pgm(d + "/segmentation.pgm", g.dims, states);
  write_map_yaml(d + "/segmentation.yaml", "segmentation.pgm", g);
  const std::string pgm = slurp(d + "/segmentation.pgm");
  const std::string raster = pgm.substr(pgm.size() - 15);
  // Top row first: y = 2 is states[10..14].
  EXPECT_EQ(static_cast<unsigned char>(raster[0]), kPgmOccupied);
  EXPECT_EQ(static_cast<unsigned char>(raster[3]), kPgmUnknown);
  EXPECT_EQ(static_cast<unsigned char>(raster[4]), kPgmFree);
  const Grid back = read_map_yaml(d + "/segmentation.yaml");
  EXPECT_EQ(back.dims, g.dims);
  EXPECT_EQ(back.voxel_size, 0.1);
  EXPECT_EQ(back.origin, g.origin);
  Params p;
  for (std::size_t i = 0; i < states.size(); ++i) EXPECT_EQ(static_cast<int>(p.state_of(back.p[i])), states[i]) << i;
  EXPECT_THROW(write_state_pgm(d + "/x.pgm", Dims{2, 2, 2}, std::vector<std::uint8_t>(8)), Error);
  EXPECT_FALSE(fs::exists(d + "/x.pgm"));
}

TEST(MapServer, OccupancyGridBufferThroughTheCAbi) {
  // A room as an OccupancyGrid: -1 outside, walls 100, free 0 with graded 10 / 20, a box at 90.
  const size_t dims[3] = {12, 10, 1};
  std::vector<std::int8_t> cells(120, -1);
  for (std::size_t y = 1; y <= 8; ++y)
    for (std::size_t x = 1; x <= 10; ++x)
      cells[y * 12 + x] = (x == 1 || x == 10 || y == 1 || y == 8) ? 100 : static_cast<std::int8_t>((x + y) % 2 ? 10 : 0);
  cells[5 * 12 + 5] = cells[5 * 12 + 6] = 90;
  occseg_map* m = nullptr;
  ASSERT_EQ(occseg_map_from_buffer(&m, cells.data(), OCCSEG_I8_OCCUPANCY, dims, nullptr, 0.05), OCCSEG_OK)
      << occseg_last_error();
  std::vector<float> v(120);
  occseg_map_values(m, v.data(), v.size());
  EXPECT_EQ(v[0], 0.5f);
  EXPECT_EQ(v[12 + 1], 1.0f);
  EXPECT_EQ(v[5 * 12 + 5], 0.9f);
  EXPECT_EQ(v[2 * 12 + 3], static_cast<float>(0.1));
  occseg_map_free(m);
  cells[7 * 12 + 3] = 101;
  cells[9 * 12 + 11] = -7;
  EXPECT_EQ(occseg_map_from_buffer(&m, cells.data(), OCCSEG_I8_OCCUPANCY, dims, nullptr, 0.05), OCCSEG_EVALUE);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(std::string(occseg_last_error()).find("OccupancyGrid cell (3, 7, 0) = 101 is neither -1 (unknown) nor an occupancy in 0..100"),
            std::string::npos)
      << occseg_last_error();
}

// docs/reliability.md, rows "map_server .yaml" and "PGM image".
TEST(MapServer, BadYamlIsRefusedNamingFileLineAndProblem) {
  const std::string d = dir("bad_yaml");
  write_room(d);
  struct Row {
    std::string yaml;
    int status;
    std::string message;
  };
  const std::string tail = "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  const std::string head = "image: room.pgm\nresolution: 0.05\n";
  const Row rows[] = {
      {"resolution: 0.05\norigin: [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "no 'image' key"},
      {"", OCCSEG_EFORMAT, "no 'image' key"},
      {head + "origin: [0, 0, 0]\nnegate: 0\nfree_thresh: 0.196\n", OCCSEG_EFORMAT, "no 'occupied_thresh' key"},
      {head + "origin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n", OCCSEG_EFORMAT, "no 'negate' key"},
      {"image: nope.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n" + tail, OCCSEG_EIO, "image 'nope.pgm': cannot open"},
      {"image:\nresolution: 0.05\norigin: [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "line 1: image: expected the image file's name"},
      {"image: room.pgm\nresolution: 5 cm\norigin: [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "line 2: resolution: '5 cm' is not a finite number"},
      {"image: room.pgm\nresolution: 0\norigin: [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "line 2: resolution: 0 is not positive"},
      {"image: room.pgm\nresolution: nan\norigin: [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "'nan' is not a finite number"},
      {"image: room.pgm\nresolution: 0x10\norigin: [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "'0x10' is not a finite number"},
      {head + "origin: [0, 0]\n" + tail, OCCSEG_EFORMAT, "line 3: origin: expected [x, y, yaw], 3 numbers, not 2"},
      {head + "origin: 0\n" + tail, OCCSEG_EFORMAT, "line 3: origin: expected [x, y, yaw]"},
      {head + "origin: [0, 1e999, 0]\n" + tail, OCCSEG_EFORMAT, "'1e999' is not a finite number"},
      {head + "origin: [0, 0, 0.5]\n" + tail, OCCSEG_EUNSUPPORTED, "line 3: origin yaw 0.5 is not 0"},
      {head + "origin: [0, 0, 0]\n" + tail + "mode: Trinary\n", OCCSEG_EFORMAT, "line 7: mode: 'Trinary' is not trinary, scale or raw"},
      {head + "origin: [0, 0, 0]\nnegate: maybe\noccupied_thresh: 0.65\nfree_thresh: 0.196\n", OCCSEG_EFORMAT,
       "line 4: negate: 'maybe' is not 0, 1, true or false"},
      {head + "origin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 1.5\nfree_thresh: 0.196\n", OCCSEG_EFORMAT,
       "line 5: occupied_thresh: 1.5 is outside [0, 1]"},
      {head + "origin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.2\nfree_thresh: 0.3\n", OCCSEG_EFORMAT,
       "line 6: free_thresh 0.3 is above occupied_thresh 0.2"},
      {head + "origin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.3\nfree_thresh: 0.3\nmode: scale\n", OCCSEG_EFORMAT,
       "scale mode divides by their difference"},
      {head + "origin: {x: 0, y: 0}\n" + tail, OCCSEG_EFORMAT, "line 3: flow mappings ({...}) are not supported"},
      {head + "origin:\n  x: 0\n" + tail, OCCSEG_EFORMAT, "line 4: nested mappings are not supported"},
      {head + "origin: [0, [1], 0]\n" + tail, OCCSEG_EFORMAT, "line 3: nested sequences and mappings are not supported"},
      {head + "origin: [0, 0, 0\n" + tail, OCCSEG_EFORMAT, "line 3: a flow sequence must close with ']'"},
      {head + "origin: &o [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "line 3: anchors and aliases are not supported"},
      {head + "origin: [0, 0, 0]\nnegate: !!int 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n", OCCSEG_EFORMAT,
       "line 4: tags are not supported"},
      {"image: |\n  room.pgm\nresolution: 0.05\n", OCCSEG_EFORMAT, "line 1: block scalars (| and >) are not supported"},
      {head + "\torigin: [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "line 3: a tab in the indentation"},
      {head + "resolution: 0.1\norigin: [0, 0, 0]\n" + tail, OCCSEG_EFORMAT, "line 3: key 'resolution' appears twice (first on line 2)"},
      {"image: \"room.pgm\nresolution: 0.05\n", OCCSEG_EFORMAT, "line 1: unterminated quoted string"},
      {"just text\n", OCCSEG_EFORMAT, "line 1: expected 'key: value'"},
      {"- a\n- b\n", OCCSEG_EFORMAT, "line 1: a sequence item outside a key's value"},
      {head + "origin: [0, 0, 0]\n" + tail + "---\nimage: b.pgm\n", OCCSEG_EFORMAT, "line 7: a second YAML document"},
      {std::string("image: room.pgm\0\n", 17), OCCSEG_EFORMAT, "line 1: a NUL byte"},
  };
  for (const Row& r : rows) {
    put(d + "/bad.yaml", r.yaml);
    const Outcome o = c_read(d + "/bad.yaml");
    EXPECT_EQ(o.status, r.status) << r.yaml << "\n" << o.message;
    EXPECT_NE(o.message.find(r.message), std::string::npos) << r.yaml << "\n" << o.message;
    EXPECT_NE(o.message.find("bad.yaml'"), std::string::npos) << o.message;  // names the file
  }
  const Outcome missing = c_read(d + "/missing.yaml");
  EXPECT_EQ(missing.status, OCCSEG_EIO);
  EXPECT_NE(missing.message.find("cannot open '" + d + "/missing.yaml'"), std::string::npos) << missing.message;
  const Outcome directory = c_read(d);  // no extension: not ours
  EXPECT_EQ(directory.status, OCCSEG_EUNSUPPORTED);
  fs::create_directories(d + "/folder.yaml");
  const Outcome folder = c_read(d + "/folder.yaml");
  EXPECT_EQ(folder.status, OCCSEG_EIO);
  EXPECT_NE(folder.message.find("is a directory"), std::string::npos) << folder.message;
}

TEST(MapServer, BadPgmIsRefusedWithoutAllocatingWhatTheHeaderClaims) {
  const std::string d = dir("bad_pgm");
  std::size_t w, h;
  const auto px = room_pixels(w, h);
  const std::string good = p5(px, w, h);
  struct Row {
    std::string image;
    int status;
    std::string message;
  };
  const Row rows[] = {
      {good.substr(0, good.size() - 10), OCCSEG_EFORMAT, "truncated raster: 24 x 16 pixels need 384 bytes, the file has 374"},
      {good.substr(0, 10), OCCSEG_EFORMAT, "truncated"},
      {"", OCCSEG_EFORMAT, "wrong magic (expected P5 or P2)"},
      {"GIF89a....", OCCSEG_EFORMAT, "wrong magic (expected P5 or P2)"},
      {"P6\n2 2\n255\n" + std::string(12, 'x'), OCCSEG_EFORMAT, "it is a netpbm P6 file; map images are greyscale PGM"},
      {std::string("\x89PNG\r\n\x1a\n", 8) + std::string(32, '\0'), OCCSEG_EUNSUPPORTED, "is a PNG image; occseg reads map images as PGM"},
      {"P5\n2000000 2000000\n255\n", OCCSEG_EFORMAT, "2000000 x 2000000 pixels is more than 2^40"},
      {"P5\n100000 100000\n255\n" + std::string(100, 'x'), OCCSEG_EFORMAT, "truncated raster: 100000 x 100000 pixels need 10000000000 bytes"},
      {"P2\n100000 100000\n255\n1 2 3\n", OCCSEG_EFORMAT, "truncated raster"},
      {"P5\n99999999999999999999 1\n255\n", OCCSEG_EFORMAT, "the width is larger than"},
      {"P5\n0 4\n255\n", OCCSEG_EFORMAT, "0 x 4 pixels: a map needs at least one"},
      {"P5\n2 2\n0\n....", OCCSEG_EFORMAT, "maxval is 0"},
      {"P5\n2 2\n70000\n........", OCCSEG_EFORMAT, "the maxval is larger than 65535"},
      {"P5\n2 x\n255\n....", OCCSEG_EFORMAT, "the height is not a decimal number"},
      {"P5\n2 2\n100\n" + std::string("\x01\x02\x65\x03", 4), OCCSEG_EFORMAT, "pixel (0, 1) = 101 is above maxval 100"},
      {"P2\n2 2\n100\n1 2\n3 400\n", OCCSEG_EFORMAT, "pixel (1, 1) = 400 is above maxval 100"},
      {"P2\n2 2\n100\n1 2\n3 x\n", OCCSEG_EFORMAT, "the sample is not a decimal number"},
      {"P2\n2 2\n100\n1 2 3\n", OCCSEG_EFORMAT, "truncated raster: 3 of 4 samples"},
  };
  put(d + "/room.yaml", kYaml);
  for (const Row& r : rows) {
    put(d + "/room.pgm", r.image);
    const Outcome o = c_read(d + "/room.yaml");
    EXPECT_EQ(o.status, r.status) << r.image.substr(0, 40) << "\n" << o.message;
    EXPECT_NE(o.message.find(r.message), std::string::npos) << o.message;
    EXPECT_NE(o.message.find("'" + d + "/room.yaml': "), std::string::npos) << o.message;  // the YAML
    EXPECT_NE(o.message.find("room.pgm'"), std::string::npos) << o.message;               // and the image
  }
}

TEST(MapServer, RandomlyCorruptedFilesNeverCrashAndFailWithAFileStatus) {
  const std::string d = dir("corrupt");
  std::size_t w = 0, h = 0;
  const std::string good_pgm = p5(room_pixels(w, h), w, h);
  const std::string good_yaml = kYaml;
  std::mt19937 rng(26);
  for (int round = 0; round < 400; ++round) {
    std::string yaml = good_yaml, pgm = good_pgm;
    std::string& victim = round % 2 ? yaml : pgm;
    const std::size_t limit = round % 2 ? victim.size() : 40;  // the PGM's header, where the structure is
    for (int k = 0, n = 1 + int(rng() % 4); k < n; ++k) victim[rng() % limit] = static_cast<char>(rng() % 256);
    if (rng() % 4 == 0) victim.resize(rng() % victim.size());
    write_room(d, yaml, pgm);
    const Outcome o = c_read(d + "/room.yaml");
    EXPECT_TRUE(o.status == OCCSEG_OK || o.status == OCCSEG_EFORMAT || o.status == OCCSEG_EIO ||
                o.status == OCCSEG_EUNSUPPORTED)
        << o.status << " " << o.message;
  }
}
