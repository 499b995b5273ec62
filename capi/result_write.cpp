// occseg_result_write: labels.npy and segments.json, the files of `occseg segment --out`.
#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "internal.hpp"
#include "occseg/file_write.hpp"
#include "occseg/npy.hpp"

using occseg::Error;
using occseg::Status;
using occseg::capi::guard;
using occseg::capi::require;

namespace {

void make_dir(const std::string& dir) {
  if (::mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST)
    throw Error(Status::io, "cannot create '" + dir + "': " + std::strerror(errno));
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) throw Error(Status::io, "'" + dir + "' is not a directory");
}

// Shortest text that reads back as the same double (the JSON of the CLI does the same).
std::string number(double v) {
  char t[64];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(t, sizeof t, "%.*g", digits, v);
    if (std::strtod(t, nullptr) == v) break;
  }
  return t;
}

template <class A>
void list(std::ostream& o, const A& a) {
  o << "[" << number(a[0]) << ", " << number(a[1]) << ", " << number(a[2]) << "]";
}

// Same keys and structure as tools/occseg/segments_json.cpp.
std::string segments_json(const occseg_result& r) {
  std::ostringstream o;
  const occseg::Dims& d = r.result.dims;
  o << "{\n \"dims\": [" << d.nx << ", " << d.ny << ", " << d.nz << "],\n \"preset\": \"" << r.preset
    << "\",\n \"segments\": [";
  const char* sep = "\n";
  for (const occseg::Segment& s : r.result.segments) {
    o << sep << "  {\"id\": " << s.id << ", \"state\": \"" << occseg::state_name(s.state)
      << "\", \"voxels\": " << s.voxels << ", \"mop\": " << number(s.mop) << ", \"bbox\": {\"min\": ";
    list(o, s.bbox_min);
    o << ", \"max\": ";
    list(o, s.bbox_max);
    o << "}, \"centroid\": ";
    list(o, s.centroid);
    o << "}";
    sep = ",\n";
  }
  o << "\n ]\n}\n";
  return o.str();
}

}  // namespace

extern "C" {

int occseg_result_write(const occseg_result* result, const char* dir) {
  return guard("occseg_result_write", [&] {
    require(result, "result");
    require(dir, "dir");
    const std::string text = segments_json(*result);
    make_dir(dir);
    const std::string labels = std::string(dir) + "/labels.npy", json = std::string(dir) + "/segments.json";
    occseg::write_labels_npy(labels, result->result.dims, result->result.labels);
    try {
      occseg::write_file_atomically(json, [&](std::ostream& out) { out << text; });
    } catch (...) {
      std::remove(labels.c_str());  // all or nothing, as the CLI does
      throw;
    }
  });
}

}  // extern "C"
