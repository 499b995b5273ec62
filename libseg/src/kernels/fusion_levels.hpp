// The scan fusion's kernels of every level (select_fusion.cpp fills the table with them).
#pragma once
#include "kernels/fusion.hpp"

namespace occseg::kernels {

namespace scalar {
void fusion_walk_rays(const NextRay& next, std::uint8_t* marks, const Dims& dims, TouchBox& box,
                      std::vector<std::uint64_t>& hits);
}  // namespace scalar

#if defined(__SSE2__)
namespace sse2 {
void fusion_walk_rays(const NextRay& next, std::uint8_t* marks, const Dims& dims, TouchBox& box,
                      std::vector<std::uint64_t>& hits);
}  // namespace sse2
#endif

#if defined(__x86_64__) && defined(__GNUC__)
namespace avx2 {
void fusion_walk_rays(const NextRay& next, std::uint8_t* marks, const Dims& dims, TouchBox& box,
                      std::vector<std::uint64_t>& hits);
}  // namespace avx2
#endif

}  // namespace occseg::kernels
