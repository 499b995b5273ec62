// .bt and .ot files. OctoMap's readers trust the file: a truncated or corrupt body makes them
// read uninitialised bytes and recurse without bound. So the structure is walked here first
// (bounded depth, every byte accounted for), and only a file that passes goes to OctoMap.
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/file_read.hpp"
#include "occseg/octomap_tree.hpp"

namespace occseg {

namespace {

constexpr int kTreeDepth = 16;  // octomap's OcTree, ColorOcTree and OcTreeStamped

[[noreturn]] void bad(const std::string& path, const std::string& why) {
  throw Error(Status::format, "'" + path + "' is not a valid OctoMap file: " + why);
}

std::string slurp(const std::string& path) { return read_file(path); }

struct Header {
  bool binary = false;  // .bt ("# Octomap OcTree binary file") or .ot ("# Octomap OcTree file")
  std::string id;
  unsigned long size = 0;
  double res = 0;
  std::size_t data = 0;  // offset of the first data byte
};

// The text header, as OctoMap's AbstractOcTree::readHeader reads it: keyword lines up to "data".
Header parse_header(const std::string& b, const std::string& path) {
  Header h;
  const std::size_t eol = b.find('\n');
  const std::string first = b.substr(0, eol);
  if (first.rfind("# Octomap OcTree binary file", 0) == 0) h.binary = true;
  else if (first.rfind("# Octomap OcTree file", 0) == 0) h.binary = false;
  else bad(path, "the first line is not an OctoMap header (legacy .bt files: convert them with convert_octree)");
  std::size_t pos = eol == std::string::npos ? b.size() : eol + 1;
  bool have_size = false, have_res = false;
  while (pos < b.size()) {
    std::size_t e = b.find('\n', pos);
    if (e == std::string::npos) bad(path, "the header has no 'data' line");
    std::istringstream line(b.substr(pos, e - pos));
    pos = e + 1;
    std::string key;
    if (!(line >> key) || key[0] == '#') continue;
    if (key == "data") {
      h.data = pos;
      if (h.id.empty()) bad(path, "the header has no 'id'");
      if (!have_size || !have_res || !(h.res > 0) || !std::isfinite(h.res)) bad(path, "the header has no valid 'size' and 'res'");
      if (h.id == "1") h.id = "OcTree";  // deprecated id, as OctoMap maps it
      return h;
    }
    if (key == "id") line >> h.id;
    else if (key == "size") have_size = static_cast<bool>(line >> h.size);
    else if (key == "res") have_res = static_cast<bool>(line >> h.res);
  }
  bad(path, "the header has no 'data' line");
}

// Walks a .bt body (2 bytes per inner node: 2 bits per child, 01 free leaf, 10 occupied leaf,
// 11 inner node, 00 absent). Returns the number of nodes.
struct Walker {
  const std::string& b;
  const std::string& path;
  std::size_t pos;
  std::size_t payload = 0;  // .ot: bytes of node data before the child byte
  unsigned long nodes = 0;

  unsigned char byte() {
    if (pos >= b.size()) bad(path, "the tree data is truncated at byte " + std::to_string(pos));
    return static_cast<unsigned char>(b[pos++]);
  }
  void binary_node(int depth) {
    if (depth >= kTreeDepth) bad(path, "the tree is deeper than " + std::to_string(kTreeDepth) + " levels");
    const unsigned bits = byte() | (unsigned(byte()) << 8);
    int n_inner = 0;
    for (int i = 0; i < 8; ++i) {
      const unsigned code = (bits >> (2 * i)) & 3u;
      nodes += code != 0;
      n_inner += code == 3;
    }
    for (int k = 0; k < n_inner; ++k) binary_node(depth + 1);
  }
  void full_node(int depth) {
    if (depth > kTreeDepth) bad(path, "the tree is deeper than " + std::to_string(kTreeDepth) + " levels");
    if (b.size() - pos < payload) bad(path, "the tree data is truncated at byte " + std::to_string(pos));
    float l;
    std::memcpy(&l, b.data() + pos, sizeof l);
    if (!std::isfinite(l)) bad(path, "a node's log-odds at byte " + std::to_string(pos) + " is not finite");
    pos += payload;
    ++nodes;
    const unsigned children = byte();
    for (int i = 0; i < 8; ++i)
      if (children & (1u << i)) full_node(depth + 1);
  }
};

template <typename Tree>
Grid read_full(const std::string& bytes, const Header& h, const std::string& path, const OctreeOptions& o) {
  std::istringstream in(bytes);
  std::unique_ptr<octomap::AbstractOcTree> t(octomap::AbstractOcTree::read(in));
  const Tree* tree = dynamic_cast<const Tree*>(t.get());
  if (!tree) bad(path, "OctoMap could not read a tree of type '" + h.id + "'");
  return grid_from_octree(*tree, o);
}

}  // namespace

Grid read_octree_file(const std::string& path, const OctreeOptions& options) {
  options.validate();
  const std::string bytes = slurp(path);
  const Header h = parse_header(bytes, path);
  Walker w{bytes, path, h.data};
  if (h.binary) {
    if (h.id != "OcTree") throw Error(Status::unsupported, "'" + path + "': binary tree type '" + h.id + "' is not supported");
    if (h.size > 0) {
      w.nodes = 1;
      w.binary_node(0);
    }
  } else {
    if (h.id == "OcTree") w.payload = 4;                // float log-odds
    else if (h.id == "ColorOcTree") w.payload = 7;      // + r, g, b
    else if (h.id == "OcTreeStamped") w.payload = 8;    // + uint32 time stamp
    else throw Error(Status::unsupported, "'" + path + "': tree type '" + h.id +
                                              "' is not supported (OcTree, ColorOcTree, OcTreeStamped)");
    if (h.size > 0) w.full_node(0);
  }
  if (w.nodes != h.size)
    bad(path, "the header promises " + std::to_string(h.size) + " nodes, the data holds " + std::to_string(w.nodes));
  try {
    if (h.binary) {
      octomap::OcTree tree(h.res);
      std::istringstream in(bytes);
      if (!tree.readBinary(in)) bad(path, "OctoMap's readBinary failed");
      return grid_from_octree(tree, options);
    }
    if (h.id == "OcTree") return read_full<octomap::OcTree>(bytes, h, path, options);
    if (h.id == "ColorOcTree") return read_full<octomap::ColorOcTree>(bytes, h, path, options);
    return read_full<octomap::OcTreeStamped>(bytes, h, path, options);
  } catch (const Error& e) {
    if (e.status() == Status::format) throw;
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
}

}  // namespace occseg
