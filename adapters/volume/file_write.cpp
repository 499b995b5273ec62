#include "occseg/file_write.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "occseg/error.hpp"

namespace occseg {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  // Unique per call, not only per process: threads writing the same path must not share it.
  static std::atomic<unsigned long> calls{0};
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(calls.fetch_add(1));
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw Error(Status::io, "cannot write '" + path + "': " + std::strerror(errno));
  try {
    write(out);
    out.flush();
    if (!out) throw Error(Status::io, "cannot write '" + path + "': write failed (disk full?)");
    out.close();
    if (!out) throw Error(Status::io, "cannot write '" + path + "': closing failed (disk full?)");
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
      throw Error(Status::io, "cannot write '" + path + "': " + std::strerror(errno));
  } catch (...) {
    out.close();
    std::remove(tmp.c_str());
    throw;
  }
}

}  // namespace occseg
