#include "outputs.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "occseg/error.hpp"
#include "progress.hpp"

namespace occseg::cli {

namespace {

bool is_dir(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

}  // namespace

OutputSet::OutputSet(std::string dir) : dir_(std::move(dir)) {
  while (dir_.size() > 1 && dir_.back() == '/') dir_.pop_back();
  if (dir_.empty()) throw Error(Status::invalid_argument, "the output directory name is empty");
  // Create each missing component, remembering which, so a cancelled run can take them back.
  std::vector<std::string> missing;
  for (std::string p = dir_; !p.empty() && p != "/" && p != "." && !is_dir(p);) {
    missing.push_back(p);
    const std::size_t slash = p.find_last_of('/');
    p = slash == std::string::npos ? "" : p.substr(0, slash);
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (::mkdir(it->c_str(), 0777) != 0 && errno != EEXIST)
      throw Error(Status::io, "cannot create '" + *it + "': " + std::strerror(errno));
    created_dirs_.push_back(*it);
  }
  if (!is_dir(dir_)) throw Error(Status::io, "'" + dir_ + "' is not a directory");
}

OutputSet::~OutputSet() {
  if (committed_) return;
  for (const std::string& f : files_) std::remove(f.c_str());
  for (auto it = created_dirs_.rbegin(); it != created_dirs_.rend(); ++it) ::rmdir(it->c_str());
}

void OutputSet::write(const std::string& name, const std::function<void(const std::string&)>& write) {
  const std::string p = path(name);
  write(p);
  files_.push_back(p);
  check_interrupted();
}

void OutputSet::adopt(const std::string& name) { files_.push_back(path(name)); }

}  // namespace occseg::cli
