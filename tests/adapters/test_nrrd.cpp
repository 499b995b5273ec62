// NRRD read/write and the .npy writers for every C ABI dtype.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>
#include <filesystem>
#include <fstream>
#include <limits>

#include "occseg/error.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"

using namespace occseg;
namespace fs = std::filesystem;

namespace {
std::string tmp(const std::string& name) {
  fs::create_directories(OCCSEG_TEST_TMP);
  return std::string(OCCSEG_TEST_TMP) + "/" + name;
}
void put(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}
std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
Status status_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.status();
  }
  return Status::ok;
}
Grid ramp() {
  Grid g(Dims{4, 3, 2}, 0.5f, 0.25);
  g.origin = {-1.0, 2.0, 0.5};
  for (std::size_t i = 0; i < g.p.size(); ++i) g.p[i] = float(i) / 23.0f;
  return g;
}
}  // namespace

TEST(Nrrd, MapRoundTripKeepsValuesAndGeometry) {
  const Grid g = ramp();
  const std::string f = tmp("ramp.nrrd");
  write_grid_nrrd(f, g);
  const std::string text = slurp(f);
  // The header as ParaView/Slicer read it: voxel centres, RAS space, exact short numbers.
  EXPECT_NE(text.find("type: float\n"), std::string::npos);
  EXPECT_NE(text.find("sizes: 4 3 2\n"), std::string::npos);
  EXPECT_NE(text.find("space directions: (0.25,0,0) (0,0.25,0) (0,0,0.25)\n"), std::string::npos);
  EXPECT_NE(text.find("space origin: (-0.875,2.125,0.625)\n"), std::string::npos) << "corner + half a voxel";
  EXPECT_NE(text.find("space: right-anterior-superior\n"), std::string::npos);
  const Grid back = grid_from_nrrd(read_nrrd(f), f);
  EXPECT_TRUE(back.dims == g.dims);
  EXPECT_DOUBLE_EQ(back.voxel_size, 0.25);
  for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(back.origin[k], g.origin[k]);
  EXPECT_EQ(back.p, g.p);
}

TEST(Nrrd, LabelsAreUint32AndNotAMap) {
  const Grid g = ramp();
  LabelArray labels(g.p.size());
  for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = std::uint32_t(i * 1000003u);
  const std::string f = tmp("labels.nrrd");
  write_labels_nrrd(f, g, labels);
  const NrrdVolume v = read_nrrd(f);
  ASSERT_EQ(v.type, NrrdType::u32);
  ASSERT_EQ(v.data.size(), labels.size() * 4);
  EXPECT_EQ(std::memcmp(v.data.data(), labels.data(), v.data.size()), 0);
  EXPECT_EQ(status_of([&] { grid_from_nrrd(v, f); }), Status::format);
  EXPECT_EQ(status_of([&] { write_labels_nrrd(f, g, {1, 2}); }), Status::invalid_argument);
}

TEST(Nrrd, HandWrittenBigEndianAndAsciiFiles) {
  // uint16, big endian, 2x1x1, spacings instead of space directions.
  const std::string be = tmp("be.nrrd");
  put(be, std::string("NRRD0004\ntype: ushort\ndimension: 3\nsizes: 2 1 1\nspacings: 0.5 0.5 0.5\nendian: big\n"
                      "encoding: raw\n\n") + std::string("\xff\xff\x00\x00", 4));
  const Grid g = grid_from_nrrd(read_nrrd(be), be);
  EXPECT_FLOAT_EQ(g.p[0], 1.0f);
  EXPECT_FLOAT_EQ(g.p[1], 0.0f);
  EXPECT_DOUBLE_EQ(g.voxel_size, 0.5);
  EXPECT_DOUBLE_EQ(g.origin[0], -0.25) << "no space origin: the first centre is at 0";
  // ascii doubles, 2D, CRLF line ends, a comment and a key/value pair.
  const std::string a = tmp("ascii.nrrd");
  put(a, "NRRD0005\r\n# comment\r\ntype: double\r\ndimension: 2\r\nsizes: 3 1\r\nencoding: ascii\r\nkey:=value\r\n"
         "space dimension: 2\r\nspace origin: (1,2)\r\n\r\n0.25 0.5\n0.75\n");
  const Grid h = grid_from_nrrd(read_nrrd(a), a);
  EXPECT_TRUE(h.dims == (Dims{3, 1, 1}));
  EXPECT_FLOAT_EQ(h.p[2], 0.75f);
  EXPECT_DOUBLE_EQ(h.origin[1], 1.5);
}

TEST(Nrrd, BadFilesGiveStatusesNamingTheFile) {
  EXPECT_EQ(status_of([] { read_nrrd(tmp("missing.nrrd")); }), Status::io);
  const std::string hdr = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nendian: little\n";
  const std::string f = tmp("bad.nrrd");
  put(f, hdr + "encoding: raw\n\n" + std::string(31, '\0'));  // one byte short
  try {
    read_nrrd(f);
    FAIL() << "truncated file accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::format);
    EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  put(f, hdr + "encoding: gzip\n\n");  // gzip is read (issue 27); no data is a truncated stream
  EXPECT_EQ(status_of([&] { read_nrrd(f); }), Status::format);
  put(f, hdr + "encoding: bzip2\n\n");
  EXPECT_EQ(status_of([&] { read_nrrd(f); }), Status::unsupported);
  put(f, hdr + "encoding: raw\nspace: RAS\nspace directions: (0,1,0) (1,0,0) (0,0,1)\n\n" + std::string(32, '\0'));
  EXPECT_EQ(status_of([&] { read_nrrd(f); }), Status::unsupported) << "rotated axes";
  put(f, hdr + "encoding: raw\n" + std::string(32, '\0'));
  EXPECT_EQ(status_of([&] { read_nrrd(f); }), Status::format) << "no blank line";
  put(f, "P6\n");
  EXPECT_EQ(status_of([&] { read_nrrd(f); }), Status::format);
  put(f, "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nspacings: 1 2 1\nendian: little\nencoding: raw\n\n" +
             std::string(32, '\0'));
  EXPECT_EQ(status_of([&] { grid_from_nrrd(read_nrrd(f), f); }), Status::format) << "anisotropic";
  float two = 2.0f;
  put(f, hdr + "encoding: raw\n\n" + std::string(reinterpret_cast<char*>(&two), 4) + std::string(28, '\0'));
  EXPECT_EQ(status_of([&] { grid_from_nrrd(read_nrrd(f), f); }), Status::bad_value);
}

namespace {
// Status and message of read_nrrd on a file holding `bytes`.
std::pair<Status, std::string> read_status(const std::string& name, const std::string& bytes) {
  const std::string f = tmp(name);
  put(f, bytes);
  try {
    read_nrrd(f);
  } catch (const Error& e) {
    return {e.status(), e.what()};
  }
  return {Status::ok, ""};
}
}  // namespace

TEST(Nrrd, FieldsAreMatchedAsTeemMatchesThem) {
  const std::string data(8 * 4, '\0');
  // Any case, teem's spellings: all of these are fields teem reads, and so does occseg.
  const std::string shouted = "NRRD0004\nTYPE: FLOAT\nDimension: 3\nSPACE: RAS\nSizes: 2 2 2\n"
                              "Space Directions: (0.5,0,0) (0,0.5,0) (0,0,0.5)\nENDIAN: LITTLE\nEncoding: RAW\n"
                              "SpaceOrigin: (1,2,3)\n\n";
  put(tmp("shouted.nrrd"), shouted + data);
  const NrrdVolume v = read_nrrd(tmp("shouted.nrrd"));
  EXPECT_EQ(v.type, NrrdType::f32);
  EXPECT_EQ(v.spacing, (std::array<double, 3>{0.5, 0.5, 0.5})) << "Space Directions was read";
  EXPECT_EQ(v.origin, (std::array<double, 3>{1, 2, 3})) << "SpaceOrigin was read";
  EXPECT_EQ(v.space, "right-anterior-superior");
  // "Data File:" names the data elsewhere: the bytes after the header are not the samples
  // (occseg once skipped the field and read them).
  const std::string hdr = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n";
  for (const char* line : {"Data File: other.raw\n", "DATAFILE: other.raw\n", "data file: x:=y\n"}) {
    const auto r = read_status("detached.nrrd", hdr + line + "\n" + data);
    EXPECT_EQ(r.first, Status::unsupported) << line << r.second;
    EXPECT_NE(r.second.find("detached data files"), std::string::npos) << r.second;
  }
  // What teem refuses: a field twice, a line naming no field, per-axis fields before the
  // dimension, vectors before the space, both kinds of space, a magic it does not know.
  const std::vector<std::pair<std::string, std::string>> refused = {
      {hdr + "sizes: 4 4 4\n", "the field 'sizes' appears twice"},
      {hdr + "Encoding: ascii\n", "the field 'encoding' appears twice"},
      {hdr + "colour: red\n", "'colour' is not a NRRD field"},
      {hdr + "typo line\n", "is not 'field: value'"},
      {"NRRD0004\ntype: float\nsizes: 2 2 2\ndimension: 3\nendian: little\nencoding: raw\n", "'sizes' comes before 'dimension'"},
      {hdr + "space directions: (1,0,0) (0,1,0) (0,0,1)\n", "'space directions' comes before 'space'"},
      {hdr + "space origin: (0,0,0)\n", "'space origin' comes before 'space'"},
      {hdr + "space: LPS\nspace dimension: 3\n", "both 'space' and 'space dimension'"},
      {hdr + "space: up-down-sideways\n", "is not a NRRD space"},
      {hdr + "space: RAS\nspace origin: (0,0)\n", "malformed space origin"},
      {"NRRD0009\ntype: float\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n", "is not a NRRD magic"},
      {"NRRD0004\ntype: float\ndimension: 99999999999999999999\n", "dimension '99999999999999999999' is not a number"},
  };
  for (const auto& c : refused) {
    const auto r = read_status("refused.nrrd", c.first + "\n" + data);
    EXPECT_EQ(r.first, Status::format) << c.first << r.second;
    EXPECT_NE(r.second.find(c.second), std::string::npos) << c.first << r.second;
  }
  const auto skip = read_status("skip.nrrd", hdr + "byte skip: 99999999999999999999999\n\n" + data);
  EXPECT_EQ(skip.first, Status::unsupported) << skip.second;
  const auto time = read_status("time.nrrd", hdr + "space: RAST\n\n" + data);
  EXPECT_EQ(time.first, Status::unsupported) << time.second;
  // A line with both ": " and ":=" whose field part is no field is a key/value pair.
  EXPECT_EQ(read_status("kv.nrrd", hdr + "my key: with colon:=value\n\n" + data).first, Status::ok);
}

TEST(Nrrd, TheFilesSpaceIsKeptAndWrittenBack) {
  // 3D Slicer saves in left-posterior-superior: the grid is in LPS coordinates, and labels
  // written with the volume's space lie on it. Written as RAS with the same numbers (as they
  // once were) they came out mirrored in x and y.
  const std::string f = tmp("lps.nrrd");
  put(f, "NRRD0004\ntype: float\ndimension: 3\nspace: LPS\nsizes: 4 3 2\n"
         "space directions: (0.5,0,0) (0,0.5,0) (0,0,0.5)\nendian: little\nencoding: raw\n"
         "space origin: (10.25,-20.5,3)\n\n" + std::string(24 * 4, '\0'));
  const NrrdVolume v = read_nrrd(f);
  EXPECT_EQ(v.space, "left-posterior-superior");
  const Grid g = grid_from_nrrd(v, f);
  EXPECT_EQ(g.origin, (std::array<double, 3>{10.0, -20.75, 2.75}));
  const LabelArray labels(g.p.size(), 7u);
  const std::string out = tmp("lps_labels.nrrd");
  write_labels_nrrd(out, g, labels, v.space);
  const std::string text = slurp(out);
  EXPECT_NE(text.find("\nspace: left-posterior-superior\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\nspace directions: (0.5,0,0) (0,0.5,0) (0,0,0.5)\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\nspace origin: (10.25,-20.5,3)\n"), std::string::npos) << text;
  EXPECT_EQ(read_nrrd(out).space, "left-posterior-superior");
  // No space given: RAS, as before. A name that is no 3D space is refused.
  write_labels_nrrd(out, g, labels);
  EXPECT_NE(slurp(out).find("\nspace: right-anterior-superior\n"), std::string::npos);
  EXPECT_EQ(status_of([&] { write_labels_nrrd(out, g, labels, "RAST"); }), Status::invalid_argument);
  EXPECT_EQ(status_of([&] { write_labels_nrrd(out, g, labels, "sideways"); }), Status::invalid_argument);
}

// The writer refuses a geometry its reader would refuse (the C++ Grid is an open struct, so a
// caller can build any): before, an origin of DBL_MAX with big voxels was written as
// "space origin: (inf, ...)", and one of 1.7e308 as a map whose voxels all share x.
TEST(Nrrd, WriterRefusesGeometryItsReaderRefusesAndWritesNothing) {
  auto refused = [](Grid g, const std::string& name, const std::string& words) {
    const std::string f = tmp(name);
    fs::remove(f);
    try {
      write_grid_nrrd(f, g);
      ADD_FAILURE() << name << " was written";
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::bad_value) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
    for (const auto& e : fs::directory_iterator(fs::path(f).parent_path()))  // no file, no temporary
      EXPECT_NE(e.path().filename().string().rfind(name, 0), 0u) << e.path();
  };
  Grid g = ramp();
  g.origin = {std::numeric_limits<double>::max(), 0, 0};
  g.voxel_size = 1e300;  // centre = origin + 5e299 = inf
  refused(g, "centre_inf.nrrd", "out of range");
  g = ramp();
  g.origin = {1.7e308, 0, 0};
  refused(g, "far_origin.nrrd", "out of range");
  g = ramp();
  g.voxel_size = 1e308;  // 4 voxels: far corner inf
  refused(g, "extent_inf.nrrd", "out of range");
  g = ramp();
  g.voxel_size = std::numeric_limits<double>::quiet_NaN();
  refused(g, "nan_voxel.nrrd", "voxel size");
  // The reader refuses the same, naming the file.
  const std::string f = tmp("far_read.nrrd");
  put(f, "NRRD0004\ntype: float\ndimension: 3\nspace: RAS\nsizes: 1 1 1\nspace directions: (1,0,0) (0,1,0) (0,0,1)\n"
         "endian: little\nencoding: raw\nspace origin: (0,1e300,0)\n\n" + std::string(4, '\0'));
  try {
    grid_from_nrrd(read_nrrd(f), f);
    ADD_FAILURE() << "read";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::bad_value) << e.what();
    EXPECT_NE(std::string(e.what()).find("far_read.nrrd"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
  }
  // .npy carries no geometry, so grid_from_npy checks the voxel size it is given.
  const std::string n = tmp("small.npy");
  const float zeros[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  write_npy(n, "<f4", {2, 2, 2}, zeros, sizeof zeros);
  EXPECT_EQ(status_of([&] { grid_from_npy(read_npy(n), 1e308, n); }), Status::bad_value);
  EXPECT_EQ(status_of([&] { grid_from_npy(read_npy(n), std::nan(""), n); }), Status::bad_value);
  EXPECT_EQ(status_of([&] { grid_from_npy(read_npy(n), 0.05, n); }), Status::ok);
}

TEST(NpyWriters, EveryCAbiDtypeRoundTrips) {
  const Grid g = ramp();
  for (const char* d : {"<f4", "<f8", "|u1", "<u2"}) {
    const std::string f = tmp(std::string("ramp_") + (d[1] == 'u' ? "u" : "f") + d[2] + ".npy");
    write_grid_npy_as(f, g, d);
    const NpyArray a = read_npy(f);
    EXPECT_EQ(a.descr, d);
    ASSERT_EQ(a.shape, (std::vector<std::size_t>{2, 3, 4}));
    const Grid back = grid_from_npy(a, 1.0, f);
    const double tol = d[1] == 'u' ? (d[2] == '1' ? 0.5 / 255 : 0.5 / 65535) + 1e-7 : 1e-7;
    for (std::size_t i = 0; i < g.p.size(); ++i) EXPECT_NEAR(back.p[i], g.p[i], tol) << d << " " << i;
  }
  // Quantisation by hand: 0.5 * 255 = 127.5 rounds to 128.
  Grid half(Dims{1, 1, 1}, 0.5f);
  write_grid_npy_as(tmp("half.npy"), half, "|u1");
  EXPECT_EQ(read_npy(tmp("half.npy")).data[0], 128);
  EXPECT_EQ(status_of([&] { write_grid_npy_as(tmp("x.npy"), g, "<i8"); }), Status::invalid_argument);
}
