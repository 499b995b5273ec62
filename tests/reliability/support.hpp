// Helpers of the reliability tests: scratch paths, files, status checks, child processes.
#pragma once
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "occseg/occseg.h"

namespace occseg::reliability {

namespace fs = std::filesystem;

// A fresh, empty scratch directory for one test.
inline std::string scratch(const std::string& name) {
  const fs::path p = fs::path(OCCSEG_TEST_TMP) / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline void put(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Names of the entries of a directory (sorted), to prove nothing was left behind.
inline std::vector<std::string> entries(const std::string& dir) {
  std::vector<std::string> out;
  if (!fs::exists(dir)) return out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// Runs `body` in a forked child and returns its exit status (or 128 + signal). The child's
// exit code is what `body` returns; a crash shows as a signal.
inline int in_child(const std::function<int()>& body) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    int rc = 99;
    try {
      rc = body();
    } catch (...) {
      rc = 98;
    }
    ::_exit(rc);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// A dense f32 map of size n^3: 0.1 everywhere, 0.9 in a centred box of half the size.
inline std::vector<float> box_map(std::size_t n) {
  std::vector<float> p(n * n * n, 0.1f);
  for (std::size_t z = n / 4; z < 3 * n / 4; ++z)
    for (std::size_t y = n / 4; y < 3 * n / 4; ++y)
      for (std::size_t x = n / 4; x < 3 * n / 4; ++x) p[x + n * (y + n * z)] = 0.9f;
  return p;
}

}  // namespace occseg::reliability

// Expects `call` (an occseg_* call returning int) to fail with `code` and a last-error text
// containing `text`.
#define EXPECT_STATUS(call, code, text)                                                      \
  do {                                                                                       \
    const int rc_ = (call);                                                                  \
    EXPECT_EQ(rc_, (code)) << #call << ": " << occseg_last_error();                          \
    EXPECT_NE(std::string(occseg_last_error()).find(text), std::string::npos)                \
        << #call << ": '" << occseg_last_error() << "' lacks '" << (text) << "'";            \
  } while (0)
