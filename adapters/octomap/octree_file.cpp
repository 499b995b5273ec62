// .bt and .ot files. OctoMap's readers trust the file: a truncated or corrupt body makes them
// read uninitialised bytes and recurse without bound. So the header is parsed here as OctoMap
// parses it, the tree structure is walked (bounded depth, every byte accounted for), and only the
// walked tree bytes of a file that passes go to OctoMap.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "occseg/error.hpp"
#include "occseg/file_read.hpp"
#include "occseg/io_progress.hpp"
#include "occseg/octomap_tree.hpp"
#include "octree_header.hpp"
#include "octree_leaves.hpp"

namespace occseg {

namespace {

constexpr int kTreeDepth = 16;  // octomap's OcTree, ColorOcTree and OcTreeStamped

[[noreturn]] void bad(const std::string& path, const std::string& why) {
  throw Error(Status::format, "'" + path + "' is not a valid OctoMap file: " + why);
}

std::string slurp(const std::string& path) { return read_file(path); }

// OctoMap's keys are 16 bits per axis: coordinates span +-2^15 voxels around the origin.
constexpr double kKeyHalfRange = 32768.0;

struct Header {
  bool binary = false;  // .bt ("# Octomap OcTree binary file") or .ot ("# Octomap OcTree file")
  std::string id;
  unsigned size = 0;
  double res = 0;
  std::size_t data = 0;  // offset of the first data byte
};

// The text header, parsed as liboctomap parses it (octree_header.hpp), plus what occseg needs
// beyond liboctomap's own checks: a resolution at which every key has a finite coordinate.
Header parse_header(const std::string& b, const std::string& path) {
  const octree_detail::RawHeader raw = octree_detail::parse_raw_header(b);
  if (!raw.first_line)
    bad(path, "the first line is not an OctoMap header (legacy .bt files: convert them with convert_octree)");
  if (!raw.data_word) bad(path, "the header has no 'data' word (or a value OctoMap cannot read before it)");
  if (!raw.complete) bad(path, raw.id.empty() ? "the header has no 'id'" : "the header has no valid 'res'");
  Header h;
  h.binary = raw.binary;
  h.id = raw.id;
  h.size = raw.size;
  h.res = raw.res;
  h.data = raw.data;
  if (!(h.res > 0) || !std::isfinite(h.res * kKeyHalfRange)) {
    char t[40];
    std::snprintf(t, sizeof t, "%.17g", h.res);
    bad(path, std::string("resolution ") + t + " is too large for OctoMap's 16-bit keys");
  }
  return h;
}

// Walks a .bt body (2 bytes per inner node: 2 bits per child, 01 free leaf, 10 occupied leaf,
// 11 inner node, 00 absent). Returns the number of nodes.
struct Walker {
  const std::string& b;
  const std::string& path;
  std::size_t pos;
  std::size_t payload = 0;  // .ot: bytes of node data before the child byte
  unsigned long nodes = 0;

  // .bt: the leaves as liboctomap's readBinaryData would make them (OccupancyOcTreeBase::
  // readBinaryNode: code 01 a free leaf at the clamping minimum, 10 an occupied leaf at the
  // maximum, 11 a node read next that then takes its children's largest log-odds, which for a
  // node without children is OcTreeNode::getMaxChildLogOdds of none; a root without children
  // keeps the maximum), in its leaf iterator's order (depth first, children 0..7).
  std::vector<octree_detail::Leaf>* leaves = nullptr;
  float free_l = 0, occupied_l = 0, childless_l = 0;

  unsigned char byte() {
    if (pos >= b.size()) bad(path, "the tree data is truncated at byte " + std::to_string(pos));
    return static_cast<unsigned char>(b[pos++]);
  }
  void binary_node(int depth, const std::uint16_t lo[3]) {
    if (depth >= kTreeDepth) bad(path, "the tree is deeper than " + std::to_string(kTreeDepth) + " levels");
    const unsigned bits = byte() | (unsigned(byte()) << 8);
    const std::uint16_t half = static_cast<std::uint16_t>(1u << (kTreeDepth - depth - 1));
    if (bits == 0 && leaves)
      leaves->push_back({{lo[0], lo[1], lo[2]}, std::uint8_t(kTreeDepth - depth), depth == 0 ? occupied_l : childless_l});
    for (unsigned i = 0; i < 8; ++i) {
      // liboctomap's bit order: of child i's two bits, bit 2i set alone is a free leaf, 2i + 1
      // alone an occupied one.
      const unsigned code = (bits >> (2 * i)) & 3u;
      if (!code) continue;
      ++nodes;
      const std::uint16_t child[3] = {static_cast<std::uint16_t>(lo[0] + ((i & 1) ? half : 0)),
                                      static_cast<std::uint16_t>(lo[1] + ((i & 2) ? half : 0)),
                                      static_cast<std::uint16_t>(lo[2] + ((i & 4) ? half : 0))};
      if (code == 3) binary_node(depth + 1, child);
      else if (leaves)
        leaves->push_back({{child[0], child[1], child[2]}, std::uint8_t(kTreeDepth - depth - 1),
                           code == 1 ? free_l : occupied_l});
    }
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

// The tree from the checked tree bytes alone: liboctomap never sees the header (its own header
// parser is what the check above mirrors), so it reads exactly the bytes the walk accounted for.
// Constructing the tree at the header's resolution and reading its data is what
// AbstractOcTree::read (.ot: createTree, readData) and readBinary (.bt: readBinaryData) do after
// their header.
template <typename Tree>
Grid read_tree(std::string_view body, const Header& h, const std::string& path, const OctreeOptions& o) {
  Tree tree(h.res);
  BytesBuf buf(body);  // the checked bytes themselves, not a copy
  std::istream in(&buf);
  if (h.size > 0) {
    if (h.binary) tree.readBinaryData(in);
    else tree.readData(in);
  }
  if (in.fail() || tree.size() != h.size)
    bad(path, "OctoMap read " + std::to_string(tree.size()) + " nodes of the " + std::to_string(h.size) + " checked");
  report_progress(o.progress, 0.3);
  OctreeOptions rest = o;  // the conversion reports the rest of the bar
  if (o.progress) rest.progress = [&o](double f) { return o.progress(0.3 + 0.7 * f); };
  return grid_from_octree(tree, rest);
}

}  // namespace

Grid read_octree_file(const std::string& path, const OctreeOptions& options) {
  options.validate();
  const std::string bytes = slurp(path);
  report_progress(options.progress, 0.1);
  const Header h = parse_header(bytes, path);
  Walker w{bytes, path, h.data};
  if (h.binary) {
    if (h.id != "OcTree")
      throw Error(Status::unsupported, "'" + path + "': binary tree type '" + printable(h.id) + "' is not supported");
    // The leaves come from the walk itself: the tree liboctomap would build from these bytes is
    // never built (most of its reading time is allocating and freeing nodes).
    const octomap::OcTree defaults(h.res);
    w.free_l = defaults.getClampingThresMinLog();
    w.occupied_l = defaults.getClampingThresMaxLog();
    w.childless_l = octomap::OcTreeNode().getMaxChildLogOdds();
    std::vector<octree_detail::Leaf> leaves;
    leaves.reserve(std::min<std::size_t>(h.size, (bytes.size() - h.data) * 4 + 1));
    w.leaves = &leaves;
    if (h.size > 0) {
      w.nodes = 1;
      const std::uint16_t zero[3] = {0, 0, 0};
      w.binary_node(0, zero);
    }
    if (w.nodes != h.size)
      bad(path, "the header promises " + std::to_string(h.size) + " nodes, the data holds " + std::to_string(w.nodes));
    report_progress(options.progress, 0.3);
    OctreeOptions rest = options;
    if (options.progress) rest.progress = [&options](double f) { return options.progress(0.3 + 0.7 * f); };
    try {
      return octree_detail::grid_from_leaves(leaves, h.res, kTreeDepth, rest);
    } catch (const Error& e) {
      if (e.status() == Status::format) throw;
      throw Error(e.status(), "'" + path + "': " + e.what());
    }
  } else {
    // OcTreeNode::readData reads the float log-odds alone; ColorOcTreeNode adds r, g, b. An
    // OcTreeStamped node is written and read as a plain OcTreeNode (its time stamp is not saved).
    if (h.id == "OcTree" || h.id == "OcTreeStamped") w.payload = 4;
    else if (h.id == "ColorOcTree") w.payload = 7;
    else throw Error(Status::unsupported, "'" + path + "': tree type '" + printable(h.id) +
                                              "' is not supported (OcTree, ColorOcTree, OcTreeStamped)");
    if (h.size > 0) w.full_node(0);
  }
  if (w.nodes != h.size)
    bad(path, "the header promises " + std::to_string(h.size) + " nodes, the data holds " + std::to_string(w.nodes));
  const std::string_view body = std::string_view(bytes).substr(h.data, w.pos - h.data);
  try {
    if (h.binary || h.id == "OcTree") return read_tree<octomap::OcTree>(body, h, path, options);
    if (h.id == "ColorOcTree") return read_tree<octomap::ColorOcTree>(body, h, path, options);
    return read_tree<octomap::OcTreeStamped>(body, h, path, options);
  } catch (const Error& e) {
    if (e.status() == Status::format) throw;
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
}

}  // namespace occseg
