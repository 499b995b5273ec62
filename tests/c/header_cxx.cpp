// occseg.h must compile warning-free as C++ (-Wall -Wextra -pedantic -Werror) and give the
// functions C linkage (a C++ caller links against the same symbols).
#include <occseg/occseg.h>

#include <type_traits>

static_assert(std::is_same<decltype(&occseg_segment),
                           int (*)(occseg_result**, const occseg_map*, const occseg_params*)>::value,
              "occseg_segment has the pinned signature");
static_assert(OCCSEG_EINVAL == -1 && OCCSEG_EINTERNAL == -11, "pinned status values");

int main() {
  occseg_map* map = nullptr;
  const size_t dims[3] = {1, 1, 1};
  const float p = 0.5f;
  const int rc = occseg_map_from_buffer(&map, &p, OCCSEG_F32, dims, nullptr, 1.0);
  occseg_map_free(map);
  return rc == OCCSEG_OK ? 0 : 1;
}
