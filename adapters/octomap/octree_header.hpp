// The text header of .bt and .ot files, read exactly as liboctomap 1.9 reads it (internal to
// liboccseg_octomap and its fuzz target; not installed).
//
// liboctomap's AbstractOcTree::readHeader is not line based: it reads whitespace-separated
// words with `stream >> token` until the word "data", skipping the rest of the line after a word
// starting with '#' or an unknown word, reads the value after "id", "res" and "size" with
// `stream >> value` (which skips newlines too), and takes the tree data to start after the end
// of the line holding "data", even when "data" stands in the middle of a line. A checker that
// reads the header line by line finds a different "data" line than liboctomap, checks bytes
// liboctomap never reads and lets through bytes liboctomap reads as the tree (issue 24: a '#'
// line of 0xff bytes made liboctomap recurse until the stack overflowed). So the header is parsed
// here by the same stream operations, and liboctomap is then given only the tree bytes that were
// checked (never the header).
#pragma once
#include <istream>
#include <locale>
#include <sstream>
#include <string>

namespace occseg::octree_detail {

inline const std::string kBinaryHeader = "# Octomap OcTree binary file";  // AbstractOccupancyOcTree::binaryFileHeader
inline const std::string kFullHeader = "# Octomap OcTree file";           // AbstractOcTree::fileHeader

struct RawHeader {
  bool first_line = false;  // the first line starts with kBinaryHeader or kFullHeader
  bool binary = false;      // kBinaryHeader
  bool data_word = false;   // the word "data" ended the header
  bool complete = false;    // readHeader's checks passed: "data" seen, id not empty, res > 0
  std::string id;           // as readHeader leaves it (the deprecated "1" becomes "OcTree")
  unsigned size = 0;        // readHeader reads an unsigned (32 bits)
  double res = 0;
  std::size_t data = 0;     // offset of the first byte of tree data
};

// Skips to the character after the next '\n' (or to the end), as readHeader does.
inline void skip_line(std::istream& s) {
  char c;
  do {
    c = static_cast<char>(s.get());
  } while (s.good() && c != '\n');
}

// AbstractOcTree::readHeader of liboctomap 1.9.7 (src/AbstractOcTree.cpp), operation for
// operation, on a stream positioned after the first line. Returns its result; `data_word` tells
// whether the word "data" was found.
inline bool read_header_like_octomap(std::istream& s, std::string& id, unsigned& size, double& res,
                                     bool& data_word) {
  id = "";
  size = 0;
  res = 0.0;
  std::string token;
  bool header_read = false;
  while (s.good() && !header_read) {
    s >> token;  // on failure the previous word stays in `token`, as in liboctomap
    if (token == "data") {
      header_read = true;
      skip_line(s);
    } else if (token.compare(0, 1, "#") == 0) {
      skip_line(s);
    } else if (token == "id") {
      s >> id;
    } else if (token == "res") {
      s >> res;
    } else if (token == "size") {
      s >> size;
    } else {
      skip_line(s);
    }
  }
  data_word = header_read;
  if (!header_read || id.empty() || res <= 0.0) return false;
  if (id == "1") id = "OcTree";  // the deprecated id, mapped by readHeader itself
  return true;
}

// The header of a whole file held in `bytes`, as AbstractOcTree::read (.ot) and
// AbstractOccupancyOcTree::readBinary (.bt) see it: the first line by std::getline and a prefix
// compare, then readHeader. The classic locale makes the numbers independent of the host's
// global locale.
inline RawHeader parse_raw_header(const std::string& bytes) {
  RawHeader h;
  std::istringstream s(bytes);
  s.imbue(std::locale::classic());
  std::string line;
  std::getline(s, line);
  if (line.compare(0, kBinaryHeader.size(), kBinaryHeader) == 0) h.binary = true;
  else if (line.compare(0, kFullHeader.size(), kFullHeader) != 0) return h;
  h.first_line = true;
  h.complete = read_header_like_octomap(s, h.id, h.size, h.res, h.data_word);
  const std::streampos at = s.tellg();  // -1 once the stream has failed: the data is empty
  h.data = at < 0 ? bytes.size() : static_cast<std::size_t>(at);
  return h;
}

}  // namespace occseg::octree_detail
