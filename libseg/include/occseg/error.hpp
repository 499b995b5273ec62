// occseg::Error: the one exception type of the C++ core. It carries a status code that maps
// one-to-one onto the C ABI's OCCSEG_E* values, so capi/ can translate without guessing.
#pragma once
#include <stdexcept>
#include <string>

namespace occseg {

// Pinned values: identical to the OCCSEG_E* codes of include/occseg/occseg.h.
enum class Status : int {
  ok = 0,
  invalid_argument = -1,  // NULL pointer, bad enum, bad parameter name or value
  bad_dims = -2,          // zero, overflowing or too-large dimensions
  bad_value = -3,         // NaN, infinity or probability outside [0, 1]
  no_memory = -4,         // allocation failed
  io = -5,                // file cannot be opened, read or written
  format = -6,            // file is truncated, corrupt or not of the expected format
  out_of_range = -7,      // index out of range, output buffer too small
  cancelled = -8,         // the progress callback asked to stop
  plugin = -9,            // plugin failed to load or register
  unsupported = -10,      // valid request this build cannot serve
  internal = -11,         // a bug: please report
};

class Error : public std::runtime_error {
 public:
  Error(Status status, const std::string& message) : std::runtime_error(message), status_(status) {}
  Status status() const noexcept { return status_; }

 private:
  Status status_;
};

}  // namespace occseg
