// Maps from caller buffers large enough to be converted by several threads (issue 27): the copy
// (occseg_map_from_buffer) and the borrowed map (occseg_map_view_buffer, converted by each call)
// of every non-float32 dtype give the values of the conversion formulas, and a bad value is
// named as the first one in x-fastest order, whichever thread converts the row it is in.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "occseg/occseg.h"

namespace {

// 4.6 M voxels: several threads' worth of rows (the conversion goes parallel from 2 M voxels).
const size_t kDims[3] = {320, 120, 120};
const size_t kCount = kDims[0] * kDims[1] * kDims[2];

std::vector<float> values_of(occseg_map* m) {
  std::vector<float> v(kCount);
  EXPECT_EQ(occseg_map_values(m, v.data(), v.size()), OCCSEG_OK) << occseg_last_error();
  return v;
}

}  // namespace

TEST(LargeConversions, EveryDtypeCopiedOrBorrowedIsTheFormulaOfEachElement) {
  std::vector<double> f64(kCount);
  std::vector<std::uint8_t> u8(kCount);
  std::vector<std::uint16_t> u16(kCount);
  for (size_t i = 0; i < kCount; ++i) {
    f64[i] = double((i * 2654435761u) % 1000003) / 1000003.0;
    u8[i] = static_cast<std::uint8_t>(i * 7 + i / 320);
    u16[i] = static_cast<std::uint16_t>(i * 40503u);
  }
  struct Case {
    occseg_dtype dtype;
    const void* data;
  };
  for (const Case& c : {Case{OCCSEG_F64, f64.data()}, Case{OCCSEG_U8, u8.data()}, Case{OCCSEG_U16, u16.data()}}) {
    for (int borrowed = 0; borrowed < 2; ++borrowed) {
      occseg_map* m = nullptr;
      const int rc = borrowed ? occseg_map_view_buffer(&m, c.data, c.dtype, kDims, nullptr, 1.0, 0)
                              : occseg_map_from_buffer(&m, c.data, c.dtype, kDims, nullptr, 1.0);
      ASSERT_EQ(rc, OCCSEG_OK) << occseg_last_error();
      const std::vector<float> v = values_of(m);
      occseg_map_free(m);
      size_t differ = 0;
      for (size_t i = 0; i < kCount; ++i) {
        float want;
        switch (c.dtype) {
          case OCCSEG_F64: want = static_cast<float>(f64[i]); break;
          case OCCSEG_U8: want = static_cast<float>(u8[i] / 255.0); break;
          default: want = static_cast<float>(u16[i] / 65535.0); break;
        }
        differ += v[i] != want;
      }
      EXPECT_EQ(differ, 0u) << "dtype " << int(c.dtype) << (borrowed ? " borrowed" : " copied");
    }
  }
}

TEST(LargeConversions, TheFirstBadValueIsNamedWhicheverThreadConvertsIt) {
  // The first bad voxel in the last rows, a second one after it; the first at the end of the
  // first half's rows and the second at the start of the second half's (on 2, 4 or 8 threads, the
  // thread of the second half meets its bad value long before the first thread meets its own);
  // one early and one late.
  const size_t plane = kDims[0] * kDims[1], half = kCount / 2;
  for (const std::vector<size_t>& bad : {std::vector<size_t>{kCount - 400, kCount - 1},
                                         std::vector<size_t>{half - 300, half + 5},
                                         std::vector<size_t>{3 * plane + 5, kCount - 2 * plane}}) {
    std::vector<double> f64(kCount, 0.25);
    f64[bad[0]] = std::nan("");
    f64[bad[1]] = 2.0;
    const size_t i = bad[0];
    const std::string voxel = "(" + std::to_string(i % kDims[0]) + ", " + std::to_string(i / kDims[0] % kDims[1]) +
                              ", " + std::to_string(i / plane) + ") = nan is NaN";
    occseg_map* m = nullptr;
    EXPECT_EQ(occseg_map_from_buffer(&m, f64.data(), OCCSEG_F64, kDims, nullptr, 1.0), OCCSEG_EVALUE);
    EXPECT_EQ(m, nullptr);
    EXPECT_NE(std::string(occseg_last_error()).find("probability at voxel " + voxel), std::string::npos)
        << occseg_last_error();
    ASSERT_EQ(occseg_map_view_buffer(&m, f64.data(), OCCSEG_F64, kDims, nullptr, 1.0, 0), OCCSEG_OK);
    std::vector<float> v(kCount);
    EXPECT_EQ(occseg_map_values(m, v.data(), v.size()), OCCSEG_EVALUE);
    EXPECT_NE(std::string(occseg_last_error()).find("probability at voxel " + voxel), std::string::npos)
        << occseg_last_error();
    occseg_map_free(m);
  }
}
