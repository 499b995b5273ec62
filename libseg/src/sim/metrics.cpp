// Scores of a segmentation against a simulated scene's ground truth (metrics.hpp).
#include "occseg/sim/metrics.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <string>

#include "occseg/error.hpp"

namespace occseg::sim {

std::vector<std::uint16_t> attribute_to_objects(const Dims& dims, const std::vector<std::uint16_t>& objects, int reach) {
  const std::size_t n = dims.count();
  if (objects.size() != n) throw Error(Status::bad_dims, "object mask size does not match the dims");
  std::vector<std::uint16_t> owner(objects);
  std::vector<std::size_t> frontier, next;
  for (std::size_t i = 0; i < n; ++i)
    if (owner[i]) frontier.push_back(i);
  const std::size_t nx = dims.nx, ny = dims.ny, nz = dims.nz, sxy = nx * ny;
  for (int step = 0; step < reach && !frontier.empty(); ++step) {
    next.clear();
    for (std::size_t i : frontier) {
      const std::size_t x = i % nx, y = (i / nx) % ny, z = i / sxy;
      auto visit = [&](std::size_t j) {
        if (!owner[j]) {
          owner[j] = owner[i];
          next.push_back(j);
        }
      };
      if (x > 0) visit(i - 1);
      if (x + 1 < nx) visit(i + 1);
      if (y > 0) visit(i - nx);
      if (y + 1 < ny) visit(i + nx);
      if (z > 0) visit(i - sxy);
      if (z + 1 < nz) visit(i + sxy);
    }
    // Keep voxel order within a level so ties resolve the same way every run.
    std::sort(next.begin(), next.end());
    frontier.swap(next);
  }
  return owner;
}

Scores score_segmentation(const Truth& truth, const LabelArray& labels,
                          const std::vector<State>& segment_states, int reach) {
  const std::size_t n = truth.dims.count();
  if (truth.state.size() != n || truth.objects.size() != n)
    throw Error(Status::bad_dims, "ground truth arrays do not match its dims");
  if (labels.size() != n)
    throw Error(Status::bad_dims, "labels hold " + std::to_string(labels.size()) + " voxels, the ground truth " +
                                      std::to_string(n));
  Scores s;
  s.voxels = n;
  s.segments = static_cast<std::uint32_t>(segment_states.size());
  for (State st : segment_states) ++s.segments_by_state[static_cast<int>(st)];
  std::uint16_t max_id = 0;
  for (std::uint16_t o : truth.objects) max_id = std::max(max_id, o);
  s.objects.resize(max_id);
  for (std::uint16_t k = 0; k < max_id; ++k) s.objects[k].id = static_cast<std::uint16_t>(k + 1);

  const std::vector<std::uint16_t> owner = attribute_to_objects(truth.dims, truth.objects, reach);
  std::array<std::uint64_t, 3> both{};
  std::uint64_t correct = 0;
  std::vector<std::set<std::uint16_t>> seg_objects(segment_states.size());
  // Occupied-labelled voxels per (object, segment), for the largest-segment share.
  std::vector<std::map<std::uint32_t, std::uint64_t>> per_object(max_id);
  const std::size_t nx = truth.dims.nx, sxy = nx * truth.dims.ny;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t l = labels[i];
    if (l >= segment_states.size())
      throw Error(Status::out_of_range, "voxel (" + std::to_string(i % nx) + ", " + std::to_string((i / nx) % truth.dims.ny) +
                                            ", " + std::to_string(i / sxy) + ") has label " + std::to_string(l) +
                                            " but there are " + std::to_string(segment_states.size()) + " segments");
    const int pred = static_cast<int>(segment_states[l]);
    const int ideal = truth.state[i];
    if (ideal > 2) throw Error(Status::bad_value, "ground truth state " + std::to_string(ideal) + " is not 0, 1 or 2");
    ++s.truth_voxels[ideal];
    ++s.labelled_voxels[pred];
    if (pred == ideal) {
      ++correct;
      ++both[ideal];
    }
    const bool labelled_free = pred == static_cast<int>(State::free);
    if (ideal == static_cast<int>(State::unknown)) {
      ++s.unknown_voxels;
      s.unknown_free += labelled_free;
    }
    if (const std::uint16_t o = truth.objects[i]) {
      ++s.object_voxels;
      s.object_free += labelled_free;
      ++s.objects[o - 1].voxels;
      s.objects[o - 1].labelled_free += labelled_free;
    }
    if (ideal == static_cast<int>(State::occupied) && owner[i]) {
      ++s.objects[owner[i] - 1].surface;
      s.objects[owner[i] - 1].surface_found += pred == static_cast<int>(State::occupied);
    }
    if (pred == static_cast<int>(State::occupied) && owner[i]) {
      seg_objects[l].insert(owner[i]);
      ++per_object[owner[i] - 1][l];
    }
  }
  s.accuracy = n ? double(correct) / double(n) : 1.0;
  for (int k = 0; k < 3; ++k) {
    const std::uint64_t uni = s.truth_voxels[k] + s.labelled_voxels[k] - both[k];
    s.iou[k] = uni ? double(both[k]) / double(uni) : 1.0;
  }
  s.object_free_share = s.object_voxels ? double(s.object_free) / double(s.object_voxels) : 0.0;
  s.unknown_free_share = s.unknown_voxels ? double(s.unknown_free) / double(s.unknown_voxels) : 0.0;
  for (std::size_t l = 0; l < segment_states.size(); ++l) {
    if (segment_states[l] != State::occupied) continue;
    if (seg_objects[l].size() >= 2) ++s.spanning_segments;
    if (seg_objects[l].empty()) ++s.stray_segments;
    for (std::uint16_t o : seg_objects[l]) ++s.objects[o - 1].segments;
  }
  for (std::size_t k = 0; k < per_object.size(); ++k) {
    std::uint64_t total = 0, largest = 0;
    for (const auto& e : per_object[k]) {
      total += e.second;
      largest = std::max(largest, e.second);
    }
    s.objects[k].largest_share = total ? double(largest) / double(total) : 0.0;
  }
  return s;
}

}  // namespace occseg::sim
