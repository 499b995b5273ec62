#include "occseg/nrrd.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <limits>
#include <sstream>

#include "occseg/error.hpp"
#include "occseg/geometry.hpp"
#include "occseg/file_read.hpp"
#include "occseg/file_write.hpp"

namespace occseg {

namespace {

[[noreturn]] void bad(const std::string& path, const std::string& why) {
  throw Error(Status::format, "'" + path + "' is not a valid NRRD file: " + why);
}
[[noreturn]] void unsupported(const std::string& path, const std::string& why) {
  throw Error(Status::unsupported, "'" + path + "': " + why);
}

std::size_t type_size(NrrdType t) {
  switch (t) {
    case NrrdType::u8: return 1;
    case NrrdType::u16: return 2;
    case NrrdType::u32: case NrrdType::i32: case NrrdType::f32: return 4;
    case NrrdType::f64: return 8;
  }
  return 0;
}

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

bool parse_type(const std::string& s, NrrdType& t) {
  static const struct { const char* name; NrrdType type; } names[] = {
      {"uchar", NrrdType::u8}, {"unsigned char", NrrdType::u8}, {"uint8", NrrdType::u8}, {"uint8_t", NrrdType::u8},
      {"ushort", NrrdType::u16}, {"unsigned short", NrrdType::u16}, {"unsigned short int", NrrdType::u16},
      {"uint16", NrrdType::u16}, {"uint16_t", NrrdType::u16},
      {"uint", NrrdType::u32}, {"unsigned int", NrrdType::u32}, {"uint32", NrrdType::u32}, {"uint32_t", NrrdType::u32},
      {"int", NrrdType::i32}, {"signed int", NrrdType::i32}, {"int32", NrrdType::i32}, {"int32_t", NrrdType::i32},
      {"float", NrrdType::f32}, {"double", NrrdType::f64}};
  for (const auto& n : names)
    if (s == n.name) {
      t = n.type;
      return true;
    }
  return false;
}

// "(a,b,c)" -> {a, b, c}; false when malformed.
bool parse_vector(const std::string& s, std::vector<double>& out) {
  out.clear();
  const std::string t = trim(s);
  if (t.size() < 2 || t.front() != '(' || t.back() != ')') return false;
  std::istringstream in(t.substr(1, t.size() - 2));
  std::string item;
  while (std::getline(in, item, ',')) {
    std::istringstream v(item);
    double x;
    if (!(v >> x)) return false;
    out.push_back(x);
  }
  return !out.empty();
}

// Splits "(a,b,c) (d,e,f) none" into vector tokens.
std::vector<std::string> split_vectors(const std::string& s) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    if (i >= s.size()) break;
    std::size_t j = s[i] == '(' ? s.find(')', i) : s.find_first_of(" \t", i);
    j = j == std::string::npos ? s.size() : j + (s[i] == '(' ? 1 : 0);
    out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

void swap_bytes(std::vector<unsigned char>& d, std::size_t size) {
  for (std::size_t i = 0; i + size <= d.size(); i += size) std::reverse(d.begin() + i, d.begin() + i + size);
}

// Shortest text that reads back to the same double ("0.02", not "0.020000000000000000416").
std::string num(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

bool host_little_endian() {
  const std::uint16_t one = 1;
  unsigned char c;
  std::memcpy(&c, &one, 1);
  return c == 1;
}

}  // namespace

const char* nrrd_type_name(NrrdType t) {
  switch (t) {
    case NrrdType::u8: return "uint8";
    case NrrdType::u16: return "uint16";
    case NrrdType::u32: return "uint32";
    case NrrdType::i32: return "int32";
    case NrrdType::f32: return "float";
    case NrrdType::f64: return "double";
  }
  return "?";
}

NrrdVolume read_nrrd(const std::string& path) {
  const std::string b = read_file(path);
  if (b.compare(0, 4, "NRRD") != 0) bad(path, "it does not start with NRRD");
  NrrdVolume v;
  bool have_type = false, have_sizes = false, big = false, ascii = false, have_endian = false;
  int dimension = 0;
  std::vector<std::size_t> sizes;
  std::size_t pos = b.find('\n');
  if (pos == std::string::npos) bad(path, "the header is truncated");
  ++pos;
  for (;;) {
    const std::size_t e = b.find('\n', pos);
    if (e == std::string::npos) bad(path, "the header does not end with an empty line");
    std::string line = b.substr(pos, e - pos);
    pos = e + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) break;  // data follows
    if (line[0] == '#') continue;
    if (line.find(":=") != std::string::npos) continue;  // key/value pairs carry no geometry
    const std::size_t c = line.find(": ");
    if (c == std::string::npos) bad(path, "header line '" + line + "' is not 'field: value'");
    const std::string field = line.substr(0, c), value = trim(line.substr(c + 2));
    if (field == "type") {
      have_type = parse_type(value, v.type);
      if (!have_type) unsupported(path, "type '" + value + "' is not supported (uint8, uint16, uint32, int32, float, double)");
    } else if (field == "dimension") {
      dimension = std::atoi(value.c_str());
      if (dimension != 2 && dimension != 3) unsupported(path, "dimension " + value + " (only 2 and 3)");
    } else if (field == "sizes") {
      std::istringstream s(value);
      std::size_t n;
      sizes.clear();
      while (s >> n) sizes.push_back(n);
      have_sizes = s.eof();
      if (!have_sizes) bad(path, "malformed sizes '" + value + "'");
    } else if (field == "encoding") {
      std::string enc = value;
      std::transform(enc.begin(), enc.end(), enc.begin(), [](unsigned char ch) { return std::tolower(ch); });
      if (enc == "ascii" || enc == "text" || enc == "txt") ascii = true;
      else if (enc != "raw")
        unsupported(path, "encoding '" + value + "' is not supported (raw, ascii); re-save with `unu save -e raw`");
    } else if (field == "endian") {
      have_endian = true;
      if (value == "big") big = true;
      else if (value != "little") bad(path, "endian '" + value + "'");
    } else if (field == "data file" || field == "datafile") {
      unsupported(path, "detached data files are not supported");
    } else if (field == "line skip" || field == "lineskip" || field == "byte skip" || field == "byteskip") {
      if (std::atoi(value.c_str()) != 0) unsupported(path, field + " is not supported");
    } else if (field == "space origin") {
      std::vector<double> o;
      if (!parse_vector(value, o) || o.size() < 2 || o.size() > 3) bad(path, "malformed space origin '" + value + "'");
      for (std::size_t k = 0; k < o.size(); ++k) v.origin[k] = o[k];
    } else if (field == "space directions") {
      const std::vector<std::string> dirs = split_vectors(value);
      std::size_t axis = 0;
      for (const std::string& d : dirs) {
        if (d == "none") unsupported(path, "non-spatial axes are not supported");
        std::vector<double> dv;
        if (!parse_vector(d, dv) || axis >= 3) bad(path, "malformed space directions '" + value + "'");
        for (std::size_t k = 0; k < dv.size(); ++k)
          if (k != axis && dv[k] != 0) unsupported(path, "rotated axes (non-diagonal space directions) are not supported");
        if (!(axis < dv.size() && dv[axis] > 0)) unsupported(path, "flipped or zero space directions are not supported");
        v.spacing[axis] = dv[axis];
        ++axis;
      }
    } else if (field == "spacings") {
      std::istringstream s(value);
      for (std::size_t k = 0; k < 3 && s >> v.spacing[k]; ++k) {
      }
    }
    // Other fields (space, kinds, labels, content, centers, ...) do not change the samples.
  }
  if (!have_type) bad(path, "the header has no type");
  if (!dimension || !have_sizes || sizes.size() != std::size_t(dimension))
    bad(path, "dimension and sizes are missing or disagree");
  v.dims = Dims{sizes[0], sizes[1], dimension == 3 ? sizes[2] : 1};
  try {
    check_dims(v.dims);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
  for (double s : v.spacing)
    if (!(s > 0) || !std::isfinite(s)) bad(path, "spacing is not positive");
  for (double o : v.origin)
    if (!std::isfinite(o)) bad(path, "space origin is not finite");
  const std::size_t isz = type_size(v.type), n = v.dims.count();
  if (ascii) {
    // Each sample takes at least two characters (a digit and a separator, the last one may
    // end the file): a header promising more cannot be honoured, so nothing is allocated for it.
    if (n > (b.size() - pos + 1) / 2)
      bad(path, "ascii data ends before " + std::to_string(n) + " samples (the file has " +
                    std::to_string(b.size() - pos) + " bytes of data)");
    std::istringstream s(b.substr(pos));
    v.data.resize(n * isz);
    for (std::size_t i = 0; i < n; ++i) {
      double x;
      if (!(s >> x)) bad(path, "ascii data ends after " + std::to_string(i) + " of " + std::to_string(n) + " samples");
      const double top = v.type == NrrdType::u8 ? 255.0 : v.type == NrrdType::u16 ? 65535.0 : 4294967295.0;
      const bool integer = v.type != NrrdType::f32 && v.type != NrrdType::f64;
      if (integer && !(x == std::floor(x) && x >= (v.type == NrrdType::i32 ? -2147483648.0 : 0.0) &&
                       x <= (v.type == NrrdType::i32 ? 2147483647.0 : top)))
        bad(path, "ascii sample " + std::to_string(i) + " is not a " + nrrd_type_name(v.type));
      unsigned char* d = v.data.data() + i * isz;
      switch (v.type) {
        case NrrdType::u8: { const std::uint8_t t = static_cast<std::uint8_t>(x); std::memcpy(d, &t, 1); break; }
        case NrrdType::u16: { const std::uint16_t t = static_cast<std::uint16_t>(x); std::memcpy(d, &t, 2); break; }
        case NrrdType::u32: { const std::uint32_t t = static_cast<std::uint32_t>(x); std::memcpy(d, &t, 4); break; }
        case NrrdType::i32: { const std::int32_t t = static_cast<std::int32_t>(x); std::memcpy(d, &t, 4); break; }
        case NrrdType::f32: { const float t = static_cast<float>(x); std::memcpy(d, &t, 4); break; }
        case NrrdType::f64: std::memcpy(d, &x, 8); break;
      }
    }
    return v;
  }
  if (isz > 1 && !have_endian) bad(path, "multi-byte raw data needs an endian field");
  if (b.size() - pos < n * isz)
    bad(path, "truncated data: the header promises " + std::to_string(n * isz) + " bytes, the file has " +
                  std::to_string(b.size() - pos));
  v.data.assign(b.begin() + static_cast<std::ptrdiff_t>(pos), b.begin() + static_cast<std::ptrdiff_t>(pos + n * isz));
  if (isz > 1 && big == host_little_endian()) swap_bytes(v.data, isz);
  return v;
}

Grid grid_from_nrrd(const NrrdVolume& v, const std::string& name) {
  if (v.type == NrrdType::u32 || v.type == NrrdType::i32)
    throw Error(Status::format, "'" + name + "' holds " + nrrd_type_name(v.type) +
                                    " integers, not probabilities (use float, double, uint8 or uint16)");
  const double s = v.spacing[0];
  for (int k = 1; k < (v.dims.nz > 1 ? 3 : 2); ++k)
    if (std::fabs(v.spacing[k] - s) > 1e-6 * s)
      throw Error(Status::format, "'" + name + "' has anisotropic spacing; occseg maps have cubic voxels");
  Grid g;
  g.dims = v.dims;
  g.voxel_size = s;
  for (int k = 0; k < 3; ++k) g.origin[k] = v.origin[k] - s / 2;
  try {
    check_geometry(g);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + name + "': " + e.what());
  }
  const std::size_t n = v.dims.count();
  g.p.resize(n);
  const unsigned char* d = v.data.data();
  for (std::size_t i = 0; i < n; ++i) {
    switch (v.type) {
      case NrrdType::u8: g.p[i] = static_cast<float>(d[i] / 255.0); break;
      case NrrdType::u16: { std::uint16_t t; std::memcpy(&t, d + 2 * i, 2); g.p[i] = static_cast<float>(t / 65535.0); break; }
      case NrrdType::f32: std::memcpy(&g.p[i], d + 4 * i, 4); break;
      case NrrdType::f64: { double t; std::memcpy(&t, d + 8 * i, 8); g.p[i] = static_cast<float>(t); break; }
      default: break;
    }
  }
  try {
    check_probabilities(g);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + name + "': " + e.what());
  }
  return g;
}

void write_nrrd(const std::string& path, NrrdType type, const Dims& dims, double voxel_size,
                const std::array<double, 3>& corner, const void* data, std::size_t bytes, const std::string& content) {
  check_dims(dims);
  if (bytes != dims.count() * type_size(type))
    throw Error(Status::invalid_argument, "write_nrrd: " + std::to_string(bytes) + " bytes do not match the dims");
  if (!host_little_endian()) throw Error(Status::unsupported, "write_nrrd: big-endian hosts are not supported");
  // What read_nrrd will find: the centre of the first voxel, and the corner it gives back. Both
  // must pass the reader's geometry check, or the file would be one occseg cannot read.
  std::array<double, 3> centre{}, back{};
  for (int k = 0; k < 3; ++k) {
    centre[k] = corner[k] + voxel_size / 2;
    back[k] = centre[k] - voxel_size / 2;
  }
  try {
    check_geometry(dims, voxel_size, corner);
    check_geometry(dims, voxel_size, back);
  } catch (const Error& e) {
    throw Error(e.status(), "cannot write '" + path + "': " + e.what());
  }
  std::ostringstream h;
  h << "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\n";
  if (!content.empty()) h << "content: " << content << "\n";
  h << "type: " << nrrd_type_name(type) << "\ndimension: 3\nspace: right-anterior-superior\n"
    << "sizes: " << dims.nx << " " << dims.ny << " " << dims.nz << "\n"
    << "space directions: (" << num(voxel_size) << ",0,0) (0," << num(voxel_size) << ",0) (0,0," << num(voxel_size)
    << ")\nkinds: domain domain domain\nendian: little\nencoding: raw\n"
    << "space origin: (" << num(centre[0]) << "," << num(centre[1]) << "," << num(centre[2]) << ")\n\n";
  const std::string header = h.str();
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  });
}

void write_grid_nrrd(const std::string& path, const Grid& g) {
  write_nrrd(path, NrrdType::f32, g.dims, g.voxel_size, g.origin, g.p.data(), g.p.size() * sizeof(float),
             "occupancy probability");
}

void write_labels_nrrd(const std::string& path, const Grid& g, const LabelArray& labels) {
  if (labels.size() != g.dims.count())
    throw Error(Status::invalid_argument, "write_labels_nrrd: " + std::to_string(labels.size()) +
                                              " labels for " + std::to_string(g.dims.count()) + " voxels");
  write_nrrd(path, NrrdType::u32, g.dims, g.voxel_size, g.origin, labels.data(), labels.size() * 4, "segment labels");
}

}  // namespace occseg
