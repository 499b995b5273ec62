// segments.json: the segment table as written by `occseg segment`.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "occseg/segment.hpp"

namespace occseg::cli {

nlohmann::json segments_json(const Result& r, const std::string& preset);

}  // namespace occseg::cli
