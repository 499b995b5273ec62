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
#include "occseg/gzip.hpp"

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

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return s;
}

// Teem's field identifiers and their spellings (nrrd/enumsNrrd.c, _nrrdFieldStrEqv), matched as
// teem's airEnumVal matches them: the whole text before ": ", case-insensitively. Returns the
// canonical name, or nullptr for a text that is no field.
const char* canonical_field(const std::string& text) {
  static const char* const eqv[][2] = {
      {"content", "content"}, {"number", "number"}, {"type", "type"}, {"block size", "block size"},
      {"blocksize", "block size"}, {"dimension", "dimension"}, {"space", "space"},
      {"space dimension", "space dimension"}, {"spacedimension", "space dimension"}, {"sizes", "sizes"},
      {"spacings", "spacings"}, {"thicknesses", "thicknesses"}, {"axis mins", "axis mins"}, {"axismins", "axis mins"},
      {"axis maxs", "axis maxs"}, {"axismaxs", "axis maxs"}, {"space directions", "space directions"},
      {"spacedirections", "space directions"}, {"centers", "centers"}, {"centerings", "centers"}, {"kinds", "kinds"},
      {"labels", "labels"}, {"units", "units"}, {"min", "min"}, {"max", "max"}, {"old min", "old min"},
      {"oldmin", "old min"}, {"old max", "old max"}, {"oldmax", "old max"}, {"endian", "endian"},
      {"encoding", "encoding"}, {"line skip", "line skip"}, {"lineskip", "line skip"}, {"byte skip", "byte skip"},
      {"byteskip", "byte skip"}, {"sample units", "sample units"}, {"sampleunits", "sample units"},
      {"space units", "space units"}, {"spaceunits", "space units"}, {"space origin", "space origin"},
      {"spaceorigin", "space origin"}, {"measurement frame", "measurement frame"},
      {"measurementframe", "measurement frame"}, {"data file", "data file"}, {"datafile", "data file"}};
  const std::string l = lower(text);
  for (const auto& e : eqv)
    if (l == e[0]) return e[1];
  return nullptr;
}

// Teem's space names and spellings (_nrrdSpaceStrEqv), case-insensitive: the canonical name and
// the space's dimension.
bool canonical_space(const std::string& text, std::string& name, int& dim) {
  static const struct { const char* spelling; const char* name; int dim; } eqv[] = {
      {"right-anterior-superior", "right-anterior-superior", 3}, {"right anterior superior", "right-anterior-superior", 3},
      {"rightanteriorsuperior", "right-anterior-superior", 3}, {"ras", "right-anterior-superior", 3},
      {"left-anterior-superior", "left-anterior-superior", 3}, {"left anterior superior", "left-anterior-superior", 3},
      {"leftanteriorsuperior", "left-anterior-superior", 3}, {"las", "left-anterior-superior", 3},
      {"left-posterior-superior", "left-posterior-superior", 3}, {"left posterior superior", "left-posterior-superior", 3},
      {"leftposteriorsuperior", "left-posterior-superior", 3}, {"lps", "left-posterior-superior", 3},
      {"right-anterior-superior-time", "right-anterior-superior-time", 4},
      {"right anterior superior time", "right-anterior-superior-time", 4},
      {"rightanteriorsuperiortime", "right-anterior-superior-time", 4}, {"rast", "right-anterior-superior-time", 4},
      {"left-anterior-superior-time", "left-anterior-superior-time", 4},
      {"left anterior superior time", "left-anterior-superior-time", 4},
      {"leftanteriorsuperiortime", "left-anterior-superior-time", 4}, {"last", "left-anterior-superior-time", 4},
      {"left-posterior-superior-time", "left-posterior-superior-time", 4},
      {"left posterior superior time", "left-posterior-superior-time", 4},
      {"leftposteriorsuperiortime", "left-posterior-superior-time", 4}, {"lpst", "left-posterior-superior-time", 4},
      {"scanner-xyz", "scanner-xyz", 3}, {"scanner-xyz-time", "scanner-xyz-time", 4}, {"scanner-xyzt", "scanner-xyz-time", 4},
      {"3d-right-handed", "3D-right-handed", 3}, {"3d right handed", "3D-right-handed", 3},
      {"3drighthanded", "3D-right-handed", 3}, {"3d-left-handed", "3D-left-handed", 3},
      {"3d left handed", "3D-left-handed", 3}, {"3dlefthanded", "3D-left-handed", 3},
      {"3d-right-handed-time", "3D-right-handed-time", 4}, {"3d right handed time", "3D-right-handed-time", 4},
      {"3drighthandedtime", "3D-right-handed-time", 4}, {"3d-left-handed-time", "3D-left-handed-time", 4},
      {"3d left handed time", "3D-left-handed-time", 4}, {"3dlefthandedtime", "3D-left-handed-time", 4}};
  const std::string l = lower(text);
  for (const auto& e : eqv)
    if (l == e.spelling) {
      name = e.name;
      dim = e.dim;
      return true;
    }
  return false;
}

// A non-negative decimal integer filling the whole text (no sign, no overflow: atoi's undefined
// behaviour on "99999999999999999999" is not an option).
bool parse_count(const std::string& t, std::size_t& out) {
  if (t.empty() || t.size() > 15 || t.find_first_not_of("0123456789") != std::string::npos) return false;
  out = std::stoull(t);
  return true;
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

NrrdVolume read_nrrd(const std::string& path, const IoProgress& progress) {
  const std::string b = read_file(path);
  if (b.compare(0, 4, "NRRD") != 0) bad(path, "it does not start with NRRD");
  NrrdVolume v;
  bool have_type = false, have_sizes = false, big = false, ascii = false, gzip = false, have_endian = false;
  int dimension = 0, space_dim = 0;
  std::vector<std::size_t> sizes;
  std::vector<std::string> seen;  // canonical names of the fields read so far
  std::size_t pos = b.find('\n');
  if (pos == std::string::npos) bad(path, "the header is truncated");
  {
    std::string magic = b.substr(0, pos);
    if (!magic.empty() && magic.back() == '\r') magic.pop_back();
    if (magic != "NRRD0001" && magic != "NRRD0002" && magic != "NRRD0003" && magic != "NRRD0004" &&
        magic != "NRRD0005" && magic != "NRRD00.01")
      bad(path, "the first line '" + printable(magic) + "' is not a NRRD magic (NRRD0001 to NRRD0005)");
  }
  ++pos;
  for (;;) {
    const std::size_t e = b.find('\n', pos);
    if (e == std::string::npos) bad(path, "the header does not end with an empty line");
    std::string line = b.substr(pos, e - pos);
    pos = e + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) break;  // data follows
    if (line[0] == '#') continue;
    // As teem (_nrrdReadNrrdParseField): the text before the first ": " names a field when it is
    // one (any case); otherwise a line holding ":=" is a key/value pair (no geometry), and any
    // other line is an error. A field may appear once.
    const std::size_t c = line.find(": ");
    const char* known = c == std::string::npos ? nullptr : canonical_field(line.substr(0, c));
    if (!known) {
      if (line.find(":=") != std::string::npos) continue;
      if (c == std::string::npos) bad(path, "header line '" + printable(line) + "' is not 'field: value'");
      bad(path, "header line '" + printable(line) + "': '" + printable(line.substr(0, c)) + "' is not a NRRD field");
    }
    const std::string field = known, value = trim(line.substr(c + 2));
    if (std::find(seen.begin(), seen.end(), field) != seen.end()) bad(path, "the field '" + field + "' appears twice");
    seen.push_back(field);
    const std::string shown = printable(value);
    // Teem reads the per-axis fields only once it knows the dimension, and vectors once it knows
    // the space's dimension.
    auto need_dimension = [&] {
      if (!dimension) bad(path, "'" + field + "' comes before 'dimension'");
    };
    auto need_space = [&] {
      if (!space_dim) bad(path, "'" + field + "' comes before 'space' or 'space dimension'");
    };
    if (field == "type") {
      have_type = parse_type(lower(value), v.type);
      if (!have_type) unsupported(path, "type '" + shown + "' is not supported (uint8, uint16, uint32, int32, float, double)");
    } else if (field == "dimension") {
      std::size_t d = 0;
      if (!parse_count(value, d)) bad(path, "dimension '" + shown + "' is not a number");
      if (d != 2 && d != 3) unsupported(path, "dimension " + shown + " (only 2 and 3)");
      dimension = static_cast<int>(d);
    } else if (field == "space") {
      if (std::find(seen.begin(), seen.end(), "space dimension") != seen.end())
        bad(path, "it has both 'space' and 'space dimension'");
      if (!canonical_space(value, v.space, space_dim)) bad(path, "space '" + shown + "' is not a NRRD space");
      if (space_dim != 3) unsupported(path, "space '" + shown + "' has a time axis (only 3D spaces are read)");
    } else if (field == "space dimension") {
      if (std::find(seen.begin(), seen.end(), "space") != seen.end())
        bad(path, "it has both 'space' and 'space dimension'");
      std::size_t d = 0;
      if (!parse_count(value, d) || d < 2 || d > 3) unsupported(path, "space dimension '" + shown + "' (only 2 and 3)");
      space_dim = static_cast<int>(d);
    } else if (field == "sizes") {
      need_dimension();
      std::istringstream s(value);
      std::string t;
      sizes.clear();
      while (s >> t) {
        std::size_t n = 0;
        if (!parse_count(t, n)) bad(path, "malformed sizes '" + shown + "'");
        sizes.push_back(n);
      }
      have_sizes = true;
    } else if (field == "encoding") {
      const std::string enc = lower(value);
      if (enc == "ascii" || enc == "text" || enc == "txt") ascii = true;
      else if (enc == "gzip" || enc == "gz") gzip = true;  // teem's spellings of gzip
      else if (enc != "raw")
        unsupported(path, "encoding '" + shown + "' is not supported (raw, gzip, ascii); re-save with `unu save -e gzip`");
    } else if (field == "endian") {
      have_endian = true;
      const std::string en = lower(value);
      if (en == "big") big = true;
      else if (en != "little") bad(path, "endian '" + shown + "'");
    } else if (field == "data file") {
      unsupported(path, "detached data files are not supported");
    } else if (field == "line skip" || field == "byte skip") {
      std::size_t n = 0;
      if (!parse_count(value, n) || n != 0) unsupported(path, field + " " + shown + " is not supported");
    } else if (field == "block size") {
      unsupported(path, "block types are not supported");
    } else if (field == "space origin") {
      need_space();
      std::vector<double> o;
      if (!parse_vector(value, o) || o.size() != std::size_t(space_dim))
        bad(path, "malformed space origin '" + shown + "'");
      for (std::size_t k = 0; k < o.size(); ++k) v.origin[k] = o[k];
    } else if (field == "space directions") {
      need_dimension();
      need_space();
      const std::vector<std::string> dirs = split_vectors(value);
      if (dirs.size() != std::size_t(dimension)) bad(path, "malformed space directions '" + shown + "'");
      std::size_t axis = 0;
      for (const std::string& d : dirs) {
        if (d == "none") unsupported(path, "non-spatial axes are not supported");
        std::vector<double> dv;
        if (!parse_vector(d, dv) || dv.size() != std::size_t(space_dim))
          bad(path, "malformed space directions '" + shown + "'");
        for (std::size_t k = 0; k < dv.size(); ++k)
          if (k != axis && dv[k] != 0) unsupported(path, "rotated axes (non-diagonal space directions) are not supported");
        if (!(axis < dv.size() && dv[axis] > 0)) unsupported(path, "flipped or zero space directions are not supported");
        v.spacing[axis] = dv[axis];
        ++axis;
      }
    } else if (field == "spacings") {
      need_dimension();
      std::istringstream s(value);
      for (std::size_t k = 0; k < 3 && s >> v.spacing[k]; ++k) {
      }
    } else if (field == "kinds" || field == "centers" || field == "thicknesses" || field == "axis mins" ||
               field == "axis maxs" || field == "labels" || field == "units") {
      need_dimension();
    } else if (field == "space units" || field == "measurement frame") {
      need_space();
    }
    // The other fields (content, number, min, max, ...) do not change the samples.
  }
  if (!have_type) bad(path, "the header has no type");
  if (!dimension || !have_sizes || sizes.size() != std::size_t(dimension))
    bad(path, "dimension and sizes are missing or disagree");
  v.dims = Dims{sizes[0], sizes[1], dimension == 3 ? sizes[2] : 1};
  {
    // Data the file cannot hold is a format error before any size check (which may refuse a map
    // too large for the memory): raw bytes missing, or more than deflate's 1032:1 could give.
    const double promised = double(v.dims.nx) * double(v.dims.ny) * double(v.dims.nz) * double(type_size(v.type));
    const double have = double(b.size() - pos);
    if (gzip && promised / 1032 > have + 64)
      bad(path, "the " + std::to_string(b.size() - pos) + " bytes of gzip data cannot hold the " +
                    std::to_string(static_cast<unsigned long long>(promised)) + " bytes the header promises");
    if (!gzip && !ascii && promised > have && v.dims.count() > 0 && promised < 1e18)
      bad(path, "truncated data: the header promises " + std::to_string(static_cast<unsigned long long>(promised)) +
                    " bytes, the file has " + std::to_string(b.size() - pos));
  }
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
  if (gzip) {
    // Deflate shrinks data at most 1032:1, so a header promising more than that of the bytes
    // present cannot be honoured: refused before anything is allocated for it.
    const std::size_t have = b.size() - pos;
    if (n * isz / 1032 > have + 64)
      bad(path, "the " + std::to_string(have) + " bytes of gzip data cannot hold the " + std::to_string(n * isz) +
                    " bytes the header promises");
    v.data.resize(n * isz);
    const std::string why = gunzip_exact(b.data() + pos, have, v.data.data(), v.data.size(), progress);
    if (!why.empty()) bad(path, why);
    if (isz > 1 && big == host_little_endian()) swap_bytes(v.data, isz);
    return v;
  }
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
                const std::array<double, 3>& corner, const void* data, std::size_t bytes, const std::string& content,
                const std::string& space, StagedFiles* into, const NrrdWriteOptions& options) {
  check_dims(dims);
  if (bytes != dims.count() * type_size(type))
    throw Error(Status::invalid_argument, "write_nrrd: " + std::to_string(bytes) + " bytes do not match the dims");
  if (!host_little_endian()) throw Error(Status::unsupported, "write_nrrd: big-endian hosts are not supported");
  std::string space_name = kNrrdDefaultSpace;
  int space_dim = 3;
  if (!space.empty() && (!canonical_space(space, space_name, space_dim) || space_dim != 3))
    throw Error(Status::invalid_argument, "write_nrrd: '" + printable(space) + "' is not a 3D NRRD space");
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
  h << "type: " << nrrd_type_name(type) << "\ndimension: 3\nspace: " << space_name << "\n"
    << "sizes: " << dims.nx << " " << dims.ny << " " << dims.nz << "\n"
    << "space directions: (" << num(voxel_size) << ",0,0) (0," << num(voxel_size) << ",0) (0,0," << num(voxel_size)
    << ")\nkinds: domain domain domain\nendian: little\nencoding: " << (options.gzip ? "gzip" : "raw") << "\n"
    << "space origin: (" << num(centre[0]) << "," << num(centre[1]) << "," << num(centre[2]) << ")\n\n";
  const std::string header = h.str();
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    if (options.gzip) {
      write_gzip(out, data, bytes, options.level, options.threads, options.progress, options.runs);
      return;
    }
    // Raw: written in pieces straight from the caller's array, reporting progress between them.
    const char* d = static_cast<const char*>(data);
    for (std::size_t at = 0; at < bytes && out;) {
      const std::size_t k = std::min(bytes - at, kGzipPiece * 4);
      out.write(d + at, static_cast<std::streamsize>(k));
      at += k;
      report_progress(options.progress, double(at) / double(bytes));
    }
  }, into);
}

void write_grid_nrrd(const std::string& path, const Grid& g, const std::string& space, StagedFiles* into,
                     const NrrdWriteOptions& options) {
  write_nrrd(path, NrrdType::f32, g.dims, g.voxel_size, g.origin, g.p.data(), g.p.size() * sizeof(float),
             "occupancy probability", space, into, options);
}

void write_labels_nrrd(const std::string& path, const Grid& g, const LabelArray& labels, const std::string& space,
                       StagedFiles* into, const NrrdWriteOptions& options) {
  if (labels.size() != g.dims.count())
    throw Error(Status::invalid_argument, "write_labels_nrrd: " + std::to_string(labels.size()) +
                                              " labels for " + std::to_string(g.dims.count()) + " voxels");
  NrrdWriteOptions o = options;
  if (o.gzip && o.runs.word == 0) o.runs = {4, g.dims.nx, g.dims.nx * g.dims.ny};  // labels: long runs
  write_nrrd(path, NrrdType::u32, g.dims, g.voxel_size, g.origin, labels.data(), labels.size() * 4, "segment labels",
             space, into, o);
}

}  // namespace occseg
