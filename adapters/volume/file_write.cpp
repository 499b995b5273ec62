#include "occseg/file_write.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "occseg/error.hpp"

namespace occseg {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw Error(Status::io, "cannot write '" + path + "': " + std::strerror(errno));
  try {
    write(out);
    out.flush();
    if (!out) throw Error(Status::io, "cannot write '" + path + "': write failed (disk full?)");
    out.close();
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
      throw Error(Status::io, "cannot write '" + path + "': " + std::strerror(errno));
  } catch (...) {
    out.close();
    std::remove(tmp.c_str());
    throw;
  }
}

}  // namespace occseg
