#include "occseg/map_yaml.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <map>
#include <set>
#include <sstream>

#include "occseg/error.hpp"
#include "occseg/file_read.hpp"
#include "occseg/file_write.hpp"
#include "occseg/params.hpp"

namespace occseg {

namespace {

// ---- the YAML subset ------------------------------------------------------------------------

// One value of a top-level key: a scalar or a sequence of scalars, with the line it is on.
struct YamlValue {
  std::size_t line = 0;
  bool sequence = false;
  std::vector<std::string> items;  // a scalar is one item
};

class YamlReader {
 public:
  YamlReader(const std::string& text, const std::string& name) : name_(name) { parse(text); }

  const YamlValue* find(const std::string& key) const {
    const auto it = keys_.find(key);
    return it == keys_.end() ? nullptr : &it->second;
  }
  [[noreturn]] void fail(std::size_t line, const std::string& why) const {
    throw Error(Status::format, "'" + name_ + "': line " + std::to_string(line) + ": " + why);
  }

 private:
  static bool blank(char c) { return c == ' ' || c == '\t'; }
  static std::string trim(const std::string& s) {
    std::size_t a = 0, b = s.size();
    while (a < b && blank(s[a])) ++a;
    while (b > a && blank(s[b - 1])) --b;
    return s.substr(a, b - a);
  }

  // The line without its comment: '#' at the start or after a blank, outside quotes. A quote
  // opens a quoted scalar only where a value starts (after ':', '-', '[', ',' or at the start);
  // inside a plain scalar (it's.pgm) it is an ordinary character.
  std::string uncomment(const std::string& s, std::size_t line) const {
    char quote = 0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      const char c = s[i];
      if (quote) {
        if (c == '\\' && quote == '"') ++i;
        else if (c == '\'' && quote == '\'' && i + 1 < s.size() && s[i + 1] == '\'') ++i;  // '' inside '...'
        else if (c == quote) quote = 0;
      } else if ((c == '\'' || c == '"') && value_starts(s, i)) {
        quote = c;
      } else if (c == '#' && (i == 0 || blank(s[i - 1]))) {
        return s.substr(0, i);
      }
    }
    if (quote) fail(line, "unterminated quoted string");
    return s;
  }

  static bool value_starts(const std::string& s, std::size_t i) {
    while (i > 0 && blank(s[i - 1])) --i;
    return i == 0 || s[i - 1] == ':' || s[i - 1] == '-' || s[i - 1] == '[' || s[i - 1] == ',';
  }

  // A scalar: quoted ('it''s', "a \"b\"") or plain. Plain scalars that would start a YAML
  // construct outside the subset are refused rather than misread.
  std::string scalar(const std::string& raw, std::size_t line) const {
    const std::string s = trim(raw);
    if (s.empty()) return s;
    if (s[0] == '\'' || s[0] == '"') {
      const char q = s[0];
      std::string out;
      std::size_t i = 1;
      for (; i < s.size(); ++i) {
        if (s[i] == q) {
          if (q == '\'' && i + 1 < s.size() && s[i + 1] == '\'') {
            out += '\'';
            ++i;
            continue;
          }
          break;
        }
        if (q == '"' && s[i] == '\\') {
          if (i + 1 >= s.size()) break;
          const char e = s[++i];
          if (e == '"' || e == '\\' || e == '/') out += e;
          else if (e == 't') out += '\t';
          else if (e == 'n') out += '\n';
          else fail(line, std::string("escape '\\") + e + "' is not supported");
          continue;
        }
        out += s[i];
      }
      if (i >= s.size()) fail(line, "unterminated quoted string");
      if (!trim(s.substr(i + 1)).empty()) fail(line, "text after the closing quote");
      return out;
    }
    const char c = s[0];
    if (c == '{') fail(line, "flow mappings ({...}) are not supported: map_server files hold plain values");
    if (c == '&' || c == '*') fail(line, "anchors and aliases are not supported");
    if (c == '!') fail(line, "tags are not supported");
    if (c == '|' || c == '>') fail(line, "block scalars (| and >) are not supported");
    if (c == '[' || c == ']' || c == ',' || c == '@' || c == '`' || c == '%')
      fail(line, "'" + s + "' is not a plain value");
    if (s.find(": ") != std::string::npos || s.back() == ':')
      fail(line, "nested mappings are not supported: map_server files hold one key per line");
    return s;
  }

  // [a, b, c] on one line.
  std::vector<std::string> flow_sequence(const std::string& s, std::size_t line) const {
    if (s.back() != ']') fail(line, "a flow sequence must close with ']' on the same line");
    const std::string inner = trim(s.substr(1, s.size() - 2));
    std::vector<std::string> items;
    if (inner.empty()) return items;
    std::size_t start = 0;
    char quote = 0;
    for (std::size_t i = 0; i <= inner.size(); ++i) {
      if (i < inner.size() && quote) {
        if (inner[i] == '\\' && quote == '"') ++i;
        else if (inner[i] == quote) quote = 0;
        continue;
      }
      if (i < inner.size() && (inner[i] == '\'' || inner[i] == '"')) {
        quote = inner[i];
        continue;
      }
      if (i < inner.size() && (inner[i] == '[' || inner[i] == '{'))
        fail(line, "nested sequences and mappings are not supported");
      if (i == inner.size() || inner[i] == ',') {
        const std::string item = trim(inner.substr(start, i - start));
        if (item.empty()) fail(line, "empty item in a flow sequence");
        items.push_back(scalar(item, line));
        start = i + 1;
      }
    }
    return items;
  }

  void parse(const std::string& text) {
    std::size_t line = 0, pos = 0;
    std::string open_key;  // a key whose value is a block sequence on the following lines
    bool document_started = false;
    while (pos <= text.size()) {
      const std::size_t end = std::min(text.find('\n', pos), text.size());
      std::string raw = text.substr(pos, end - pos);
      pos = end + 1;
      ++line;
      if (!raw.empty() && raw.back() == '\r') raw.pop_back();
      if (raw.find('\0') != std::string::npos) fail(line, "a NUL byte (is this a YAML file?)");
      std::string s = uncomment(raw, line);
      if (trim(s).empty()) {
        if (end == text.size()) break;
        continue;
      }
      std::size_t indent = 0;
      while (indent < s.size() && blank(s[indent])) {
        if (s[indent] == '\t') fail(line, "a tab in the indentation (YAML allows spaces only)");
        ++indent;
      }
      const std::string body = trim(s);
      if (indent == 0 && (body == "---" || body.rfind("--- ", 0) == 0)) {
        if (document_started) fail(line, "a second YAML document");
        document_started = true;
        if (!trim(body.substr(3)).empty()) fail(line, "a value after '---'");
        open_key.clear();
        continue;
      }
      if (indent == 0 && body == "...") break;
      if (indent == 0 && body[0] == '%') fail(line, "YAML directives are not supported");
      document_started = true;
      if (body[0] == '-' && (body.size() == 1 || blank(body[1]))) {
        if (open_key.empty()) fail(line, "a sequence item outside a key's value");
        YamlValue& v = keys_[open_key];
        v.sequence = true;
        const std::string item = trim(body.substr(1));
        if (item.empty()) fail(line, "an empty sequence item");
        if (item[0] == '-' && (item.size() == 1 || blank(item[1]))) fail(line, "nested sequences are not supported");
        v.items.push_back(scalar(item, line));
        continue;
      }
      if (indent != 0) fail(line, "nested mappings are not supported: map_server files hold one key per line");
      open_key.clear();
      std::size_t colon = std::string::npos;
      for (std::size_t i = 0; i < body.size(); ++i)
        if (body[i] == ':' && (i + 1 == body.size() || blank(body[i + 1]))) {
          colon = i;
          break;
        }
      if (colon == std::string::npos || colon == 0) fail(line, "expected 'key: value'");
      const std::string key = trim(body.substr(0, colon));
      if (key[0] == '\'' || key[0] == '"' || key[0] == '?' || key[0] == '[' || key[0] == '{')
        fail(line, "'" + key + "' is not a plain key");
      if (keys_.count(key)) fail(line, "key '" + key + "' appears twice (first on line " + std::to_string(keys_[key].line) + ")");
      YamlValue v;
      v.line = line;
      const std::string value = trim(body.substr(colon + 1));
      if (value.empty()) {
        open_key = key;  // a block sequence may follow; otherwise the value is empty (null)
      } else if (value[0] == '[') {
        v.sequence = true;
        v.items = flow_sequence(value, line);
      } else {
        v.items.push_back(scalar(value, line));
      }
      keys_[key] = v;
      if (end == text.size()) break;
    }
  }

  std::string name_;
  std::map<std::string, YamlValue> keys_;
};

std::string fmt(double v) {
  char t[64];
  std::snprintf(t, sizeof t, "%.9g", v);
  return t;
}

// A number as yaml-cpp's as<double> reads one: the whole text, finite.
double number(const YamlReader& y, const YamlValue& v, const std::string& key, const std::string& text) {
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double d = std::strtod(s, &end);
  if (text.empty() || end == s || *end != '\0' || errno == ERANGE || !std::isfinite(d) || text.find_first_of("xXpP") != std::string::npos)
    y.fail(v.line, key + ": '" + text + "' is not a finite number");
  return d;
}

const YamlValue& required(const YamlReader& y, const std::string& key, const std::string& name) {
  const YamlValue* v = y.find(key);
  if (!v)
    throw Error(Status::format, "'" + name + "': no '" + key +
                                    "' key (a map_server map needs image, resolution, origin, negate, "
                                    "occupied_thresh and free_thresh)");
  return *v;
}

double scalar_number(const YamlReader& y, const std::string& key, const std::string& name) {
  const YamlValue& v = required(y, key, name);
  if (v.sequence || v.items.size() != 1) y.fail(v.line, key + ": expected a number");
  return number(y, v, key, v.items[0]);
}

std::string folder_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

// ---- PGM ------------------------------------------------------------------------------------

[[noreturn]] void bad_pgm(const std::string& name, const std::string& why) {
  throw Error(Status::format, "'" + name + "' is not a valid PGM image: " + why);
}

bool pgm_space(unsigned char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

// Skips white space and # comments (to the end of the line).
void skip_space(const unsigned char* b, std::size_t size, std::size_t& i) {
  while (i < size) {
    if (pgm_space(b[i])) ++i;
    else if (b[i] == '#') {
      while (i < size && b[i] != '\n' && b[i] != '\r') ++i;
    } else break;
  }
}

// An unsigned decimal header or raster number; at most `limit`.
std::size_t pgm_number(const unsigned char* b, std::size_t size, std::size_t& i, std::size_t limit,
                       const std::string& name, const char* what) {
  skip_space(b, size, i);
  if (i >= size) bad_pgm(name, std::string("truncated: the file ends before the ") + what);
  if (b[i] < '0' || b[i] > '9') bad_pgm(name, std::string("the ") + what + " is not a decimal number");
  std::size_t v = 0;
  while (i < size && b[i] >= '0' && b[i] <= '9') {
    v = v * 10 + std::size_t(b[i] - '0');
    if (v > limit) bad_pgm(name, std::string("the ") + what + " is larger than " + std::to_string(limit));
    ++i;
  }
  if (i < size && !pgm_space(b[i]) && b[i] != '#') bad_pgm(name, std::string("the ") + what + " is not a decimal number");
  return v;
}

}  // namespace

MapYaml parse_map_yaml(const std::string& text, const std::string& name) {
  const YamlReader y(text, name);
  MapYaml m;
  const YamlValue& image = required(y, "image", name);
  if (image.sequence || image.items.size() != 1 || image.items[0].empty())
    y.fail(image.line, "image: expected the image file's name");
  m.image = image.items[0];
  m.image_path = m.image[0] == '/' ? m.image : folder_of(name) + "/" + m.image;

  m.resolution = scalar_number(y, "resolution", name);
  if (!(m.resolution > 0)) y.fail(y.find("resolution")->line, "resolution: " + fmt(m.resolution) + " is not positive");

  const YamlValue& origin = required(y, "origin", name);
  if (!origin.sequence || origin.items.size() != 3)
    y.fail(origin.line, "origin: expected [x, y, yaw], 3 numbers" +
                            (origin.sequence ? ", not " + std::to_string(origin.items.size()) : std::string()));
  for (int k = 0; k < 3; ++k) m.origin[k] = number(y, origin, "origin", origin.items[k]);
  if (m.origin[2] != 0)
    throw Error(Status::unsupported, "'" + name + "': line " + std::to_string(origin.line) + ": origin yaw " +
                                         fmt(m.origin[2]) +
                                         " is not 0: occseg maps are axis-aligned grids, and a rotated map "
                                         "would have to be resampled (rotate the image and set yaw 0)");

  const YamlValue& negate = required(y, "negate", name);
  if (negate.sequence || negate.items.size() != 1) y.fail(negate.line, "negate: expected 0, 1, true or false");
  {
    // map_server reads negate as an int first, then as a YAML bool.
    const std::string& t = negate.items[0];
    char* end = nullptr;
    const long v = std::strtol(t.c_str(), &end, 10);
    static const std::set<std::string> truths = {"true", "True", "TRUE", "yes", "Yes", "YES", "on", "On", "ON", "y", "Y"};
    static const std::set<std::string> falses = {"false", "False", "FALSE", "no", "No", "NO", "off", "Off", "OFF", "n", "N"};
    if (!t.empty() && end != t.c_str() && *end == '\0') m.negate = v != 0;
    else if (truths.count(t)) m.negate = true;
    else if (falses.count(t)) m.negate = false;
    else y.fail(negate.line, "negate: '" + t + "' is not 0, 1, true or false");
  }

  m.occupied_thresh = scalar_number(y, "occupied_thresh", name);
  m.free_thresh = scalar_number(y, "free_thresh", name);
  if (const YamlValue* mode = y.find("mode")) {
    const std::string t = mode->sequence || mode->items.size() != 1 ? "" : mode->items[0];
    if (t == "trinary") m.mode = MapMode::trinary;
    else if (t == "scale") m.mode = MapMode::scale;
    else if (t == "raw") m.mode = MapMode::raw;
    else y.fail(mode->line, "mode: '" + t + "' is not trinary, scale or raw");
  }
  const std::size_t tl = y.find("occupied_thresh")->line;
  if (!(m.occupied_thresh >= 0 && m.occupied_thresh <= 1)) y.fail(tl, "occupied_thresh: " + fmt(m.occupied_thresh) + " is outside [0, 1]");
  const std::size_t fl = y.find("free_thresh")->line;
  if (!(m.free_thresh >= 0 && m.free_thresh <= 1)) y.fail(fl, "free_thresh: " + fmt(m.free_thresh) + " is outside [0, 1]");
  if (m.free_thresh > m.occupied_thresh)
    y.fail(fl, "free_thresh " + fmt(m.free_thresh) + " is above occupied_thresh " + fmt(m.occupied_thresh));
  if (m.mode == MapMode::scale && m.free_thresh == m.occupied_thresh)
    y.fail(fl, "free_thresh equals occupied_thresh: scale mode divides by their difference");
  return m;
}

PgmImage parse_pgm(const unsigned char* b, std::size_t size, const std::string& name) {
  if (size >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G')
    throw Error(Status::unsupported, "'" + name + "' is a PNG image; occseg reads map images as PGM (P5 or P2): "
                                                  "convert it, e.g. with `convert map.png map.pgm` or `pngtopnm`");
  if (size < 2 || b[0] != 'P' || (b[1] != '5' && b[1] != '2')) {
    if (size >= 2 && b[0] == 'P' && b[1] >= '1' && b[1] <= '7')
      bad_pgm(name, std::string("it is a netpbm P") + char(b[1]) + " file; map images are greyscale PGM (P5 or P2)");
    bad_pgm(name, "wrong magic (expected P5 or P2)");
  }
  const bool plain = b[1] == '2';
  std::size_t i = 2;
  if (i < size && !pgm_space(b[i]) && b[i] != '#') bad_pgm(name, "wrong magic (expected P5 or P2)");
  PgmImage img;
  img.width = pgm_number(b, size, i, kMaxVoxels, name, "width");
  img.height = pgm_number(b, size, i, kMaxVoxels, name, "height");
  img.maxval = static_cast<unsigned>(pgm_number(b, size, i, 65535, name, "maxval"));
  if (img.width == 0 || img.height == 0)
    bad_pgm(name, std::to_string(img.width) + " x " + std::to_string(img.height) + " pixels: a map needs at least one");
  if (img.height > kMaxVoxels / img.width)
    bad_pgm(name, std::to_string(img.width) + " x " + std::to_string(img.height) + " pixels is more than 2^40");
  if (img.maxval == 0) bad_pgm(name, "maxval is 0 (must be 1..65535)");
  const std::size_t n = img.width * img.height;
  if (!plain) {
    if (i >= size || !pgm_space(b[i])) bad_pgm(name, "truncated: no white space after maxval");
    ++i;  // exactly one white-space byte, then the raster
    const std::size_t bytes = img.maxval > 255 ? 2 : 1;
    if ((size - i) / bytes < n)
      bad_pgm(name, "truncated raster: " + std::to_string(img.width) + " x " + std::to_string(img.height) + " pixels need " +
                        std::to_string(n * bytes) + " bytes, the file has " + std::to_string(size - i));
    img.pixels.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const unsigned v = bytes == 2 ? (unsigned(b[i + 2 * k]) << 8 | b[i + 2 * k + 1]) : b[i + k];
      if (v > img.maxval)
        bad_pgm(name, "pixel (" + std::to_string(k % img.width) + ", " + std::to_string(k / img.width) + ") = " +
                          std::to_string(v) + " is above maxval " + std::to_string(img.maxval));
      img.pixels[k] = static_cast<std::uint16_t>(v);
    }
  } else {
    // Each sample takes at least two bytes (a digit and a separator), which bounds the
    // allocation by the file's size before a single sample is read.
    if ((size - i) / 2 + 1 < n)
      bad_pgm(name, "truncated raster: " + std::to_string(n) + " samples cannot fit in " + std::to_string(size - i) + " bytes");
    img.pixels.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      skip_space(b, size, i);
      if (i >= size)
        bad_pgm(name, "truncated raster: " + std::to_string(k) + " of " + std::to_string(n) + " samples");
      const std::size_t v = pgm_number(b, size, i, 65535, name, "sample");
      if (v > img.maxval)
        bad_pgm(name, "pixel (" + std::to_string(k % img.width) + ", " + std::to_string(k / img.width) + ") = " +
                          std::to_string(v) + " is above maxval " + std::to_string(img.maxval));
      img.pixels[k] = static_cast<std::uint16_t>(v);
    }
  }
  return img;
}

std::vector<std::int8_t> map_server_cells(const MapYaml& m, const PgmImage& img) {
  std::vector<std::int8_t> cells(img.width * img.height);
  const double maxval = img.maxval;
  for (std::size_t y = 0; y < img.height; ++y)
    for (std::size_t x = 0; x < img.width; ++x) {
      const double shade = img.pixels[y * img.width + x] / maxval;
      const double occ = m.negate ? shade : 1.0 - shade;
      int cell;
      if (m.mode == MapMode::raw) {
        const double v = std::round(shade * 255);
        cell = v >= 0 && v <= 100 ? static_cast<int>(v) : -1;
      } else if (m.occupied_thresh < occ) {
        cell = 100;
      } else if (occ < m.free_thresh) {
        cell = 0;
      } else if (m.mode == MapMode::trinary) {
        cell = -1;
      } else {  // scale (a PGM has no alpha, so every pixel is opaque)
        cell = static_cast<int>(std::rint((occ - m.free_thresh) / (m.occupied_thresh - m.free_thresh) * 100.0));
      }
      cells[img.width * (img.height - y - 1) + x] = static_cast<std::int8_t>(cell);  // image top = largest y
    }
  return cells;
}

Grid read_map_yaml(const std::string& path) {
  const MapYaml m = parse_map_yaml(read_file(path), path);
  std::string bytes;
  try {
    bytes = read_file(m.image_path);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': image '" + m.image + "': " + e.what());
  }
  PgmImage img;
  try {
    img = parse_pgm(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), m.image_path);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
  bytes = std::string();
  const std::vector<std::int8_t> cells = map_server_cells(m, img);
  Grid g;
  g.dims = Dims{img.width, img.height, 1};
  g.voxel_size = m.resolution;
  g.origin = {m.origin[0], m.origin[1], 0.0};
  g.p.resize(cells.size());
  for (std::size_t k = 0; k < cells.size(); ++k) occupancy_cell_probability(cells[k], g.p[k]);  // always -1..100
  return g;
}

void write_state_pgm(const std::string& path, const Dims& d, const std::vector<std::uint8_t>& states,
                     StagedFiles* into) {
  if (d.nz != 1)
    throw Error(Status::invalid_argument, "'" + path + "': a PGM map holds one layer; the map has nz = " + std::to_string(d.nz));
  if (states.size() != d.count())
    throw Error(Status::invalid_argument, "'" + path + "': " + std::to_string(states.size()) + " states for " +
                                              std::to_string(d.count()) + " cells");
  std::string raster(d.count(), '\0');
  for (std::size_t y = 0; y < d.ny; ++y)
    for (std::size_t x = 0; x < d.nx; ++x) {
      const auto s = static_cast<State>(states[x + d.nx * y]);
      raster[(d.ny - 1 - y) * d.nx + x] = static_cast<char>(
          s == State::occupied ? kPgmOccupied : (s == State::free ? kPgmFree : kPgmUnknown));
    }
  const std::string header = "P5\n# occseg segmentation: occupied 0, free 254, unknown 205\n" + std::to_string(d.nx) +
                             " " + std::to_string(d.ny) + "\n255\n";
  write_file_atomically(path, [&](std::ostream& o) {
    o.write(header.data(), static_cast<std::streamsize>(header.size()));
    o.write(raster.data(), static_cast<std::streamsize>(raster.size()));
  }, into);
}

namespace {

// The shortest text that reads back as the same double.
std::string exact(double v) {
  char t[64];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(t, sizeof t, "%.*g", digits, v);
    if (std::strtod(t, nullptr) == v) break;
  }
  return t;
}

}  // namespace

void write_map_yaml(const std::string& path, const std::string& image, const Grid& g, StagedFiles* into) {
  std::ostringstream o;
  o << "image: " << image << "\n"
    << "mode: trinary\n"
    << "resolution: " << exact(g.voxel_size) << "\n"
    << "origin: [" << exact(g.origin[0]) << ", " << exact(g.origin[1]) << ", 0]\n"
    << "negate: 0\n"
    << "occupied_thresh: 0.65\n"
    << "free_thresh: 0.196\n";
  const std::string text = o.str();
  write_file_atomically(path, [&](std::ostream& s) { s << text; }, into);
}

}  // namespace occseg
