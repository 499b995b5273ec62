#include "occseg/segments_json.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "occseg/params.hpp"

namespace occseg {

namespace {

// Appends the shortest text that reads back as the same double (JSON has no NaN: null).
void number(char*& p, const char* end, double v) {
  if (!std::isfinite(v)) {
    p += std::snprintf(p, static_cast<std::size_t>(end - p), "null");
    return;
  }
  char t[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(t, sizeof t, "%.*g", digits, v);
    if (std::strtod(t, nullptr) == v) break;
  }
  p += std::snprintf(p, static_cast<std::size_t>(end - p), "%s", t);
}

template <class A>
void triple(char*& p, const char* end, const A& a, int count = 3) {
  *p++ = '[';
  for (int i = 0; i < count; ++i) {
    if (i) {
      *p++ = ',';
      *p++ = ' ';
    }
    number(p, end, static_cast<double>(a[i]));
  }
  *p++ = ']';
}

void json_string(std::ostream& out, const std::string& s) {
  out << '"';
  for (const char c : s) {
    if (c == '"' || c == '\\') out << '\\' << c;
    else if (static_cast<unsigned char>(c) < 0x20) {
      char e[8];
      std::snprintf(e, sizeof e, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out << e;
    } else {
      out << c;
    }
  }
  out << '"';
}

}  // namespace

void write_segments_json(std::ostream& out, const Result& r, const std::string& preset) {
  write_segments_json(out, r, preset, SegmentsFrame{});
}

void write_segments_json(std::ostream& out, const Result& r, const std::string& preset, const SegmentsFrame& frame) {
  out << "{\n \"dims\": [" << r.dims.nx << ", " << r.dims.ny << ", " << r.dims.nz << "],\n \"preset\": ";
  json_string(out, preset);
  const std::vector<OrientedBox>* boxes =
      frame.boxes && frame.boxes->size() == r.segments.size() ? frame.boxes : nullptr;
  if (boxes) {
    char head[160];
    char* p = head;
    p += std::snprintf(p, sizeof head, ",\n \"voxel_size\": ");
    number(p, head + sizeof head, frame.voxel_size);
    p += std::snprintf(p, static_cast<std::size_t>(head + sizeof head - p), ",\n \"origin\": ");
    triple(p, head + sizeof head, frame.origin);
    out.write(head, p - head);
  }
  out << ",\n \"segments\": [";
  const char* sep = "\n";
  // One line of at most 16 numbers of <= 24 characters and a few fixed words: 1024 bytes suffice.
  char line[1024];
  const char* end = line + sizeof line;
  for (const Segment& s : r.segments) {
    char* p = line;
    p += std::snprintf(p, static_cast<std::size_t>(end - p),
                       "%s  {\"id\": %u, \"state\": \"%s\", \"voxels\": %llu, \"mop\": ", sep,
                       static_cast<unsigned>(s.id), state_name(s.state), static_cast<unsigned long long>(s.voxels));
    number(p, end, s.mop);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"bbox\": {\"min\": ");
    triple(p, end, s.bbox_min);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"max\": ");
    triple(p, end, s.bbox_max);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), "}, \"centroid\": ");
    triple(p, end, s.centroid);
    if (boxes) {
      const OrientedBox& b = (*boxes)[static_cast<std::size_t>(&s - r.segments.data())];
      p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"obb\": {\"center\": ");
      triple(p, end, b.center);
      p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"extents\": ");
      triple(p, end, b.extents);
      p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"quaternion\": ");
      triple(p, end, b.quaternion, 4);
      *p++ = '}';
    }
    *p++ = '}';
    out.write(line, p - line);
    sep = ",\n";
  }
  out << "\n ]\n}\n";
}

}  // namespace occseg
