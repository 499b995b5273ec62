#include "occseg/segments_json.hpp"

#include <array>
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

// The frame (voxel size, origin) is the result's own (segment() records the map's); `frame`
// adds the oriented boxes.
void write_segments_json(std::ostream& out, const Result& r, const std::string& preset, const SegmentsFrame& frame) {
  char head[256];
  char* h = head;
  const char* const head_end = head + sizeof head;
  h += std::snprintf(h, static_cast<std::size_t>(head_end - h), "{\n \"dims\": [%zu, %zu, %zu],\n \"voxel_size\": ",
                     r.dims.nx, r.dims.ny, r.dims.nz);
  number(h, head_end, r.voxel_size);
  h += std::snprintf(h, static_cast<std::size_t>(head_end - h), ",\n \"origin\": ");
  triple(h, head_end, r.origin);
  h += std::snprintf(h, static_cast<std::size_t>(head_end - h), ",\n \"preset\": ");
  out.write(head, h - head);
  json_string(out, preset);
  const std::vector<OrientedBox>* boxes =
      frame.boxes && frame.boxes->size() == r.segments.size() ? frame.boxes : nullptr;
  out << ",\n \"segments\": [";
  const char* sep = "\n";
  // One line of at most 28 numbers of <= 24 characters and a few fixed words: 2048 bytes suffice.
  char line[2048];
  const char* end = line + sizeof line;
  for (const Segment& s : r.segments) {
    char* p = line;
    p += std::snprintf(p, static_cast<std::size_t>(end - p),
                       "%s  {\"id\": %u, \"state\": \"%s\", \"kind\": \"%s\", \"voxels\": %llu, \"mop\": ", sep,
                       static_cast<unsigned>(s.id), state_name(s.state), kind_name(s.kind),
                       static_cast<unsigned long long>(s.voxels));
    number(p, end, s.mop);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"bbox\": {\"min\": ");
    triple(p, end, s.bbox_min);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"max\": ");
    triple(p, end, s.bbox_max);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), "}, \"centroid\": ");
    triple(p, end, s.centroid);
    // The same in metres in the map's frame: the box from the min corner of its first voxels to
    // the max corner of its last ones, its size, the centroid as the mean voxel centre.
    std::array<double, 3> lo, hi, size, c;
    for (int k = 0; k < 3; ++k) {
      lo[k] = r.origin[k] + r.voxel_size * s.bbox_min[k];
      hi[k] = r.origin[k] + r.voxel_size * (double(s.bbox_max[k]) + 1);
      size[k] = r.voxel_size * (double(s.bbox_max[k]) - s.bbox_min[k] + 1);
      c[k] = r.origin[k] + r.voxel_size * (s.centroid[k] + 0.5);
    }
    p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"box_m\": {\"min\": ");
    triple(p, end, lo);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"max\": ");
    triple(p, end, hi);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), "}, \"size_m\": ");
    triple(p, end, size);
    p += std::snprintf(p, static_cast<std::size_t>(end - p), ", \"centroid_m\": ");
    triple(p, end, c);
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
