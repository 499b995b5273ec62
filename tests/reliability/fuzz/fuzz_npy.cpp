// .npy reader: header parsing, dtypes, C and Fortran order, probability checks.
#include "fuzz_common.hpp"
#include "occseg/npy.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const occseg::NpyArray a = occseg::parse_npy(data, size, "fuzz.npy");
    if (a.data.size() != a.element_count() * (a.descr.back() == '8' ? 8 : a.descr.back() - '0')) std::abort();
    const occseg::Grid g = occseg::grid_from_npy(a, 1.0, "fuzz.npy");
    if (g.p.size() != g.dims.count() || g.p.size() != a.element_count()) std::abort();
  } catch (const occseg::Error& e) {
    occseg::fuzz::check_error(e);
  }
  return 0;
}
