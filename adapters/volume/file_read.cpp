#include "occseg/file_read.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "occseg/error.hpp"

namespace occseg {

namespace {

// Opens `path` for reading and rejects directories; returns the descriptor.
int open_file(const std::string& path, struct stat& st) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(Status::io, "cannot open '" + path + "': " + std::strerror(errno));
  const int err = ::fstat(fd, &st) != 0 ? errno : 0;
  if (err || S_ISDIR(st.st_mode)) {
    ::close(fd);
    // libstdc++'s streams would throw from inside the read here; say what it is instead.
    throw Error(Status::io, "cannot read '" + path + "': " + (err ? std::strerror(err) : "it is a directory"));
  }
  return fd;
}

struct Closer {
  int fd;
  ~Closer() { ::close(fd); }
};

}  // namespace

void check_readable(const std::string& path) {
  struct stat st {};
  Closer closer{open_file(path, st)};
}

std::string read_file(const std::string& path) {
  struct stat st {};
  const int fd = open_file(path, st);
  Closer closer{fd};
  std::string bytes;
  if (S_ISREG(st.st_mode) && st.st_size > 0) bytes.reserve(static_cast<std::size_t>(st.st_size));
  char buf[1 << 16];
  for (;;) {  // until end of file: sizes of pipes and /proc files are not known in advance
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw Error(Status::io, "cannot read '" + path + "': " + std::strerror(errno));
    }
    bytes.append(buf, static_cast<std::size_t>(n));
  }
  return bytes;
}

std::string printable(std::string_view text, std::size_t max_bytes) {
  static const char hex[] = "0123456789abcdef";
  std::string out;
  const std::size_t n = std::min(text.size(), max_bytes);
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '\\') {
      out += "\\\\";
    } else if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  if (n < text.size()) out += "...";
  return out;
}

}  // namespace occseg
