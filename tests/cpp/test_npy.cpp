#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "occseg/error.hpp"
#include "occseg/npy.hpp"

using namespace occseg;
namespace fs = std::filesystem;

namespace {
std::string tmp(const std::string& name) {
  fs::create_directories(OCCSEG_TEST_TMP);
  return std::string(OCCSEG_TEST_TMP) + "/" + name;
}

// A v1.0 .npy written by hand, byte for byte as numpy.save would.
std::vector<unsigned char> hand_npy(const std::string& header_dict, const std::vector<unsigned char>& body) {
  std::string h = header_dict;
  while ((10 + h.size() + 1) % 64) h.push_back(' ');
  h.push_back('\n');
  std::vector<unsigned char> b = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0,
                                  static_cast<unsigned char>(h.size()), 0};
  b.insert(b.end(), h.begin(), h.end());
  b.insert(b.end(), body.begin(), body.end());
  return b;
}
}  // namespace

TEST(Npy, RoundTripFloatMap) {
  Grid g(Dims{3, 2, 2}, 0.25f);
  g.at(2, 1, 1) = 0.75f;
  write_grid_npy(tmp("rt.npy"), g);
  const NpyArray a = read_npy(tmp("rt.npy"));
  EXPECT_EQ(a.descr, "<f4");
  EXPECT_EQ(a.shape, (std::vector<std::size_t>{2, 2, 3}));
  const Grid h = grid_from_npy(a, 0.05, "rt.npy");
  EXPECT_EQ(h.p, g.p);
  EXPECT_DOUBLE_EQ(h.voxel_size, 0.05);
}

TEST(Npy, Uint8AndFortranOrder) {
  // shape (z=1, y=2, x=3) in Fortran order: file order is z fastest, then y, then x.
  // [y][x] = {{0, 51, 102}, {153, 204, 255}} -> file bytes: (y0x0, y1x0, y0x1, y1x1, y0x2, y1x2).
  const auto bytes = hand_npy("{'descr': '|u1', 'fortran_order': True, 'shape': (1, 2, 3), }",
                              {0, 153, 51, 204, 102, 255});
  const Grid g = grid_from_npy(parse_npy(bytes.data(), bytes.size(), "f.npy"), 1.0, "f.npy");
  ASSERT_EQ(g.dims, (Dims{3, 2, 1}));
  EXPECT_FLOAT_EQ(g.at(1, 0, 0), 0.2f);
  EXPECT_FLOAT_EQ(g.at(0, 1, 0), 0.6f);
  EXPECT_FLOAT_EQ(g.at(2, 1, 0), 1.0f);
}

TEST(Npy, BadFilesAreFormatErrors) {
  auto status_of = [](const std::vector<unsigned char>& b) {
    try {
      parse_npy(b.data(), b.size(), "x.npy");
    } catch (const Error& e) {
      return e.status();
    }
    return Status::ok;
  };
  auto good = hand_npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }", std::vector<unsigned char>(16, 0));
  EXPECT_EQ(status_of(good), Status::ok);
  auto truncated = good;
  truncated.resize(truncated.size() - 1);
  EXPECT_EQ(status_of(truncated), Status::format);
  auto magic = good;
  magic[1] = 'X';
  EXPECT_EQ(status_of(magic), Status::format);
  EXPECT_EQ(status_of(hand_npy("{'descr': '>f4', 'fortran_order': False, 'shape': (2, 2), }", {})), Status::format);
  EXPECT_EQ(status_of(hand_npy("{'descr': '>c8', 'fortran_order': False, 'shape': (1,), }", std::vector<unsigned char>(8, 0))),
            Status::format);
  EXPECT_EQ(status_of(hand_npy("{'descr': '<f4', 'fortran_order': False, 'shape': (1000000, 1000000), }", {})),
            Status::format);
  EXPECT_EQ(status_of({0x93, 'N'}), Status::format);
}

TEST(Npy, MissingFileIsIoError) {
  try {
    read_npy("/nonexistent/map.npy");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::io);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/map.npy"), std::string::npos);
  }
}

TEST(Npy, BigEndianElementsAreSwapped) {
  // NumPy writes an array of big-endian dtype as it is ('>f4' and its bytes, most significant
  // first) and np.load reads it back: so does occseg. 0.5f is 3f 00 00 00, 0.25 is 3f d0 00 .. 00.
  auto parse = [](const std::string& dict, const std::vector<unsigned char>& body) {
    const std::vector<unsigned char> b = hand_npy(dict, body);
    return parse_npy(b.data(), b.size(), "be.npy");
  };
  const NpyArray f = parse("{'descr': '>f4', 'fortran_order': False, 'shape': (1, 2), }",
                           {0x3f, 0x00, 0x00, 0x00, 0x3f, 0x80, 0x00, 0x00});
  EXPECT_TRUE(f.big_endian);
  EXPECT_EQ(f.descr, "<f4");
  EXPECT_EQ(grid_from_npy(f, 1.0, "be.npy").p, (std::vector<float>{0.5f, 1.0f}));
  const NpyArray d = parse("{'descr': '>f8', 'fortran_order': False, 'shape': (1, 1), }", {0x3f, 0xd0, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(grid_from_npy(d, 1.0, "be.npy").p, (std::vector<float>{0.25f}));
  const NpyArray u = parse("{'descr': '>u2', 'fortran_order': False, 'shape': (1, 2), }", {0xff, 0xff, 0x00, 0x01});
  EXPECT_EQ(grid_from_npy(u, 1.0, "be.npy").p, (std::vector<float>{1.0f, static_cast<float>(1 / 65535.0)}));
}
