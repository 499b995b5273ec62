#include "occseg/file_write.hpp"

#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "occseg/error.hpp"

namespace occseg {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& why) {
  throw Error(Status::io, "cannot write '" + path + "': " + why);
}

std::string reason(int err) { return std::strerror(err); }

std::string dir_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

bool is_directory(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

// 64 random bits. The name only needs to be unguessable so that nobody can plant it before it is
// created (O_EXCL refuses it then, and another is drawn); the fallback, for a kernel without
// getrandom, mixes what differs between calls and processes.
std::uint64_t random_bits() {
  std::uint64_t v = 0;
  if (::getrandom(&v, sizeof v, GRND_NONBLOCK) == static_cast<ssize_t>(sizeof v)) return v;
  static std::atomic<std::uint64_t> calls{0};
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  v = (std::uint64_t(::getpid()) << 32) ^ std::uint64_t(ts.tv_nsec) ^ (std::uint64_t(ts.tv_sec) << 20) ^
      (calls.fetch_add(1) * 0x9E3779B97F4A7C15ull) ^ reinterpret_cast<std::uintptr_t>(&v);
  v ^= v >> 31;  // splitmix64's finaliser spreads the bits
  v *= 0xBF58476D1CE4E5B9ull;
  v ^= v >> 27;
  return v;
}

// `NAME.tmp-` + 16 hex digits beside `path`, NAME shortened where the whole would exceed NAME_MAX.
std::string temp_name(const std::string& path) {
  static constexpr std::size_t kSuffix = 5 + 16;  // ".tmp-" + digits
  const std::size_t slash = path.find_last_of('/');
  const std::size_t base_at = slash == std::string::npos ? 0 : slash + 1;
  std::string t = path.substr(0, base_at);
  t += path.substr(base_at, std::min(path.size() - base_at, std::size_t(NAME_MAX) - kSuffix));
  char hex[24];
  std::snprintf(hex, sizeof hex, ".tmp-%016llx", static_cast<unsigned long long>(random_bits()));
  return t + hex;
}

// Creates a new temporary for `path`; returns its descriptor and sets `tmp` to its name.
int create_temp(const std::string& path, std::string& tmp) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    tmp = temp_name(path);
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0) return fd;
    if (errno == EINTR || errno == EEXIST) continue;  // EEXIST: the name is taken (or planted)
    fail(path, reason(errno));
  }
  fail(path, "no unused temporary name beside it");
}

// Blocks the signals that ask a process to stop on the calling thread while alive.
class DeferStopSignals {
 public:
  DeferStopSignals() {
    sigset_t s;
    sigemptyset(&s);
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) sigaddset(&s, sig);
    ok_ = ::pthread_sigmask(SIG_BLOCK, &s, &old_) == 0;
  }
  ~DeferStopSignals() {
    if (ok_) ::pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  DeferStopSignals(const DeferStopSignals&) = delete;
  DeferStopSignals& operator=(const DeferStopSignals&) = delete;

 private:
  sigset_t old_;
  bool ok_ = false;
};

void fsync_dir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  // Errors are not reported: the new files are in place already, and some file systems refuse
  // fsync on a directory (EINVAL) although their renames are durable.
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

FdOutBuf::FdOutBuf(int fd) : fd_(fd), buf_(new char[kSize]) { setp(buf_.get(), buf_.get() + kSize); }

bool FdOutBuf::flush_all() { return drain() && error_ == 0; }

FdOutBuf::int_type FdOutBuf::overflow(int_type c) {
  if (!drain()) return traits_type::eof();
  if (!traits_type::eq_int_type(c, traits_type::eof())) {
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
  }
  return traits_type::not_eof(c);
}

std::streamsize FdOutBuf::xsputn(const char* s, std::streamsize n) {
  if (error_ || n <= 0) return 0;  // (an empty write may come with s == nullptr: memcpy's UB)
  if (n < static_cast<std::streamsize>(epptr() - pptr())) {
    std::memcpy(pptr(), s, static_cast<std::size_t>(n));
    pbump(static_cast<int>(n));
    return n;
  }
  if (!drain() || !put(s, static_cast<std::size_t>(n))) return 0;
  return n;
}

int FdOutBuf::sync() { return flush_all() ? 0 : -1; }

bool FdOutBuf::drain() {
  if (error_) return false;
  const std::size_t n = static_cast<std::size_t>(pptr() - pbase());
  setp(buf_.get(), buf_.get() + kSize);
  return put(buf_.get(), n);
}

bool FdOutBuf::put(const char* s, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd_, s, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      error_ = w < 0 ? errno : EIO;
      return false;
    }
    s += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

StagedFiles::~StagedFiles() { discard(); }

void StagedFiles::discard() noexcept {
  if (committed_) return;
  for (const File& f : files_) ::unlink(f.tmp.c_str());
  files_.clear();
  removals_.clear();
}

std::vector<std::string> StagedFiles::paths() const {
  std::vector<std::string> p;
  for (const File& f : files_) p.push_back(f.path);
  return p;
}

void StagedFiles::stage(const std::string& path, const std::function<void(std::ostream&)>& write) {
  if (committed_) throw Error(Status::internal, "cannot stage '" + path + "': the set was committed already");
  if (is_directory(path)) fail(path, "it is a directory");
  File f{path, {}};
  const int fd = create_temp(path, f.tmp);
  try {
    // Reserved before writing, so that recording the finished file cannot fail.
    files_.reserve(files_.size() + 1);
    {
      FdOutBuf buf(fd);
      std::ostream out(&buf);
      write(out);
      if (!buf.flush_all() || !out) fail(path, buf.error() ? reason(buf.error()) : "write failed");
    }
    if (::fsync(fd) != 0) fail(path, reason(errno));
  } catch (...) {
    ::close(fd);
    ::unlink(f.tmp.c_str());
    throw;
  }
  if (::close(fd) != 0) {  // NFS and quotas may report a failed write only here
    const int err = errno;
    ::unlink(f.tmp.c_str());
    fail(path, reason(err));
  }
  for (File& old : files_)
    if (old.path == path) {
      ::unlink(old.tmp.c_str());
      old.tmp = std::move(f.tmp);
      return;
    }
  files_.push_back(std::move(f));
}

void StagedFiles::adopt(StagedFiles& other) {
  if (committed_ || other.committed_) throw Error(Status::internal, "cannot adopt files: a set was committed already");
  // Reserved first, so that nothing below can fail half-way.
  files_.reserve(files_.size() + other.files_.size());
  removals_.reserve(removals_.size() + other.removals_.size());
  for (File& f : other.files_) {
    auto old = std::find_if(files_.begin(), files_.end(), [&](const File& o) { return o.path == f.path; });
    if (old != files_.end()) {
      ::unlink(old->tmp.c_str());
      old->tmp = std::move(f.tmp);
    } else {
      files_.push_back(std::move(f));
    }
  }
  for (std::string& r : other.removals_) removals_.push_back(std::move(r));
  other.files_.clear();
  other.removals_.clear();
}

void StagedFiles::remove_on_commit(const std::string& path) {
  if (committed_) throw Error(Status::internal, "cannot remove '" + path + "': the set was committed already");
  removals_.push_back(path);
}

void StagedFiles::commit() {
  if (committed_) return;
  // Checked again after each swap; checked here so that the common case fails before any rename.
  for (const File& f : files_)
    if (is_directory(f.path)) {
      discard();
      fail(f.path, "it is a directory");
    }
  // How each target was replaced, so a failure can undo it. Allocated before the step.
  enum Done : unsigned char { swapped, added, overwritten };
  std::vector<Done> done;
  done.reserve(files_.size());
  std::vector<std::string> dirs;
  for (const File& f : files_) dirs.push_back(dir_of(f.path));
  for (const std::string& r : removals_) dirs.push_back(dir_of(r));
  // Where each removed file waits until the step has succeeded ("" when it was gone already).
  std::vector<std::string> aside;
  aside.reserve(removals_.size());
  for (const std::string& r : removals_) aside.push_back(temp_name(r));
  int err = 0;
  const char* failed = nullptr;
  bool is_dir = false;
  {
    DeferStopSignals defer;
    for (const File& f : files_) {
      const char* tmp = f.tmp.c_str();
      const char* path = f.path.c_str();
      // The old file, if any, moves to the temporary's name, so it can be put back.
      if (::renameat2(AT_FDCWD, tmp, AT_FDCWD, path, RENAME_EXCHANGE) == 0) {
        done.push_back(swapped);
        if (is_directory(f.tmp)) {  // a directory appeared at the target meanwhile
          ::renameat2(AT_FDCWD, tmp, AT_FDCWD, path, RENAME_EXCHANGE);
          done.pop_back();
          failed = path;
          is_dir = true;
          break;
        }
        continue;
      }
      const int e = errno;
      if (e == ENOENT && ::rename(tmp, path) == 0) {  // there was no old file
        done.push_back(added);
        continue;
      }
      if ((e == EINVAL || e == ENOSYS) && ::rename(tmp, path) == 0) {
        done.push_back(overwritten);  // no RENAME_EXCHANGE on this file system: the old file is gone
        continue;
      }
      err = errno;
      failed = path;
      break;
    }
    std::size_t moved = 0;  // removals done (moved aside), in order
    for (; !failed && moved < removals_.size(); ++moved) {
      struct stat st {};
      if (::lstat(removals_[moved].c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {  // only regular files go
        aside[moved].clear();
        continue;
      }
      // RENAME_NOREPLACE: the aside name is never a file that appeared there meanwhile.
      if (::renameat2(AT_FDCWD, removals_[moved].c_str(), AT_FDCWD, aside[moved].c_str(), RENAME_NOREPLACE) == 0)
        continue;
      if (errno == ENOENT) {  // gone already: nothing to remove or to put back
        aside[moved].clear();
        continue;
      }
      if ((errno == EINVAL || errno == ENOSYS) && ::access(aside[moved].c_str(), F_OK) != 0 &&
          ::rename(removals_[moved].c_str(), aside[moved].c_str()) == 0)
        continue;
      err = errno;
      failed = removals_[moved].c_str();
      break;
    }
    if (failed) {
      for (std::size_t i = moved; i-- > 0;)  // the removals before the failed one, put back
        if (!aside[i].empty()) ::rename(aside[i].c_str(), removals_[i].c_str());
      // Undo in reverse order: old files back to their names, new names removed.
      for (std::size_t i = done.size(); i-- > 0;) {
        const File& f = files_[i];
        if (done[i] == swapped) ::renameat2(AT_FDCWD, f.tmp.c_str(), AT_FDCWD, f.path.c_str(), RENAME_EXCHANGE);
        else if (done[i] == added) ::rename(f.path.c_str(), f.tmp.c_str());
      }
    } else {
      for (std::size_t i = 0; i < files_.size(); ++i)
        if (done[i] == swapped) ::unlink(files_[i].tmp.c_str());  // the old version
      for (const std::string& a : aside)
        if (!a.empty()) ::unlink(a.c_str());
    }
  }
  if (failed) {
    std::string lost;
    for (std::size_t i = 0; i < done.size(); ++i)
      if (done[i] == overwritten) lost += (lost.empty() ? "" : ", ") + files_[i].path;
    const std::string target = failed;
    discard();
    fail(target, (is_dir ? std::string("it is a directory") : "rename failed: " + reason(err)) +
                     (lost.empty() ? std::string() : "; replaced before it and not restorable: " + lost));
  }
  committed_ = true;
  std::sort(dirs.begin(), dirs.end());
  dirs.erase(std::unique(dirs.begin(), dirs.end()), dirs.end());
  for (const std::string& d : dirs) fsync_dir(d);
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           StagedFiles* into) {
  if (into) {
    into->stage(path, write);
    return;
  }
  StagedFiles one;
  one.stage(path, write);
  one.commit();
}

}  // namespace occseg
