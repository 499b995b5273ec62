// segments.ply (voxel_mesh.hpp). The PLY is written here rather than through a library, as none
// in Debian 12 writes a per-face property: PCL's savePLYFileBinary takes a pcl::PolygonMesh,
// whose faces are vertex index lists only; VTK's vtkPLYWriter writes point and cell colours,
// normals and texture coordinates, no other arrays; VTK's low-level vtkPLY (Greg Turk's library,
// which can describe any property) allocates from one process-wide heap that every ply_close
// frees (and deletes the stream it was handed), so two threads writing at once would free each
// other's memory; assimp's faces (aiFace) hold vertex indices only; tinyply and happly are not
// packaged. The format itself is a text header and fixed little-endian records; the tests read
// the files back with PCL's PLY readers.
#include "occseg/voxel_mesh.hpp"

#include <cstring>
#include <unordered_map>

#include "occseg/error.hpp"

namespace occseg {

namespace {

struct Corner {
  std::uint64_t point;  // lattice point index, x fastest over (nx + 1) x (ny + 1) x (nz + 1)
  std::uint32_t segment;
  bool operator==(const Corner& o) const { return point == o.point && segment == o.segment; }
};
struct CornerHash {
  std::size_t operator()(const Corner& c) const {
    return std::hash<std::uint64_t>()(c.point * 0x9E3779B97F4A7C15ull ^ c.segment);
  }
};

// The four corners of each face, as lattice offsets from the voxel's (x, y, z), counter-clockwise
// seen from outside; faces in the order -x, +x, -y, +y, -z, +z.
constexpr int kFace[6][4][3] = {
    {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}},
    {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}},
    {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}};

template <class T>
void put_le(std::string& out, T v) {
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the PLY body is written in host order");
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof v);
  out.append(b, sizeof b);
}

}  // namespace

VoxelMesh occupied_surface(const Result& r, double voxel_size, const std::array<double, 3>& origin) {
  VoxelMesh m;
  const Dims& d = r.dims;
  const std::uint64_t px = d.nx + 1, py = d.ny + 1;
  std::unordered_map<Corner, std::uint32_t, CornerHash> index;
  auto occupied = [&](std::uint32_t l) { return l < r.segments.size() && r.segments[l].state == State::occupied; };
  std::size_t i = 0;
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t y = 0; y < d.ny; ++y)
      for (std::size_t x = 0; x < d.nx; ++x, ++i) {
        const std::uint32_t l = r.labels[i];
        if (!occupied(l)) continue;
        const bool open[6] = {x == 0 || r.labels[i - 1] != l,
                              x + 1 == d.nx || r.labels[i + 1] != l,
                              y == 0 || r.labels[i - d.nx] != l,
                              y + 1 == d.ny || r.labels[i + d.nx] != l,
                              z == 0 || r.labels[i - d.nx * d.ny] != l,
                              z + 1 == d.nz || r.labels[i + d.nx * d.ny] != l};
        for (int f = 0; f < 6; ++f) {
          if (!open[f]) continue;
          std::array<std::uint32_t, 4> q{};
          for (int c = 0; c < 4; ++c) {
            const std::uint64_t cx = x + kFace[f][c][0], cy = y + kFace[f][c][1], cz = z + kFace[f][c][2];
            const Corner key{cx + px * (cy + py * cz), l};
            auto it = index.find(key);
            if (it == index.end()) {
              if (m.positions.size() >= 0x7fffffffu)
                throw Error(Status::bad_dims, "the surface mesh needs 2^31 vertices or more, beyond PLY's int indices");
              it = index.emplace(key, static_cast<std::uint32_t>(m.positions.size())).first;
              m.positions.push_back({static_cast<float>(origin[0] + double(cx) * voxel_size),
                                     static_cast<float>(origin[1] + double(cy) * voxel_size),
                                     static_cast<float>(origin[2] + double(cz) * voxel_size)});
              m.colours.push_back(segment_colour(l));
            }
            q[c] = it->second;
          }
          m.quads.push_back(q);
          m.face_segment.push_back(l);
        }
      }
  return m;
}

void write_mesh_ply(const std::string& path, const VoxelMesh& m, StagedFiles* into) {
  write_file_atomically(
      path,
      [&](std::ostream& os) {
        os << "ply\nformat binary_little_endian 1.0\n"
              "comment occseg segments.ply: surfaces of the occupied segments, metres; colour and segment id per segment\n"
              "element vertex "
           << m.positions.size()
           << "\nproperty float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\n"
              "element face "
           << m.quads.size() << "\nproperty list uchar int vertex_indices\nproperty uint segment\nend_header\n";
        std::string buf;
        buf.reserve(1 << 16);
        for (std::size_t v = 0; v < m.positions.size(); ++v) {
          for (const float c : m.positions[v]) put_le(buf, c);
          buf += static_cast<char>(m.colours[v].r);
          buf += static_cast<char>(m.colours[v].g);
          buf += static_cast<char>(m.colours[v].b);
          if (buf.size() >= (1 << 16) - 64) {
            os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
            buf.clear();
          }
        }
        for (std::size_t f = 0; f < m.quads.size(); ++f) {
          buf += static_cast<char>(4);
          for (const std::uint32_t v : m.quads[f]) put_le(buf, static_cast<std::int32_t>(v));
          put_le(buf, m.face_segment[f]);
          if (buf.size() >= (1 << 16) - 64) {
            os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
            buf.clear();
          }
        }
        os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
      },
      into);
}

void write_segments_ply(const std::string& path, const Result& r, double voxel_size,
                        const std::array<double, 3>& origin, StagedFiles* into) {
  write_mesh_ply(path, occupied_surface(r, voxel_size, origin), into);
}

}  // namespace occseg
