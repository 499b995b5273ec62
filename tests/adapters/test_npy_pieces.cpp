// read_npy_grid on maps large enough to be read by several threads in pieces and groups of
// pieces (issue 27): every dtype, byte order and memory order gives the values of the element
// formulas (computed here from the written array, not by the reader's code), on any thread
// count; a bad value is named as check_probabilities names the first one, whichever thread read
// the piece it is in.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/npy.hpp"

using namespace occseg;
namespace fs = std::filesystem;

namespace {

// 4.5 M voxels: 18 MB of float32 (two groups of 16 MB pieces, read by several threads), 36 MB
// of float64, 4.5 MB of uint8 (one thread).
const Dims kDims{300, 150, 100};

std::string tmp(const std::string& name) {
  fs::create_directories(std::string(OCCSEG_TEST_TMP) + "/npy_pieces");
  return std::string(OCCSEG_TEST_TMP) + "/npy_pieces/" + name;
}

// An .npy file of `values` (x fastest) as `descr` ('<f4', '>f8', '|u1', ...), in C or Fortran
// order, written here byte by byte.
void write_as(const std::string& path, const std::vector<double>& values, const std::string& descr, bool fortran) {
  std::string h = "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") + ", 'shape': (" +
                  std::to_string(kDims.nz) + ", " + std::to_string(kDims.ny) + ", " + std::to_string(kDims.nx) +
                  "), }";
  h.append((64 - (10 + h.size() + 1) % 64) % 64, ' ');
  h.push_back('\n');
  const std::size_t isz = std::stoul(descr.substr(2)), n = kDims.count();
  std::string body(n * isz, '\0');
  for (std::size_t z = 0, i = 0; z < kDims.nz; ++z)
    for (std::size_t y = 0; y < kDims.ny; ++y)
      for (std::size_t x = 0; x < kDims.nx; ++x, ++i) {
        const std::size_t at = fortran ? z + kDims.nz * (y + kDims.ny * x) : i;
        unsigned char b[8];
        const char kind = descr[1];
        if (kind == 'f' && isz == 4) {
          const float v = static_cast<float>(values[i]);
          std::memcpy(b, &v, 4);
        } else if (kind == 'f') {
          std::memcpy(b, &values[i], 8);
        } else if (isz == 2) {
          const auto v = static_cast<std::uint16_t>(values[i]);
          std::memcpy(b, &v, 2);
        } else {
          b[0] = static_cast<unsigned char>(values[i]);
        }
        for (std::size_t k = 0; k < isz; ++k) body[at * isz + k] = static_cast<char>(b[descr[0] == '>' ? isz - 1 - k : k]);
      }
  std::ofstream out(path, std::ios::binary);
  out << std::string("\x93NUMPY\x01\x00", 8) << char(h.size() & 0xff) << char(h.size() >> 8) << h << body;
}

// The probability NumPy's element means: f4 as stored, f8 rounded to float, u1/u2 v / max.
float expected(double v, const std::string& descr) {
  if (descr[1] == 'f') return static_cast<float>(descr[2] == '4' ? static_cast<double>(static_cast<float>(v)) : v);
  return static_cast<float>(v / (descr[2] == '1' ? 255.0 : 65535.0));
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(NpyPieces, EveryDtypeByteOrderAndMemoryOrderOnAnyThreadCount) {
  std::mt19937 rng(27);
  const std::size_t n = kDims.count();
  std::vector<double> probabilities(n), u8(n), u16(n);
  for (std::size_t i = 0; i < n; ++i) {
    probabilities[i] = std::uniform_real_distribution<double>(0, 1)(rng);
    u8[i] = double(rng() % 256);
    u16[i] = double(rng() % 65536);
  }
  struct Case {
    const char* descr;
    bool fortran;
  };
  for (const Case c : {Case{"<f4", false}, Case{">f4", false}, Case{"<f4", true}, Case{"<f8", false}, Case{">f8", true},
                       Case{"|u1", false}, Case{"|u1", true}, Case{"<u2", false}, Case{">u2", false}}) {
    const std::string descr = c.descr;
    const std::vector<double>& values = descr[1] == 'f' ? probabilities : descr[2] == '1' ? u8 : u16;
    const std::string f = tmp("map.npy");
    write_as(f, values, descr, c.fortran);
    for (int threads : {1, 3}) {
      const Grid g = read_npy_grid(f, 0.5, nullptr, {}, threads);
      ASSERT_EQ(g.p.size(), n);
      std::size_t differ = 0, first = n;
      for (std::size_t i = 0; i < n; ++i)
        if (g.p[i] != expected(values[i], descr)) {
          ++differ;
          first = std::min(first, i);
        }
      EXPECT_EQ(differ, 0u) << descr << (c.fortran ? " Fortran" : " C") << " order, " << threads
                            << " threads: first wrong voxel " << first;
    }
    fs::remove(f);
  }
}

TEST(NpyPieces, TheFirstBadValueIsNamedWhicheverThreadReadsIt) {
  const std::size_t n = kDims.count();
  // The first bad value late in the second group, a worse one in a later piece, each case also
  // with an earlier one in the first thread's part.
  for (const std::vector<std::pair<std::size_t, double>>& bad :
       {std::vector<std::pair<std::size_t, double>>{{n - 5, 1.5}},
        std::vector<std::pair<std::size_t, double>>{{n / 2 + 12345, -0.25}, {n - 1, std::nan("")}},
        std::vector<std::pair<std::size_t, double>>{{777, std::nan("")}, {n - 3000, 7.0}}}) {
    std::vector<double> values(n, 0.25);
    Grid g(kDims, 0.25f, 0.5);
    for (const auto& [i, v] : bad) {
      values[i] = v;
      g.p[i] = static_cast<float>(v);
    }
    const std::string why = message_of([&] { check_probabilities(g); });
    ASSERT_FALSE(why.empty());
    for (const char* descr : {"<f4", "<f8", ">f8"}) {
      const std::string f = tmp("bad.npy");
      write_as(f, values, descr, false);
      for (int threads : {1, 3}) {
        Status status = Status::ok;
        std::string message;
        try {
          read_npy_grid(f, 0.5, nullptr, {}, threads);
        } catch (const Error& e) {
          status = e.status();
          message = e.what();
        }
        EXPECT_EQ(status, Status::bad_value) << descr;
        EXPECT_EQ(message, "'" + f + "': " + why) << descr << ", " << threads << " threads";
      }
      fs::remove(f);
    }
  }
}
