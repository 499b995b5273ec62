// The output files of one command, written all or none: each file goes through
// write_file_atomically (no half-written file, ever), and unless the set is committed, a failure
// or a Ctrl-C removes the files written so far, and the directories this set created.
#pragma once
#include <functional>
#include <string>
#include <vector>

namespace occseg::cli {

class OutputSet {
 public:
  // Creates `dir` and its missing parents now; Error(io) naming it when that fails.
  explicit OutputSet(std::string dir);
  ~OutputSet();  // not committed: removes what it wrote and created
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  // Calls write(dir + "/" + name) (which must write that file atomically), records the file,
  // then throws Error(cancelled) if a signal arrived meanwhile.
  void write(const std::string& name, const std::function<void(const std::string& path)>& write);
  // Records a file written by other means (it is removed like the others).
  void adopt(const std::string& name);
  // Keeps everything.
  void commit() { committed_ = true; }

  const std::string& dir() const { return dir_; }
  std::string path(const std::string& name) const { return dir_ + "/" + name; }
  const std::vector<std::string>& files() const { return files_; }

 private:
  std::string dir_;
  std::vector<std::string> files_, created_dirs_;  // created_dirs_: innermost last
  bool committed_ = false;
};

}  // namespace occseg::cli
