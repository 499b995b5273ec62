// Element types of per-voxel scratch that may live in storage of another type (internal).
// segment() keeps the stages' scratch (texture codes, bit rows) in the label array it allocates
// anyway, so every access to that scratch goes through these types, which may alias any type (a
// GCC and Clang attribute): type-based alias analysis then never reorders such accesses against
// the array's other uses, whatever the compiler inlines (LTO included).
#pragma once
#include <cstdint>

namespace occseg::detail {

typedef std::uint16_t __attribute__((__may_alias__)) code_t;  // texture codes, parked steps
typedef std::uint64_t __attribute__((__may_alias__)) word_t;  // bit rows (bit_rows.hpp)

}  // namespace occseg::detail
