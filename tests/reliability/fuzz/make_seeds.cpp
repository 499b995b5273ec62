// Writes small seed inputs that the repository does not hold as files: OctoMap trees (.bt, and
// .ot of all three tree types) and a scan graph written by OctoMap itself, .pcd files in all
// three encodings, and C-ABI buffers. The real files of shared/data are seeds too (by path).
// Usage: occseg_make_seeds OUT_DIR  (creates OUT_DIR/{bt,ot,graph,pcd,buffer}/).
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>
#include <octomap/ScanGraph.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

// A few occupied and free voxels around the origin, with graded log-odds.
template <typename Tree>
void fill(Tree& t) {
  for (int i = -6; i <= 6; ++i)
    for (int j = -3; j <= 3; ++j) {
      t.updateNode(octomap::point3d(0.1f * i, 0.1f * j, 0.05f), i % 2 == 0);
      if (j == 0) t.updateNode(octomap::point3d(0.1f * i, 0.3f, 0.1f * j + 0.2f), float(0.3 * i));
    }
  t.updateInnerOccupancy();
}

void write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// PCD with fields x y z (float) and one uint8 field; points on a small wall in front of the sensor.
std::string pcd(const std::string& encoding) {
  std::vector<float> xyz;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 4; ++j) {
      xyz.push_back(0.2f * i - 0.5f);
      xyz.push_back(0.2f * j - 0.3f);
      xyz.push_back(1.5f);
    }
  xyz[3 * 5] = NAN;  // a hole, as in organized clouds
  const std::size_t n = xyz.size() / 3;
  std::ostringstream h;
  h << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z i\nSIZE 4 4 4 1\nTYPE F F F U\n"
    << "COUNT 1 1 1 1\nWIDTH 6\nHEIGHT 4\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << n << "\nDATA " << encoding << "\n";
  std::string s = h.str();
  if (encoding == "ascii") {
    std::ostringstream d;
    for (std::size_t i = 0; i < n; ++i) d << xyz[3 * i] << " " << xyz[3 * i + 1] << " " << xyz[3 * i + 2] << " " << i << "\n";
    return s + d.str();
  }
  std::string body;
  if (encoding == "binary") {
    for (std::size_t i = 0; i < n; ++i) {
      body.append(reinterpret_cast<const char*>(&xyz[3 * i]), 12);
      body.push_back(static_cast<char>(i));
    }
    return s + body;
  }
  // binary_compressed: fields one after another, then LZF; literal runs only (control byte
  // c < 32: c + 1 literal bytes follow) are a valid LZF stream.
  for (int f = 0; f < 3; ++f)
    for (std::size_t i = 0; i < n; ++i) body.append(reinterpret_cast<const char*>(&xyz[3 * i + f]), 4);
  for (std::size_t i = 0; i < n; ++i) body.push_back(static_cast<char>(i));
  std::string lzf;
  for (std::size_t i = 0; i < body.size(); i += 32) {
    const std::size_t len = std::min<std::size_t>(32, body.size() - i);
    lzf.push_back(static_cast<char>(len - 1));
    lzf.append(body, i, len);
  }
  const std::uint32_t sizes[2] = {static_cast<std::uint32_t>(lzf.size()), static_cast<std::uint32_t>(body.size())};
  return s + std::string(reinterpret_cast<const char*>(sizes), 8) + lzf;
}

// An input of fuzz_buffer.cpp: dtype, dims, flags, stride mode, preset, strides, then values.
std::string buffer(std::uint8_t dtype, std::uint8_t n, std::uint8_t mode) {
  std::string s{char(dtype), char(n), char(n), char(n), 0, char(mode), 0, 0, 0, 0};
  for (int i = 0; i < n * n * n; ++i) {
    const bool inside = i % n > 1 && i % n < n - 1 && (i / n) % n > 1 && (i / n) % n < n - 1;
    const float p = inside ? 0.9f : 0.1f;
    if (dtype == 0) s.append(reinterpret_cast<const char*>(&p), 4);
    else s.push_back(static_cast<char>(static_cast<std::uint8_t>(p * 255)));
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const fs::path out(argv[1]);
  for (const char* d : {"bt", "ot", "graph", "pcd", "buffer"}) fs::create_directories(out / d);

  octomap::OcTree tree(0.1);
  fill(tree);
  tree.writeBinary((out / "bt" / "small.bt").string());
  tree.write((out / "ot" / "small_octree.ot").string());
  tree.writeBinary((out / "ot" / "small.bt").string());  // the .ot target also sees .bt files
  octomap::ColorOcTree color(0.1);
  fill(color);
  color.write((out / "ot" / "small_color.ot").string());
  octomap::OcTreeStamped stamped(0.1);
  fill(stamped);
  stamped.write((out / "ot" / "small_stamped.ot").string());

  octomap::ScanGraph graph;
  for (int node = 0; node < 2; ++node) {
    auto* scan = new octomap::Pointcloud();
    for (int i = 0; i < 12; ++i) scan->push_back(1.0f, 0.1f * i - 0.6f, 0.05f * node);
    graph.addNode(scan, octomath::Pose6D(0.1 * node, 0, 0, 0, 0, 0.2 * node));
  }
  graph.addEdge(0, 1);
  graph.writeBinary((out / "graph" / "small.graph").string());

  for (const char* e : {"ascii", "binary", "binary_compressed"}) write_bytes(out / "pcd" / (std::string(e) + ".pcd"), pcd(e));
  write_bytes(out / "buffer" / "f32_dense_8.bin", buffer(0, 8, 0));
  write_bytes(out / "buffer" / "u8_fortran_6.bin", buffer(2, 6, 1));
  write_bytes(out / "buffer" / "f32_flipped_5.bin", buffer(0, 5, 2));
  return 0;
}
