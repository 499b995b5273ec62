// segments.ply: the surfaces of the occupied segments as a mesh (the voxels' outer faces), in
// metres, written as binary PLY with a colour per vertex and a segment id per face.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "occseg/file_write.hpp"
#include "occseg/grid.hpp"
#include "occseg/result.hpp"
#include "occseg/segment_colour.hpp"

namespace occseg {

// One quad per voxel face that bounds its occupied segment: a face whose neighbour across it is
// outside the map or in another segment (so each segment's surface is closed; where two
// segments touch, each has its own face there, facing its own way). Faces between two voxels of
// one segment are left out; coplanar faces are not merged. Vertices are shared within a segment
// and never between segments (each carries its segment's colour). Corners are counter-clockwise
// seen from outside (normals point out of the segment). Deterministic: faces in voxel order
// (x fastest), then -x, +x, -y, +y, -z, +z; vertices in order of first use.
struct VoxelMesh {
  std::vector<std::array<float, 3>> positions;  // metres: origin + lattice point * voxel size
  std::vector<Rgb> colours;           // per vertex: segment_colour(segment)
  std::vector<std::array<std::uint32_t, 4>> quads;
  std::vector<std::uint32_t> face_segment;      // per quad: the segment id
};

// Throws Error(bad_dims) when the mesh would have 2^31 vertices or more (PLY's int indices).
VoxelMesh occupied_surface(const Result& result, double voxel_size, const std::array<double, 3>& origin);

// Writes `mesh` as binary little-endian PLY: element vertex (float x, y, z; uchar red, green,
// blue), element face (list uchar int vertex_indices; uint segment). Throws Error(io) from
// writing; `into`: as write_file_atomically.
void write_mesh_ply(const std::string& path, const VoxelMesh& mesh, StagedFiles* into = nullptr);

// occupied_surface + write_mesh_ply.
void write_segments_ply(const std::string& path, const Result& result, double voxel_size,
                        const std::array<double, 3>& origin, StagedFiles* into = nullptr);

}  // namespace occseg
