// Reading whole input files, with errors that name the file and the problem (missing, not
// permitted, a directory, an I/O error) rather than a stream exception or an empty read.
#pragma once
#include <cstddef>
#include <ios>
#include <streambuf>
#include <string>
#include <string_view>

namespace occseg {

// The bytes of `path`, a regular file (or a symbolic link to one). Throws Error(io) "cannot open
// 'path': <reason>", "cannot read 'path': it is a directory", "... it is not a regular file but
// a FIFO (named pipe)" (or a device, a socket: refused without reading or blocking), or "cannot
// read 'path': <reason>".
std::string read_file(const std::string& path);

// A regular file opened with the checks of read_file, for readers that read it in pieces
// straight into their own arrays (no copy of the whole file first).
class InputFile {
 public:
  explicit InputFile(const std::string& path);  // the errors of read_file
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  std::size_t size() const { return size_; }  // when it was opened
  // Reads up to `n` bytes into `buf`; fewer only at the end of the file. Throws Error(io)
  // "cannot read 'path': <reason>".
  std::size_t read(void* buf, std::size_t n);
  // Reads up to `n` bytes from `offset` into `buf` (pread: the file position is neither used nor
  // moved, so several threads may read disjoint ranges of one file at once); fewer only at the
  // end of the file. The errors of read().
  std::size_t read_at(std::size_t offset, void* buf, std::size_t n) const;

 private:
  std::string path_;
  int fd_ = -1;
  std::size_t size_ = 0;
};

// Throws the same errors when `path` cannot be opened for reading or is not a regular file, for
// readers that hand the path on to a library (PCL, OctoMap).
void check_readable(const std::string& path);

// File content as it may appear in a message: printable ASCII is kept, a backslash is doubled,
// and every other byte (control characters, terminal escape sequences, bytes >= 0x80) becomes
// \xNN; at most `max_bytes` bytes of `text` are shown, and "..." marks a cut. Every reader that
// quotes bytes of its file in an error goes through this, so no message carries the file's
// control sequences to a terminal or a log.
std::string printable(std::string_view text, std::size_t max_bytes = 64);

// A read-only, seekable stream buffer over bytes held elsewhere (they must outlive it), so that
// a file read once can be parsed with std::istream without a copy. A reader checks the bytes
// and hands the library these same bytes, never the path a second time (the file may change).
class BytesBuf : public std::streambuf {
 public:
  explicit BytesBuf(std::string_view bytes) {
    char* p = const_cast<char*>(bytes.data());  // the get area is only read
    setg(p, p, p + bytes.size());
  }

 protected:
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    if (!(which & std::ios_base::in)) return pos_type(off_type(-1));
    const off_type base = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? gptr() - eback() : egptr() - eback();
    const off_type to = base + off;
    if (to < 0 || to > egptr() - eback()) return pos_type(off_type(-1));
    setg(eback(), eback() + to, egptr());
    return pos_type(to);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }
};

}  // namespace occseg
