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

const char* kind_of(mode_t m) {
  if (S_ISDIR(m)) return "it is a directory";
  if (S_ISFIFO(m)) return "it is not a regular file but a FIFO (named pipe)";
  if (S_ISCHR(m)) return "it is not a regular file but a character device";
  if (S_ISBLK(m)) return "it is not a regular file but a block device";
  if (S_ISSOCK(m)) return "it is not a regular file but a socket";
  return "it is not a regular file";
}

// Opens `path` for reading and accepts regular files only; returns the descriptor. O_NONBLOCK
// keeps the open of a FIFO from waiting for a writer (and is cleared before any read); a FIFO or
// a device could block forever or never end (/dev/zero), so neither is read at all.
int open_file(const std::string& path, struct stat& st) {
  int fd;
  do fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  while (fd < 0 && errno == EINTR);
  if (fd < 0) throw Error(Status::io, "cannot open '" + path + "': " + std::strerror(errno));
  int err = ::fstat(fd, &st) != 0 ? errno : 0;
  if (!err && S_ISREG(st.st_mode)) {
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) err = errno;
  }
  if (err || !S_ISREG(st.st_mode)) {
    ::close(fd);
    // libstdc++'s streams would throw from inside the read here; say what it is instead.
    throw Error(Status::io, "cannot read '" + path + "': " + (err ? std::strerror(err) : kind_of(st.st_mode)));
  }
  return fd;
}

struct Closer {
  int fd;
  ~Closer() { ::close(fd); }
};

}  // namespace

InputFile::InputFile(const std::string& path) : path_(path) {
  struct stat st {};
  fd_ = open_file(path, st);
  size_ = st.st_size > 0 ? static_cast<std::size_t>(st.st_size) : 0;
}

InputFile::~InputFile() { ::close(fd_); }

namespace {

// Calls `step(p + done, at_most, done)` (a read or pread of the rest) until n bytes are read or
// the file ends, in pieces of at most 1 GiB, retrying on EINTR; the bytes read.
template <class Step>
std::size_t read_fully(const std::string& path, void* buf, std::size_t n, Step step) {
  auto* p = static_cast<char*>(buf);
  std::size_t done = 0;
  while (done < n) {
    const ssize_t r = step(p + done, std::min<std::size_t>(n - done, std::size_t(1) << 30), done);
    if (r == 0) break;
    if (r < 0) {
      if (errno == EINTR) continue;
      throw Error(Status::io, "cannot read '" + path + "': " + std::strerror(errno));
    }
    done += static_cast<std::size_t>(r);
  }
  return done;
}

}  // namespace

std::size_t InputFile::read(void* buf, std::size_t n) {
  return read_fully(path_, buf, n, [this](char* p, std::size_t k, std::size_t) { return ::read(fd_, p, k); });
}

std::size_t InputFile::read_at(std::size_t offset, void* buf, std::size_t n) const {
  return read_fully(path_, buf, n, [this, offset](char* p, std::size_t k, std::size_t done) {
    return ::pread(fd_, p, k, static_cast<off_t>(offset + done));
  });
}

void check_readable(const std::string& path) {
  struct stat st {};
  Closer closer{open_file(path, st)};
}

std::string read_file(const std::string& path) {
  struct stat st {};
  const int fd = open_file(path, st);
  Closer closer{fd};
  std::string bytes;
  if (st.st_size > 0) bytes.reserve(static_cast<std::size_t>(st.st_size));
  char buf[1 << 16];
  for (;;) {  // until end of file: the size of /proc files is not known in advance
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
