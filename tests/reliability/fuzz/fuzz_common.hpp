// Shared by the fuzz targets: the file readers take paths, so each input is written to an
// in-memory file (memfd) and read back through /proc/self/fd/N, never touching the disk.
#pragma once
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "occseg/error.hpp"

namespace occseg::fuzz {

// Replaces the content of this process's scratch file with `data` and returns its path.
inline std::string as_file(const std::uint8_t* data, std::size_t size) {
  static const int fd = ::memfd_create("occseg-fuzz", 0);
  if (fd < 0 || ::ftruncate(fd, 0) != 0) std::abort();
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pwrite(fd, data + done, size - done, static_cast<off_t>(done));
    if (n <= 0) std::abort();
    done += static_cast<std::size_t>(n);
  }
  return "/proc/self/fd/" + std::to_string(fd);
}

// Every rejection must be a documented status with a message; anything else is a finding.
inline void check_error(const Error& e) {
  const int s = static_cast<int>(e.status());
  if (s > -1 || s < -11 || s == static_cast<int>(Status::internal) || std::strlen(e.what()) == 0) std::abort();
}

}  // namespace occseg::fuzz
