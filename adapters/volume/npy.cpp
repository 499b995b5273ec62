#include "occseg/npy.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "occseg/error.hpp"
#include "occseg/file_read.hpp"
#include "occseg/file_write.hpp"
#include "occseg/geometry.hpp"

namespace occseg {

namespace {

[[noreturn]] void fail(const std::string& name, const std::string& why) {
  throw Error(Status::format, "'" + name + "' is not a valid .npy file: " + why);
}

std::size_t item_size(const std::string& d) {
  if (d == "<f4" || d == "<u4" || d == "<i4") return 4;
  if (d == "<f8") return 8;
  if (d == "|u1" || d == "<u1") return 1;
  if (d == "<u2") return 2;
  return 0;
}

// Value of a key in the header dict, as the raw text after "'key':".
std::string field(const std::string& h, const std::string& key, const std::string& name) {
  const std::size_t k = h.find("'" + key + "'");
  if (k == std::string::npos) fail(name, "header has no '" + key + "'");
  std::size_t c = h.find(':', k);
  if (c == std::string::npos) fail(name, "header entry '" + key + "' has no value");
  ++c;
  while (c < h.size() && h[c] == ' ') ++c;
  return h.substr(c);
}

}  // namespace

std::size_t NpyArray::element_count() const {
  std::size_t n = 1;
  for (auto s : shape) n *= s;
  return n;
}

NpyArray parse_npy(const unsigned char* b, std::size_t size, const std::string& name) {
  static const unsigned char magic[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
  if (size < 10 || std::memcmp(b, magic, 6) != 0) fail(name, "wrong magic (not \\x93NUMPY)");
  const int major = b[6];
  std::size_t hlen, off;
  if (major == 1) {
    hlen = b[8] | (std::size_t(b[9]) << 8);
    off = 10;
  } else if (major == 2 || major == 3) {
    if (size < 12) fail(name, "truncated header");
    hlen = b[8] | (std::size_t(b[9]) << 8) | (std::size_t(b[10]) << 16) | (std::size_t(b[11]) << 24);
    off = 12;
  } else {
    fail(name, "unsupported format version " + std::to_string(major));
  }
  if (hlen > size - off) fail(name, "truncated header");
  const std::string h(reinterpret_cast<const char*>(b + off), hlen);
  NpyArray a;
  std::string d = field(h, "descr", name);
  if (d.size() < 2 || d[0] != '\'') fail(name, "malformed 'descr'");
  const std::size_t q = d.find('\'', 1);
  if (q == std::string::npos) fail(name, "malformed 'descr'");
  a.descr = d.substr(1, q - 1);
  const std::size_t isz = item_size(a.descr);
  if (!isz) fail(name, "dtype '" + a.descr + "' is not supported (use float32, float64, uint8 or uint16)");
  const std::string f = field(h, "fortran_order", name);
  if (f.rfind("True", 0) == 0) a.fortran_order = true;
  else if (f.rfind("False", 0) == 0) a.fortran_order = false;
  else fail(name, "malformed 'fortran_order'");
  const std::string s = field(h, "shape", name);
  if (s.empty() || s[0] != '(') fail(name, "malformed 'shape'");
  const std::size_t close = s.find(')');
  if (close == std::string::npos) fail(name, "malformed 'shape'");
  std::size_t count = 1;
  for (std::size_t i = 1; i < close;) {
    while (i < close && (s[i] == ' ' || s[i] == ',')) ++i;
    if (i >= close) break;
    if (s[i] < '0' || s[i] > '9') fail(name, "malformed 'shape'");
    std::size_t v = 0;
    while (i < close && s[i] >= '0' && s[i] <= '9') {
      if (v > kMaxVoxels) fail(name, "shape entry is absurdly large");
      v = v * 10 + std::size_t(s[i] - '0');
      ++i;
    }
    a.shape.push_back(v);
    if (v != 0 && count > kMaxVoxels / v) fail(name, "shape claims more than 2^40 elements");
    count *= v;
  }
  if (count > kMaxVoxels) fail(name, "shape claims more than 2^40 elements");
  const std::size_t need = count * isz, body = size - off - hlen;
  if (body < need)
    fail(name, "truncated data: header promises " + std::to_string(need) + " bytes, file has " + std::to_string(body));
  a.data.assign(b + off + hlen, b + off + hlen + need);
  return a;
}

NpyArray read_npy(const std::string& path) {
  const std::string bytes = read_file(path);
  return parse_npy(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), path);
}

void write_npy(const std::string& path, const std::string& descr, const std::vector<std::size_t>& shape,
               const void* data, std::size_t bytes) {
  std::ostringstream h;
  h << "{'descr': '" << descr << "', 'fortran_order': False, 'shape': (";
  for (std::size_t i = 0; i < shape.size(); ++i) h << shape[i] << (shape.size() == 1 || i + 1 < shape.size() ? "," : "") << (i + 1 < shape.size() ? " " : "");
  h << "), }";
  std::string hs = h.str();
  // Pad with spaces so the data starts on a 64-byte boundary; the header ends with '\n'.
  const std::size_t total = 10 + hs.size() + 1;
  hs.append((64 - total % 64) % 64, ' ');
  hs.push_back('\n');
  if (hs.size() > 65535) throw Error(Status::invalid_argument, "npy header too long");
  write_file_atomically(path, [&](std::ostream& o) {
    const unsigned char pre[10] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0,
                                   static_cast<unsigned char>(hs.size() & 0xFF),
                                   static_cast<unsigned char>(hs.size() >> 8)};
    o.write(reinterpret_cast<const char*>(pre), 10);
    o.write(hs.data(), static_cast<std::streamsize>(hs.size()));
    o.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  });
}

Grid grid_from_npy(const NpyArray& a, double voxel_size, const std::string& name) {
  if (a.shape.size() != 3 && a.shape.size() != 2)
    throw Error(Status::bad_dims, "'" + name + "' has " + std::to_string(a.shape.size()) +
                                      " dimensions; a map is [z, y, x] (or [y, x] for 2D)");
  Dims d;
  d.nx = a.shape.back();
  d.ny = a.shape[a.shape.size() - 2];
  d.nz = a.shape.size() == 3 ? a.shape[0] : 1;
  check_dims(d);
  if (a.descr == "<u4" || a.descr == "<i4")
    throw Error(Status::format, "'" + name + "' holds " + a.descr + " integers, not probabilities (use float32, float64, uint8 or uint16)");
  Grid g;
  g.dims = d;
  g.voxel_size = voxel_size;
  try {
    check_geometry(g);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + name + "': " + e.what());
  }
  g.p.resize(d.count());
  const std::size_t n = d.count();
  // The element type is decided once, not per voxel: one copy loop per dtype.
  auto convert = [&](auto value) {
    if (!a.fortran_order) {
      for (std::size_t i = 0; i < n; ++i) g.p[i] = value(i);
    } else {  // file index of [z, y, x] is z + nz * (y + ny * x)
      for (std::size_t z = 0, i = 0; z < d.nz; ++z)
        for (std::size_t y = 0; y < d.ny; ++y)
          for (std::size_t x = 0; x < d.nx; ++x, ++i) g.p[i] = value(z + d.nz * (y + d.ny * x));
    }
  };
  const unsigned char* e = a.data.data();
  if (a.descr == "<f4")
    convert([e](std::size_t k) { float v; std::memcpy(&v, e + 4 * k, 4); return v; });
  else if (a.descr == "<f8")
    convert([e](std::size_t k) { double v; std::memcpy(&v, e + 8 * k, 8); return static_cast<float>(v); });
  else if (a.descr == "<u2")
    convert([e](std::size_t k) { std::uint16_t v; std::memcpy(&v, e + 2 * k, 2); return static_cast<float>(v / 65535.0); });
  else
    convert([e](std::size_t k) { return static_cast<float>(e[k] / 255.0); });
  try {
    check_probabilities(g);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + name + "': " + e.what());
  }
  return g;
}

void write_grid_npy(const std::string& path, const Grid& g) {
  write_npy(path, "<f4", {g.dims.nz, g.dims.ny, g.dims.nx}, g.p.data(), g.p.size() * sizeof(float));
}

void write_grid_npy_as(const std::string& path, const Grid& g, const std::string& descr) {
  const std::vector<std::size_t> shape{g.dims.nz, g.dims.ny, g.dims.nx};
  const std::size_t n = g.p.size();
  if (descr == "<f4") return write_grid_npy(path, g);
  if (descr == "<f8") {
    std::vector<double> v(g.p.begin(), g.p.end());
    return write_npy(path, descr, shape, v.data(), n * sizeof(double));
  }
  if (descr == "|u1") {
    std::vector<std::uint8_t> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint8_t>(std::lround(double(g.p[i]) * 255.0));
    return write_npy(path, descr, shape, v.data(), n);
  }
  if (descr == "<u2") {
    std::vector<std::uint16_t> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<std::uint16_t>(std::lround(double(g.p[i]) * 65535.0));
    return write_npy(path, descr, shape, v.data(), n * sizeof(std::uint16_t));
  }
  throw Error(Status::invalid_argument, "cannot write a map as dtype '" + descr + "' (use <f4, <f8, |u1 or <u2)");
}

void write_labels_npy(const std::string& path, const Dims& d, const LabelArray& labels) {
  write_npy(path, "<u4", {d.nz, d.ny, d.nx}, labels.data(), labels.size() * sizeof(std::uint32_t));
}

}  // namespace occseg
