// The support planes' kernels of every level (select_planes.cpp fills the table with them).
#pragma once
#include "kernels/planes.hpp"

namespace occseg::kernels {

namespace scalar {
double planes_cost(const PlanePoints& pts, const MsacPlane& pl, double cap, double stop);
void planes_cost_pair(const PlanePoints& pts, const MsacPlane& a, const MsacPlane& b, double cap, double stop,
                      double& cost_a, double& cost_b);
double planes_cost_inliers(const PlanePoints& pts, const MsacPlane& pl, double cap, double stop, double inlier,
                           std::uint32_t* out, std::size_t& count);
std::size_t planes_row_members(const std::uint32_t* row, std::size_t x0, std::size_t x1, std::uint32_t s,
                               std::uint64_t* bits);
}  // namespace scalar

#if defined(__x86_64__) && defined(__GNUC__)
namespace avx2 {
double planes_cost(const PlanePoints& pts, const MsacPlane& pl, double cap, double stop);
void planes_cost_pair(const PlanePoints& pts, const MsacPlane& a, const MsacPlane& b, double cap, double stop,
                      double& cost_a, double& cost_b);
double planes_cost_inliers(const PlanePoints& pts, const MsacPlane& pl, double cap, double stop, double inlier,
                           std::uint32_t* out, std::size_t& count);
std::size_t planes_row_members(const std::uint32_t* row, std::size_t x0, std::size_t x1, std::uint32_t s,
                               std::uint64_t* bits);
}  // namespace avx2
#endif

}  // namespace occseg::kernels
