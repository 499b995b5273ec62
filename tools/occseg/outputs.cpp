#include "outputs.hpp"

#include <pthread.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>

#include "occseg/error.hpp"
#include "occseg/parallel.hpp"
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
  try {
    created_dirs_.reserve(missing.size());
    for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
      if (::mkdir(it->c_str(), 0777) != 0 && errno != EEXIST)
        throw Error(Status::io, "cannot create '" + *it + "': " + std::strerror(errno));
      created_dirs_.push_back(*it);
    }
    if (!is_dir(dir_)) throw Error(Status::io, "'" + dir_ + "' is not a directory");
  } catch (...) {
    for (auto it = created_dirs_.rbegin(); it != created_dirs_.rend(); ++it) ::rmdir(it->c_str());
    throw;
  }
}

OutputSet::~OutputSet() {
  if (staged_.committed()) return;
  staged_.discard();  // first, so that the directories this set created are empty again
  for (auto it = created_dirs_.rbegin(); it != created_dirs_.rend(); ++it) ::rmdir(it->c_str());
}

void OutputSet::write(const std::string& name, const std::function<void(const std::string&, StagedFiles&)>& write) {
  const std::string p = path(name);
  files_.reserve(files_.size() + 1);
  write(p, staged_);
  files_.push_back(p);
  check_interrupted();
}

void OutputSet::write(const std::vector<std::string>& names, const std::function<void(StagedFiles&)>& write) {
  files_.reserve(files_.size() + names.size());
  write(staged_);
  for (const std::string& n : names) files_.push_back(path(n));
  check_interrupted();
}

void OutputSet::write_concurrently(const std::vector<Job>& jobs, const std::vector<std::size_t>& start, int threads) {
  if (start.size() != jobs.size()) throw Error(Status::internal, "write_concurrently: the start order does not list every job");
  std::vector<StagedFiles> sets(jobs.size());
  std::vector<std::exception_ptr> errors(jobs.size());
  files_.reserve(files_.size() + jobs.size());
  parallel_for_dynamic(jobs.size(), threads, [&](std::size_t a, std::size_t b) {
    for (std::size_t k = a; k < b; ++k) {
      const std::size_t j = start[k];
      try {
        jobs[j].write(path(jobs[j].name), sets[j]);
      } catch (...) {
        errors[j] = std::current_exception();
      }
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);  // `sets` removes every temporary on the way out
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    staged_.adopt(sets[j]);
    files_.push_back(path(jobs[j].name));
  }
  check_interrupted();
}

void OutputSet::remove(const std::string& name) {
  removed_.reserve(removed_.size() + 1);
  staged_.remove_on_commit(path(name));
  removed_.push_back(path(name));
}

void OutputSet::commit() {
  sigset_t stop, old;
  sigemptyset(&stop);
  sigaddset(&stop, SIGINT);
  sigaddset(&stop, SIGTERM);
  // From here a Ctrl-C waits until the files are in place; one that came before cancels.
  ::pthread_sigmask(SIG_BLOCK, &stop, &old);
  try {
    check_interrupted();
    staged_.commit();
  } catch (...) {
    ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
    throw;
  }
  ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
}

}  // namespace occseg::cli
