// Writing files all or nothing. Every new file is written completely to a temporary in its
// target's directory, flushed and fsync'd, and only then renamed over the target, so a failure,
// an exception or a cancel never leaves a half-written output and never touches the old file.
//
// Temporaries are named `NAME.tmp-` + 16 random hex digits and created with
// O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC and mode 0666 (less the umask, or as a default ACL
// says, like any newly created file): a name that exists already, a symbolic link planted in a
// shared folder included, is never opened or followed; another random name is tried instead.
//
// Every temporary in this project is made here (tools/, capi/, adapters/ writers); do not open
// one anywhere else.
//
// SIGXFSZ: a write beyond RLIMIT_FSIZE fails with EFBIG and is reported like any write error
// only where SIGXFSZ is ignored (the `occseg` command ignores it); its default action ends the
// process. This code never changes signal dispositions.
#pragma once
#include <functional>
#include <memory>
#include <ostream>
#include <streambuf>
#include <string>
#include <vector>

namespace occseg {

// An output stream buffer over a file descriptor (not owned) that keeps the first write error
// (its errno), so that a message can say why ("No space left on device", "File too large").
// After an error it writes nothing more. The temporaries of StagedFiles are written through it,
// and the `occseg` command's stdout.
class FdOutBuf : public std::streambuf {
 public:
  explicit FdOutBuf(int fd);
  FdOutBuf(const FdOutBuf&) = delete;
  FdOutBuf& operator=(const FdOutBuf&) = delete;
  // Writes what is buffered; false when that or an earlier write failed.
  bool flush_all();
  int error() const { return error_; }  // errno of the first failed write, or 0

 protected:
  int_type overflow(int_type c) override;
  std::streamsize xsputn(const char* s, std::streamsize n) override;
  int sync() override;

 private:
  bool drain();
  bool put(const char* s, std::size_t n);
  static constexpr std::size_t kSize = 1 << 16;
  int fd_;
  int error_ = 0;
  std::unique_ptr<char[]> buf_;  // on the heap: callers' threads may have small stacks
};

// A set of files that replace their old versions together. stage() writes each new file to its
// own temporary; commit() renames all of them into place in one short step; destroying a set
// that was not committed removes its temporaries. Until commit() every old file is untouched.
// Not thread-safe: one set belongs to one thread at a time.
class StagedFiles {
 public:
  StagedFiles() = default;
  ~StagedFiles();  // not committed: removes the temporaries
  StagedFiles(const StagedFiles&) = delete;
  StagedFiles& operator=(const StagedFiles&) = delete;

  // Writes the new content of `path` with write(stream) to a fresh temporary beside it, then
  // flushes, fsyncs and closes it. Throws Error(io) naming `path` and the reason ("File too
  // large", "No space left on device", ...) when the temporary cannot be created, written,
  // synced or closed, and Error(io) "it is a directory" when `path` is one; any exception of
  // `write` passes through. On every failure this file's temporary is removed (the files staged
  // before stay staged). Staging one path twice replaces the first staged version.
  void stage(const std::string& path, const std::function<void(std::ostream&)>& write);

  // Renames every staged temporary over its target, in the order staged, with SIGINT, SIGTERM,
  // SIGHUP and SIGQUIT blocked on the calling thread during the renames (a signal that arrives
  // then is delivered after them; other threads' masks are theirs), then fsyncs the
  // directories. If a rename fails, the targets replaced before it get their old files back
  // (they are swapped, not overwritten: renameat2 RENAME_EXCHANGE; on a file system without it
  // a plain rename is used and such a target cannot be restored, which the error then says),
  // the temporaries are removed, and Error(io) names the file. The removals (remove_on_commit)
  // follow the renames in the same step and are undone with them. A set commits at most once; an
  // empty set commits nothing.
  void commit();

  // Removes the file `path` as part of commit(): at the renames it is moved aside to a
  // temporary name (and put back if the commit fails), then deleted once every file is in place.
  // A path that is gone by then is no error. For files an earlier run wrote that the new set
  // does not contain; the caller decides which those are.
  void remove_on_commit(const std::string& path);

  // Takes over the staged files and removals of `other` (not committed), after this set's own,
  // as if they had been staged here in the same order; `other` is left empty. So several sets,
  // each filled by its own thread, can be committed together. Staging one path in both: the
  // version of `other` replaces this set's.
  void adopt(StagedFiles& other);

  // Removes the temporaries of a set not committed and forgets them (the destructor does this).
  void discard() noexcept;

  // Targets staged so far, in order.
  std::vector<std::string> paths() const;
  bool committed() const { return committed_; }

 private:
  struct File {
    std::string path, tmp;
  };
  std::vector<File> files_;
  std::vector<std::string> removals_;
  bool committed_ = false;
};

// stage() into `into` when it is given (the rename then waits for into->commit()); otherwise a
// set of this one file, committed at once.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           StagedFiles* into = nullptr);

}  // namespace occseg
