#include "occseg/npy.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

#include "occseg/error.hpp"
#include "occseg/fill_values.hpp"
#include "occseg/file_read.hpp"
#include "occseg/file_write.hpp"
#include "occseg/geometry.hpp"
#include "occseg/parallel.hpp"

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

// The header dict, parsed as NumPy's reader parses it (numpy/lib/format.py: ast.literal_eval of
// the header text, then exactly the keys descr, fortran_order and shape): a Python dict literal of
// single- or double-quoted strings, True/False, non-negative decimal integers and tuples. A text
// search for "'shape'" once read files NumPy refuses or reads otherwise: a repeated key (Python
// keeps the last, the search found the first), a key inside a string value, "(3)" (an int, not a
// tuple). What literal_eval would accept but no NumPy writer produces (escapes, string prefixes,
// hexadecimal, nested parentheses) is refused too, with a message; nothing is read differently.
class HeaderParser {
 public:
  HeaderParser(const std::string& text, const std::string& name, bool python2_longs)
      : t_(text), name_(name), longs_(python2_longs) {}

  void parse(NpyArray& a) {
    skip();
    expect('{', "the header is not a Python dict");
    bool seen[3] = {false, false, false};
    static const char* const keys[3] = {"descr", "fortran_order", "shape"};
    skip();
    while (peek() != '}') {
      const std::string key = string_literal("a dict key");
      int k = 0;
      while (k < 3 && key != keys[k]) ++k;
      if (k == 3) fail("header key '" + printable(key) + "' is not one of descr, fortran_order, shape");
      if (seen[k]) fail("header key '" + key + "' appears twice");
      seen[k] = true;
      skip();
      expect(':', "a dict key is not followed by ':'");
      skip();
      if (k == 0) a.descr = string_literal("the value of 'descr'");
      else if (k == 1) a.fortran_order = boolean();
      else a.shape = tuple();
      skip();
      if (peek() == ',') {
        ++i_;
        skip();
      } else if (peek() != '}') {
        fail("dict entries are not separated by ','");
      }
    }
    ++i_;
    skip();
    if (i_ != t_.size()) {
      const std::string rest = t_.substr(i_, t_.find_last_not_of(" \t\r\n\f") + 1 - i_);
      fail("the header has text after its dict: '" + printable(rest, 20) + "'");
    }
    for (int k = 0; k < 3; ++k)
      if (!seen[k]) fail(std::string("header has no '") + keys[k] + "'");
  }

 private:
  [[noreturn]] void fail(const std::string& why) const { occseg::fail(name_, why); }

  int peek() const { return i_ < t_.size() ? static_cast<unsigned char>(t_[i_]) : -1; }

  void expect(char c, const char* why) {
    if (peek() != static_cast<unsigned char>(c)) fail(why);
    ++i_;
  }

  // Whitespace and comments, as Python's tokenizer skips them inside brackets.
  void skip() {
    while (i_ < t_.size()) {
      const char c = t_[i_];
      if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f') {
        ++i_;
      } else if (c == '#') {
        while (i_ < t_.size() && t_[i_] != '\n' && t_[i_] != '\r') ++i_;
      } else {
        break;
      }
    }
  }

  static bool name_char(int c) { return c == '_' || (c >= '0' && c <= '9') || ((c | 0x20) >= 'a' && (c | 0x20) <= 'z'); }

  std::string string_literal(const char* what) {
    const int q = peek();
    if (q != '\'' && q != '"') {
      if (name_char(q) && i_ + 1 < t_.size() && (t_[i_ + 1] == '\'' || t_[i_ + 1] == '"'))
        fail(std::string(what) + " has a string prefix (only plain '...' strings are read)");
      fail(std::string(what) + " is not a quoted string");
    }
    if (t_.compare(i_, 3, std::string(3, static_cast<char>(q))) == 0)
      fail(std::string(what) + " is a triple-quoted string (only plain '...' strings are read)");
    const std::size_t start = ++i_;
    while (i_ < t_.size() && t_[i_] != q) {
      if (t_[i_] == '\\') fail(std::string(what) + " has an escape sequence (not read)");
      if (t_[i_] == '\n' || t_[i_] == '\r') fail(std::string(what) + " is an unterminated string");
      ++i_;
    }
    if (i_ == t_.size()) fail(std::string(what) + " is an unterminated string");
    const std::string v = t_.substr(start, i_ - start);
    ++i_;
    skip();
    if (peek() == '\'' || peek() == '"') fail(std::string(what) + " is two adjacent strings (not read)");
    return v;
  }

  bool boolean() {
    for (const char* w : {"True", "False"}) {
      const std::size_t n = std::strlen(w);
      if (t_.compare(i_, n, w) == 0 && !name_char(i_ + n < t_.size() ? static_cast<unsigned char>(t_[i_ + n]) : -1)) {
        i_ += n;
        return w[0] == 'T';
      }
    }
    fail("the value of 'fortran_order' is not True or False");
  }

  std::size_t integer() {
    const int c = peek();
    if (c == '-') fail("a 'shape' entry is negative");
    if (c < '0' || c > '9') fail("the value of 'shape' is not a tuple of integers");
    const std::size_t start = i_;
    std::size_t v = 0;
    while (peek() >= '0' && peek() <= '9') {
      if (v > kMaxVoxels) fail("shape entry is absurdly large");
      v = v * 10 + std::size_t(t_[i_] - '0');
      ++i_;
    }
    // Python 3 has no leading zeros ("007" is a syntax error; "00" is 0).
    if (t_[start] == '0' && t_.find_first_not_of('0', start) < i_) fail("a 'shape' entry has a leading zero");
    if (longs_ && peek() == 'L') ++i_;  // Python 2's long suffix, which NumPy drops for versions 1 and 2
    if (name_char(peek()) || peek() == '.')
      fail("a 'shape' entry is not a plain decimal integer");
    return v;
  }

  std::vector<std::size_t> tuple() {
    expect('(', "the value of 'shape' is not a tuple");
    std::vector<std::size_t> v;
    bool trailing_comma = false;
    skip();
    while (peek() != ')') {
      v.push_back(integer());
      skip();
      trailing_comma = peek() == ',';
      if (trailing_comma) {
        ++i_;
        skip();
      } else if (peek() != ')') {
        fail("the entries of 'shape' are not separated by ','");
      }
    }
    ++i_;
    // "(3)" is the integer 3 in Python: NumPy refuses it as a shape.
    if (v.size() == 1 && !trailing_comma) fail("the value of 'shape' is an integer in parentheses, not a tuple");
    return v;
  }

  const std::string& t_;
  const std::string& name_;
  const bool longs_;
  std::size_t i_ = 0;
};

}  // namespace

std::size_t NpyArray::element_count() const {
  std::size_t n = 1;
  for (auto s : shape) n *= s;
  return n;
}

NpyArray parse_npy_header(const unsigned char* b, std::size_t size, const std::string& name, std::size_t& data_offset) {
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
  HeaderParser(h, name, major <= 2).parse(a);
  // Big-endian data ('>f4', '>f8', '>u2', ..., as NumPy writes arrays of that byte order, and
  // NumPy's np.load reads back) is swapped to little-endian as it is read (swap_to_little_endian);
  // '>u1' holds single bytes.
  if (a.descr.size() > 1 && a.descr[0] == '>' && item_size("<" + a.descr.substr(1))) {
    a.descr[0] = '<';
    a.big_endian = true;
    if (a.descr == "<u1") a.descr = "|u1";
  }
  const std::size_t isz = item_size(a.descr);
  if (!isz) fail(name, "dtype '" + printable(a.descr) + "' is not supported (use float32, float64, uint8 or uint16, either byte order)");
  std::size_t count = 1;
  for (const std::size_t v : a.shape) {
    if (v != 0 && count > kMaxVoxels / v) fail(name, "shape claims more than 2^40 elements");
    count *= v;
  }
  if (count > kMaxVoxels) fail(name, "shape claims more than 2^40 elements");
  data_offset = off + hlen;
  return a;
}

namespace {

void check_body(const NpyArray& a, std::size_t body, const std::string& name) {
  const std::size_t need = a.element_count() * item_size(a.descr);
  if (body < need)
    fail(name, "truncated data: header promises " + std::to_string(need) + " bytes, file has " + std::to_string(body));
}

// The grid of an array, checked (dims, dtype, geometry) but without its samples.
Grid npy_grid_frame(const NpyArray& a, double voxel_size, const std::string& name) {
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
  return g;
}

void checked_probabilities(const Grid& g, const std::string& name) {
  try {
    check_probabilities(g);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + name + "': " + e.what());
  }
}

// Threads for a pass over `bytes` bytes: all of `threads` for large ones (at most 8: copying from
// the page cache is bounded by memory bandwidth, not by cores), one for what is not worth
// starting a thread for.
int pass_threads(std::size_t bytes, int threads) {
  return bytes >= (std::size_t(8) << 20) ? std::min(resolve_threads(threads), 8) : 1;
}

// Reads the `n` data bytes of the file from `offset`, in pieces of whole elements that `threads`
// threads read at once (pread), reporting progress from the calling thread between groups of
// pieces; a file that ends early (it shrank since it was opened) is the truncation it is, with the
// count of the data bytes it still has. Each piece goes where `place(b, scratch)` says (the data
// byte b's place in the final array, or the reading thread's scratch of kPiece bytes) and is
// handed to `take(b, piece, bytes)` by the thread that read it, at once, while it is in that
// core's cache: it converts and checks it there, so the bytes checked are the bytes kept, read
// once. Returns false when `take` found some piece's values bad.
constexpr std::size_t kPiece = std::size_t(1) << 19;

template <class Place, class Take>
bool read_body(const InputFile& f, std::size_t offset, std::size_t n, const std::string& name, const IoProgress& progress,
               int threads, bool staged, Place place, Take take) {
  constexpr std::size_t kGroup = std::size_t(1) << 24;
  std::atomic<bool> ok{true};
  std::atomic<std::size_t> short_at{n};  // the lowest end of a short piece: where the file ends
  const int t = pass_threads(n, threads);
  for (std::size_t g0 = 0; g0 < n; g0 += kGroup) {
    const std::size_t g1 = std::min(n, g0 + kGroup), pieces = (g1 - g0 + kPiece - 1) / kPiece;
    parallel_for(pieces, t, [&](std::size_t k0, std::size_t k1) {
      UninitVector<unsigned char> scratch(staged ? kPiece : 0);
      for (std::size_t k = k0; k < k1; ++k) {
        const std::size_t b = g0 + k * kPiece, want = std::min(kPiece, g1 - b);
        unsigned char* const to = place(b, scratch.data());
        const std::size_t got = f.read_at(offset + b, to, want);
        if (got < want) {
          std::size_t seen = short_at.load();
          while (b + got < seen && !short_at.compare_exchange_weak(seen, b + got)) {
          }
          return;
        }
        if (!take(b, to, got)) ok.store(false, std::memory_order_relaxed);
      }
    });
    if (short_at.load() < n)
      fail(name, "truncated data: header promises " + std::to_string(n) + " bytes, file has " + std::to_string(short_at.load()));
    report_progress(progress, double(g1) / double(n));
  }
  return ok.load();
}

std::uint16_t byte_swapped(std::uint16_t v) { return __builtin_bswap16(v); }
std::uint32_t byte_swapped(std::uint32_t v) { return __builtin_bswap32(v); }
std::uint64_t byte_swapped(std::uint64_t v) { return __builtin_bswap64(v); }

// Reverses the bytes of each whole element of type U in bytes[0, n), at any alignment.
template <class U>
void swap_each(unsigned char* bytes, std::size_t n) {
  for (std::size_t i = 0; i + sizeof(U) <= n; i += sizeof(U)) {
    U v;
    std::memcpy(&v, bytes + i, sizeof v);
    v = byte_swapped(v);
    std::memcpy(bytes + i, &v, sizeof v);
  }
}

// The elements of a big-endian array in the machine's (little-endian) order.
void swap_to_little_endian(const NpyArray& a, unsigned char* bytes, std::size_t n) {
  if (!a.big_endian) return;
  switch (item_size(a.descr)) {
    case 2: swap_each<std::uint16_t>(bytes, n); break;
    case 4: swap_each<std::uint32_t>(bytes, n); break;
    case 8: swap_each<std::uint64_t>(bytes, n); break;
    default: break;
  }
}

// float(v / max) for every v of an unsigned integer type, computed once: a table look-up instead
// of a division per voxel, the same values.
template <class U>
const float* integer_probabilities() {
  static const std::vector<float> table = [] {
    constexpr std::size_t max = std::numeric_limits<U>::max();
    std::vector<float> t(max + 1);
    for (std::size_t v = 0; v <= max; ++v) t[v] = static_cast<float>(double(v) / double(max));
    return t;
  }();
  return table.data();
}

// Calls fn with the reader of one element of the array's dtype (element k of little-endian
// bytes e, as a probability): the type is decided once, not per voxel. u1 and u2 map 0..max to
// 0..1; f8 is rounded to float.
template <class Fn>
void with_element(const std::string& descr, Fn&& fn) {
  if (descr == "<f4")
    fn([](const unsigned char* e, std::size_t k) { float v; std::memcpy(&v, e + 4 * k, 4); return v; });
  else if (descr == "<f8")
    fn([](const unsigned char* e, std::size_t k) { double v; std::memcpy(&v, e + 8 * k, 8); return static_cast<float>(v); });
  else if (descr == "<u2")
    fn([t = integer_probabilities<std::uint16_t>()](const unsigned char* e, std::size_t k) {
      std::uint16_t v;
      std::memcpy(&v, e + 2 * k, 2);
      return t[v];
    });
  else
    fn([t = integer_probabilities<std::uint8_t>()](const unsigned char* e, std::size_t k) { return t[e[k]]; });
}

// The samples of a C-order array of any dtype straight from the file into the grid: each piece is
// read into its thread's scratch, swapped, converted into its place in g.p and checked there.
// Fortran order is read whole first (a row of the grid takes one element of every plane).
bool read_converted(const InputFile& f, std::size_t offset, const NpyArray& a, Grid& g, const std::string& path,
                    const IoProgress& progress, int threads) {
  const std::size_t isz = item_size(a.descr), n = g.dims.count();
  resize_for_fill(g.p, n, threads);
  float* const out = g.p.data();
  bool ok = true;
  with_element(a.descr, [&](auto value) {
    ok = read_body(f, offset, n * isz, path, progress, threads, true,
                   [](std::size_t, unsigned char* scratch) { return scratch; },
                   [&](std::size_t b, unsigned char* piece, std::size_t bytes) {
                     swap_to_little_endian(a, piece, bytes);
                     float* const o = out + b / isz;
                     const std::size_t count = bytes / isz;
                     for (std::size_t i = 0; i < count; ++i) o[i] = value(piece, i);
                     return probabilities_in_range(o, count);
                   });
  });
  return ok;
}

// The grid's values from a whole array (any dtype, C or Fortran order), in blocks over `threads`
// threads, each block checked as soon as it is written; false when some value is bad.
bool convert_array(const NpyArray& a, Grid& g, int threads) {
  const Dims d = g.dims;
  const std::size_t n = d.count();
  resize_for_fill(g.p, n, threads);
  float* const out = g.p.data();
  const unsigned char* const e = a.data.data();
  const int t = pass_threads(n * sizeof(float), threads);
  std::atomic<bool> ok{true};
  with_element(a.descr, [&](auto value) {
    if (!a.fortran_order) {
      constexpr std::size_t kBlock = std::size_t(1) << 14;
      parallel_for((n + kBlock - 1) / kBlock, t, [&](std::size_t k0, std::size_t k1) {
        for (std::size_t k = k0; k < k1; ++k) {
          const std::size_t i0 = k * kBlock, i1 = std::min(n, i0 + kBlock);
          for (std::size_t i = i0; i < i1; ++i) out[i] = value(e, i);
          if (!probabilities_in_range(out + i0, i1 - i0)) ok.store(false, std::memory_order_relaxed);
        }
      });
      return;
    }
    // The file index of [z, y, x] is z + nz * (y + ny * x). Per y, tiles of 16 x by every z: the
    // tile's 16 runs along z in the file are read side by side, each grid line is written whole
    // (a row of the grid alone would take one element of every plane of the file).
    constexpr std::size_t kTile = 16;
    parallel_for(d.ny, t, [&](std::size_t y0, std::size_t y1) {
      for (std::size_t y = y0; y < y1; ++y) {
        for (std::size_t x0 = 0; x0 < d.nx; x0 += kTile) {
          const std::size_t x1 = std::min(d.nx, x0 + kTile);
          for (std::size_t z = 0; z < d.nz; ++z) {
            float* const o = out + (z * d.ny + y) * d.nx;
            for (std::size_t x = x0; x < x1; ++x) o[x] = value(e, z + d.nz * (y + d.ny * x));
          }
        }
        for (std::size_t z = 0; z < d.nz; ++z)
          if (!probabilities_in_range(out + (z * d.ny + y) * d.nx, d.nx)) ok.store(false, std::memory_order_relaxed);
      }
    });
  });
  return ok.load();
}

}  // namespace

NpyArray parse_npy(const unsigned char* b, std::size_t size, const std::string& name) {
  std::size_t off = 0;
  NpyArray a = parse_npy_header(b, size, name, off);
  check_body(a, size - off, name);
  a.data.assign(b + off, b + off + a.element_count() * item_size(a.descr));
  swap_to_little_endian(a, a.data.data(), a.data.size());
  return a;
}

Grid read_npy_grid(const std::string& path, double voxel_size, NpyArray* header, const IoProgress& progress, int threads) {
  InputFile f(path);
  // The fixed prefix (magic, version, header length), then the header it announces.
  std::vector<unsigned char> head(12);
  head.resize(f.read(head.data(), std::min<std::size_t>(12, f.size())));
  std::size_t hlen = 0, off = 10;
  if (head.size() >= 10 && head[6] == 1) hlen = head[8] | (std::size_t(head[9]) << 8);
  else if (head.size() >= 12 && (head[6] == 2 || head[6] == 3))
    hlen = head[8] | (std::size_t(head[9]) << 8) | (std::size_t(head[10]) << 16) | (std::size_t(head[11]) << 24), off = 12;
  const std::size_t want = std::min(f.size(), off + hlen);  // a header beyond the file: parse says truncated
  if (want > head.size()) {
    const std::size_t had = head.size();
    head.resize(want);
    head.resize(had + f.read(head.data() + had, want - had));
  }
  std::size_t data_at = 0;
  NpyArray a = parse_npy_header(head.data(), head.size(), path, data_at);
  // A header that parses is a dict of at least two bytes, so the 12 bytes read first never reach
  // into the data: the file is positioned at data_at.
  check_body(a, f.size() - data_at, path);
  Grid g = npy_grid_frame(a, voxel_size, path);
  const std::size_t n = g.dims.count(), bytes = n * item_size(a.descr);
  bool values_ok = false;
  if (a.descr == "<f4" && !a.fortran_order && !a.big_endian) {  // the file's bytes are the grid's
    resize_for_fill(g.p, n, threads);
    unsigned char* const to = reinterpret_cast<unsigned char*>(g.p.data());
    values_ok = read_body(f, data_at, bytes, path, progress, threads, false,
                          [to](std::size_t b, unsigned char*) { return to + b; },
                          [](std::size_t, const unsigned char* piece, std::size_t got) {
                            return probabilities_in_range(reinterpret_cast<const float*>(piece), got / sizeof(float));
                          });
  } else if (!a.fortran_order) {
    values_ok = read_converted(f, data_at, a, g, path, progress, threads);
  } else {
    a.data.resize(bytes);
    unsigned char* const to = a.data.data();
    read_body(f, data_at, bytes, path, progress, threads, false, [to](std::size_t b, unsigned char*) { return to + b; },
              [](std::size_t, const unsigned char*, std::size_t) { return true; });
    swap_to_little_endian(a, a.data.data(), bytes);
    values_ok = convert_array(a, g, threads);
  }
  if (!values_ok) checked_probabilities(g, path);  // names the first bad voxel
  if (header) {
    a.data.clear();
    a.data.shrink_to_fit();
    *header = std::move(a);
  }
  return g;
}

NpyArray read_npy(const std::string& path) {
  const std::string bytes = read_file(path);
  return parse_npy(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), path);
}

void write_npy(const std::string& path, const std::string& descr, const std::vector<std::size_t>& shape,
               const void* data, std::size_t bytes, StagedFiles* into) {
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
  }, into);
}

Grid grid_from_npy(const NpyArray& a, double voxel_size, const std::string& name) {
  Grid g = npy_grid_frame(a, voxel_size, name);
  if (!convert_array(a, g, 0)) checked_probabilities(g, name);  // names the first bad voxel
  return g;
}

void write_grid_npy(const std::string& path, const Grid& g, StagedFiles* into) {
  write_npy(path, "<f4", {g.dims.nz, g.dims.ny, g.dims.nx}, g.p.data(), g.p.size() * sizeof(float), into);
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

void write_labels_npy(const std::string& path, const Dims& d, const LabelArray& labels, StagedFiles* into) {
  write_npy(path, "<u4", {d.nz, d.ny, d.nx}, labels.data(), labels.size() * sizeof(std::uint32_t), into);
}

}  // namespace occseg
