#include "segments_json.hpp"

namespace occseg::cli {

nlohmann::json segments_json(const Result& r, const std::string& preset) {
  nlohmann::json segs = nlohmann::json::array();
  for (const Segment& s : r.segments) {
    segs.push_back({{"id", s.id},
                    {"state", state_name(s.state)},
                    {"voxels", s.voxels},
                    {"mop", s.mop},
                    {"bbox", {{"min", s.bbox_min}, {"max", s.bbox_max}}},
                    {"centroid", s.centroid}});
  }
  return {{"dims", {r.dims.nx, r.dims.ny, r.dims.nz}}, {"preset", preset}, {"segments", segs}};
}

}  // namespace occseg::cli
