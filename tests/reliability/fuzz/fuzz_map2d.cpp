// map_server maps: the YAML subset (first byte 'y') or a PGM image and the OccupancyGrid cells
// map_server makes of it (any other first byte), without files: both parsers take bytes.
#include "fuzz_common.hpp"
#include "occseg/map_yaml.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  try {
    if (data[0] == 'y') {
      const occseg::MapYaml m = occseg::parse_map_yaml(std::string(reinterpret_cast<const char*>(data + 1), size - 1), "fuzz.yaml");
      if (m.image.empty() || !(m.resolution > 0) || m.origin[2] != 0 || !(m.free_thresh <= m.occupied_thresh)) std::abort();
    } else {
      const occseg::PgmImage img = occseg::parse_pgm(data + 1, size - 1, "fuzz.pgm");
      if (img.pixels.size() != img.width * img.height || img.maxval == 0) std::abort();
      for (auto v : img.pixels)
        if (v > img.maxval) std::abort();
      occseg::MapYaml m;
      m.occupied_thresh = 0.65;
      m.free_thresh = 0.196;
      m.mode = static_cast<occseg::MapMode>(data[0] % 3);
      m.negate = data[0] & 4;
      for (auto c : occseg::map_server_cells(m, img))
        if (c < -1 || c > 100) std::abort();
    }
  } catch (const occseg::Error& e) {
    occseg::fuzz::check_error(e);
  }
  return 0;
}
