// The 8-neighbour 3x3 LBP/C texture unit of the authors' earlier 2D method (Ojala, Pietikainen
// and Harwood's operator), behind the built-in texture operator "lbp8" for 2D maps (nz = 1).
#pragma once
#include <cstdint>

namespace occseg {

// Neighbour k of pixel (x, y) is (x + kLbp8Dx[k], y + kLbp8Dy[k]) and has weight 2^k, row by
// row from y - 1:   1   2   4
//                   8   .  16
//                  32  64 128
constexpr int kLbp8Dx[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
constexpr int kLbp8Dy[8] = {-1, -1, -1, 0, 0, 1, 1, 1};

struct TextureUnit8 {
  std::uint8_t lbp = 0;  // 0..255: bit k set when neighbour k >= centre
  double contrast = 0;   // mean(neighbours with bit 1) - mean(neighbours with bit 0); 0 if one side is empty
};

// The texture unit of one pixel from its eight neighbours in the order above.
TextureUnit8 texture_unit8(double centre, const double neighbours[8]);

}  // namespace occseg
