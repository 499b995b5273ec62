// Shared by the in-tree reader plugins (C++): "key=value" reader options parsed into the
// adapters' option structs, and occseg::Error turned into the plugin ABI's error reporting.
#pragma once
#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/grid.hpp"
#include "occseg/occseg_plugin.h"

namespace occseg::plugin {

// The options of one call, checked against the keys the reader knows.
class Options {
 public:
  Options(const char* path, const char* const* options, const std::vector<std::string>& known) : path_(path) {
    for (const char* const* o = options; o && *o; ++o) {
      const char* eq = std::strchr(*o, '=');
      const std::string key = eq ? std::string(*o, static_cast<std::size_t>(eq - *o)) : std::string(*o);
      if (!eq || std::find(known.begin(), known.end(), key) == known.end()) {
        std::string list;
        for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
        fail("unknown option '" + std::string(*o) + "' (known: " + list + ")");
      }
      values_[key] = eq + 1;
    }
  }
  bool has(const std::string& key) const { return values_.count(key) != 0; }
  std::string text(const std::string& key, const std::string& fallback) const {
    auto it = values_.find(key);
    return it == values_.end() ? fallback : it->second;
  }
  // Comma-separated finite numbers, exactly `n` of them (n = 1 for a single number).
  std::vector<double> numbers(const std::string& key, std::size_t n) const {
    std::vector<double> v;
    std::stringstream s(values_.at(key));
    std::string item;
    while (std::getline(s, item, ',')) {
      char* end = nullptr;
      errno = 0;
      const double x = std::strtod(item.c_str(), &end);
      if (item.empty() || *end || errno || !std::isfinite(x)) fail("option " + key + ": '" + item + "' is not a number");
      v.push_back(x);
    }
    if (v.size() != n) fail("option " + key + " needs " + std::to_string(n) + " comma-separated numbers");
    return v;
  }
  double number(const std::string& key, double fallback) const { return has(key) ? numbers(key, 1)[0] : fallback; }
  [[noreturn]] void fail(const std::string& why) const {
    throw Error(Status::invalid_argument, "'" + path_ + "': " + why);
  }

 private:
  std::string path_;
  std::map<std::string, std::string> values_;
};

// The options sensor_origin=x,y,z and sensor_orientation=w,x,y,z of the readers that fuse scans
// (occseg/scan_options.hpp, included by the plugin before this header): each replaces its half of
// the stored pose. A zero or non-finite quaternion fails when the options are validated.
template <class ScanOptionsT>
void sensor_pose_options(const Options& o, ScanOptionsT& s) {
  if (o.has("sensor_origin")) {
    const std::vector<double> v = o.numbers("sensor_origin", 3);
    s.sensor_origin = std::array<double, 3>{v[0], v[1], v[2]};
  }
  if (o.has("sensor_orientation")) {
    const std::vector<double> v = o.numbers("sensor_orientation", 4);
    if (v == std::vector<double>{0, 0, 0, 0}) o.fail("option sensor_orientation: 0,0,0,0 is no rotation (give w,x,y,z, e.g. 1,0,0,0)");
    s.sensor_orientation = std::array<double, 4>{v[0], v[1], v[2], v[3]};
  }
}

// Hands a grid to the host (map_alloc + copy).
inline void deliver(const occseg_plugin_call* call, occseg_plugin_map_sink* sink, const Grid& g) {
  const size_t dims[3] = {g.dims.nx, g.dims.ny, g.dims.nz};
  float* values = nullptr;
  if (int rc = call->host->map_alloc(sink, dims, g.voxel_size, g.origin.data(), &values))
    throw Error(static_cast<Status>(rc), "map_alloc failed");
  std::memcpy(values, g.p.data(), g.p.size() * sizeof(float));
}

// Runs a reader body: no exception crosses the C ABI.
template <class Body>
int guarded(const occseg_plugin_call* call, Body&& body) noexcept {
  try {
    body();
    return 0;
  } catch (const Error& e) {
    call->host->set_error(e.what());
    return static_cast<int>(e.status());
  } catch (const std::bad_alloc&) {
    call->host->set_error("out of memory");
    return OCCSEG_ENOMEM;
  } catch (const std::exception& e) {
    call->host->set_error(e.what());
    return OCCSEG_EFORMAT;  // a library's own exception while parsing the file
  } catch (...) {
    call->host->set_error("unknown exception");
    return OCCSEG_EINTERNAL;
  }
}

}  // namespace occseg::plugin
