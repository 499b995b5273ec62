// OctoMap .bt/.ot headers, differentially: occseg's header parser (adapters/octomap/
// octree_header.hpp) against liboctomap's own AbstractOcTree::readHeader on the same bytes. They
// must agree on acceptance, id, size, resolution and the offset where the tree data starts: a
// header that the two read differently lets liboctomap parse bytes occseg never checked (issue
// 24). Then the whole reader runs on the input, in the box of fuzz_octree.cpp.
#include <octomap/AbstractOcTree.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <locale>
#include <sstream>

#include "fuzz_common.hpp"
#include "occseg/octomap_file.hpp"
#include "octree_header.hpp"

namespace {

// readHeader is a protected static member: reachable from a derived class (never instantiated).
struct OctomapHeader : octomap::AbstractOcTree {
  static bool read(std::istream& s, std::string& id, unsigned& size, double& res) {
    return readHeader(s, id, size, res);
  }
};

// liboctomap warns on std::cerr for every unknown header word; the fuzzer does not need them.
struct QuietCerr {
  std::streambuf* saved = std::cerr.rdbuf(nullptr);
  ~QuietCerr() {
    std::cerr.rdbuf(saved);
    std::cerr.clear();
  }
};

void compare_headers(const std::string& bytes) {
  using namespace occseg::octree_detail;
  const RawHeader mine = parse_raw_header(bytes);
  std::istringstream s(bytes);
  s.imbue(std::locale::classic());
  std::string line;
  std::getline(s, line);
  const bool first = line.compare(0, kBinaryHeader.size(), kBinaryHeader) == 0 ||
                     line.compare(0, kFullHeader.size(), kFullHeader) == 0;
  if (first != mine.first_line) std::abort();
  if (!first) return;
  std::string id;
  unsigned size = 0;
  double res = 0;
  bool ok;
  {
    QuietCerr quiet;
    ok = OctomapHeader::read(s, id, size, res);
  }
  if (ok != mine.complete) std::abort();
  if (!ok) return;
  const std::streampos at = s.tellg();
  const std::size_t data = at < 0 ? bytes.size() : static_cast<std::size_t>(at);
  if (id != mine.id || size != mine.size || std::memcmp(&res, &mine.res, sizeof res) != 0 || data != mine.data)
    std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  compare_headers(bytes);
  const occseg::octree_detail::RawHeader h = occseg::octree_detail::parse_raw_header(bytes);
  const double res = h.complete && h.res > 0 && std::isfinite(h.res) ? h.res : 1;
  const std::string path = occseg::fuzz::as_file(data, size);
  occseg::OctreeOptions o;
  o.bbox = occseg::Box{{-8 * res, -8 * res, -8 * res}, {8 * res, 8 * res, 8 * res}};
  try {
    const occseg::Grid g = occseg::read_octree_file(path, o);
    if (g.dims.count() > 17 * 17 * 17) std::abort();
    occseg::check_probabilities(g);
  } catch (const occseg::Error& e) {
    occseg::fuzz::check_error(e);
  }
  return 0;
}
