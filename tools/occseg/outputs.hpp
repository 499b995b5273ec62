// The output files of one command, replaced all or nothing. Each file is staged: written
// completely to a temporary beside its target (occseg::StagedFiles), so until commit() no old
// file of the output directory is touched. commit() renames all of them into place in one short
// step, unless a signal (Ctrl-C, SIGTERM) arrived before it; destroying a set that was not
// committed (an error, out of memory, a signal) removes the temporaries and the directories the
// set created. So DIR holds either its old files, each unchanged, or the complete new set.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "occseg/file_write.hpp"

namespace occseg::cli {

class OutputSet {
 public:
  // Creates `dir` and its missing parents now; Error(io) naming it when that fails.
  explicit OutputSet(std::string dir);
  ~OutputSet();  // not committed: removes the temporaries and the directories it created
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  // Calls write(dir + "/" + name, staged), which must stage that file into `staged` (every
  // writer takes it as its `into` argument), records the name, then throws Error(cancelled) if a
  // signal arrived meanwhile.
  void write(const std::string& name, const std::function<void(const std::string& path, StagedFiles& staged)>& write);
  // The same for a writer that stages several files (`names`, in DIR) at once.
  void write(const std::vector<std::string>& names, const std::function<void(StagedFiles& staged)>& write);
  // Several files written at the same time, on up to `threads` threads (0: all cores), each
  // writer staging its file into a set of its own (the writers must not share unguarded state).
  // Jobs start in the order `start` gives (indices into `jobs`: the longest first keeps the
  // threads busy to the end); the files are recorded, and staged for the commit, in the order of
  // `jobs`, so the set is the same for any thread count. When writers fail, the exception of the
  // first failed job in `jobs` order is rethrown, after every job has ended; nothing of the
  // failed call is staged. Then throws Error(cancelled) if a signal arrived meanwhile.
  struct Job {
    std::string name;
    std::function<void(const std::string& path, StagedFiles& staged)> write;
  };
  void write_concurrently(const std::vector<Job>& jobs, const std::vector<std::size_t>& start, int threads);
  // Removes DIR/name in the commit (StagedFiles::remove_on_commit): a file of an earlier run that
  // this set does not replace. Listed by removed().
  void remove(const std::string& name);
  // Replaces the old files with the staged ones: with SIGINT and SIGTERM blocked, throws
  // Error(cancelled) if one arrived before, else renames everything (StagedFiles::commit).
  void commit();

  const std::string& dir() const { return dir_; }
  std::string path(const std::string& name) const { return dir_ + "/" + name; }
  // The files of the set, in the order written.
  const std::vector<std::string>& files() const { return files_; }
  const std::vector<std::string>& removed() const { return removed_; }

 private:
  std::string dir_;
  std::vector<std::string> files_, removed_, created_dirs_;  // created_dirs_: innermost last
  StagedFiles staged_;
};

}  // namespace occseg::cli
