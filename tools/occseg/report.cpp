#include "report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>

#include "format.hpp"
#include "render_png.hpp"
#include "render_scene.hpp"

namespace occseg::cli {

namespace {

using nlohmann::json;

// Decimals that show the voxel size and the origin exactly (0.04 m: 2), at most 6.
int metric_digits(const Grid& g) {
  int digits = 0;
  auto need = [](double v) {
    for (int d = 0; d < 6; ++d) {
      const double s = v * std::pow(10.0, d);
      if (std::fabs(s - std::round(s)) < 1e-6 * std::max(1.0, std::fabs(s))) return d;
    }
    return 6;
  };
  digits = std::max(digits, need(g.voxel_size));
  for (double o : g.origin) digits = std::max(digits, need(o));
  return digits;
}

std::string triple(const std::array<double, 3>& v, int digits, const char* sep = ", ") {
  return fixed(v[0], digits) + sep + fixed(v[1], digits) + sep + fixed(v[2], digits);
}

std::string seconds(double s) { return fixed(s, s < 10 ? 2 : 1) + " s"; }

double total_time(const RunReport& run) {
  double t = 0;
  for (const StageTime& s : run.steps) t += s.seconds;
  return t;
}

}  // namespace

MetricBox metric_box(const Grid& g, const Segment& s) {
  MetricBox b;
  for (int k = 0; k < 3; ++k) {
    b.min[k] = g.origin[k] + double(s.bbox_min[k]) * g.voxel_size;
    b.max[k] = g.origin[k] + double(s.bbox_max[k] + 1) * g.voxel_size;
  }
  return b;
}

// Occupied segments for the summary: objects first, then structure, then clutter, each by size
// (largest first; equal sizes by id).
std::vector<const Segment*> largest_objects(const Result& r, std::size_t top) {
  std::vector<const Segment*> occ;
  for (const Segment& s : r.segments)
    if (s.state == State::occupied) occ.push_back(&s);
  const std::size_t n = std::min(top, occ.size());
  const auto rank = [](Kind k) { return k == Kind::object ? 0 : k == Kind::structure ? 1 : 2; };
  std::partial_sort(occ.begin(), occ.begin() + static_cast<std::ptrdiff_t>(n), occ.end(),
                    [&](const Segment* a, const Segment* b) {
                      if (rank(a->kind) != rank(b->kind)) return rank(a->kind) < rank(b->kind);
                      return a->voxels != b->voxels ? a->voxels > b->voxels : a->id < b->id;
                    });
  occ.resize(n);
  return occ;
}

std::array<std::uint64_t, 5> segments_per_kind(const Result& r) {
  std::array<std::uint64_t, 5> k{};
  for (const Segment& s : r.segments) ++k[static_cast<int>(s.kind)];
  return k;
}

std::array<std::uint64_t, 3> voxels_per_state(const Result& r) {
  std::array<std::uint64_t, 3> v{};
  for (const Segment& s : r.segments) v[static_cast<int>(s.state)] += s.voxels;
  return v;
}

void print_summary(std::ostream& out, const RunReport& run) {
  const Grid& g = *run.grid;
  const Result& r = *run.result;
  const int md = metric_digits(g);
  const Dims& d = g.dims;
  std::array<std::uint64_t, 3> segs{};
  for (const Segment& s : r.segments) ++segs[static_cast<int>(s.state)];
  const std::array<std::uint64_t, 5> kinds = segments_per_kind(r);
  const std::array<std::uint64_t, 3> vox = voxels_per_state(r);
  const double n = double(d.count());
  out << run.input << ": " << run.format << ", " << d.nx << " x " << d.ny << " x " << d.nz << " voxels of "
      << fixed(g.voxel_size, md) << " m, origin (" << triple(g.origin, md) << ") m\n";
  out << "preset " << run.preset << ": " << r.segments.size() << " segments: " << segs[0] << " free, " << segs[1]
      << " unknown, " << segs[2] << " occupied (" << kinds[3] << " objects, " << kinds[2] << " structure, "
      << kinds[4] << " clutter)\n";
  out << "voxels: " << fixed(100 * vox[0] / n, 2) << " % free, " << fixed(100 * vox[1] / n, 2) << " % unknown, "
      << fixed(100 * vox[2] / n, 2) << " % occupied\n";
  const std::vector<const Segment*> top = largest_objects(r, run.top);
  if (run.top == 0) {
    // --top 0: no table
  } else if (top.empty()) {
    out << "no occupied segment\n";
  } else {
    out << "largest objects (occupied segments, objects first, by size; boxes in metres, min to max corner):\n";
    std::vector<std::array<std::string, 7>> rows{{"id", "kind", "voxels", "mop", "box min", "box max", "size"}};
    for (const Segment* s : top) {
      const MetricBox b = metric_box(g, *s);
      const std::array<double, 3> size{b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]};
      rows.push_back({std::to_string(s->id), kind_name(s->kind), std::to_string(s->voxels), fixed(s->mop, 3),
                      "(" + triple(b.min, md) + ")", "(" + triple(b.max, md) + ")", triple(size, md, " x ")});
    }
    std::array<std::size_t, 7> w{};
    for (const auto& row : rows)
      for (std::size_t c = 0; c < 7; ++c) w[c] = std::max(w[c], row[c].size());
    for (const auto& row : rows) {
      out << "  ";
      for (std::size_t c = 0; c < 7; ++c) {
        if (c != 1 && c < 4) out << std::right << std::setw(int(w[c])) << row[c] << "  ";
        else out << std::left << std::setw(c == 6 ? 0 : int(w[c])) << row[c] << (c == 6 ? "" : "  ");
      }
      out << std::right << "\n";
    }
  }
  out << "time:";
  for (std::size_t k = 0; k < run.steps.size(); ++k)
    out << (k ? ", " : " ") << run.steps[k].stage << " " << seconds(run.steps[k].seconds);
  out << "; total " << seconds(total_time(run)) << "\n";
  if (!run.files.empty()) {
    out << "written:";
    for (const std::string& f : run.files) out << " " << f;
    out << "\n";
  }
  if (!run.removed.empty()) {
    out << "removed (an earlier run's, not written now):";
    for (const std::string& f : run.removed) out << " " << f;
    out << "\n";
  }
}

json summary_json(const RunReport& run) {
  const Grid& g = *run.grid;
  const Result& r = *run.result;
  std::array<std::uint64_t, 3> segs{};
  for (const Segment& s : r.segments) ++segs[static_cast<int>(s.state)];
  const std::array<std::uint64_t, 5> kinds = segments_per_kind(r);
  const std::array<std::uint64_t, 3> vox = voxels_per_state(r);
  json objects = json::array();
  for (const Segment* s : largest_objects(r, run.top)) {
    const MetricBox b = metric_box(g, *s);
    objects.push_back({{"id", s->id},
                       {"kind", kind_name(s->kind)},
                       {"voxels", s->voxels},
                       {"mop", s->mop},
                       {"bbox_voxels", {{"min", s->bbox_min}, {"max", s->bbox_max}}},
                       {"bbox_m", {{"min", b.min}, {"max", b.max}}},
                       {"size_m", {b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]}}});
  }
  json times = json::object();
  for (const StageTime& s : run.steps) times[s.stage] = s.seconds;
  times["total"] = total_time(run);
  return {{"input", run.input},
          {"format", run.format},
          {"dims", {g.dims.nx, g.dims.ny, g.dims.nz}},
          {"voxel_size", g.voxel_size},
          {"origin", g.origin},
          {"preset", run.preset},
          {"segments", {{"total", r.segments.size()}, {"free", segs[0]}, {"unknown", segs[1]}, {"occupied", segs[2]}}},
          {"kinds", {{"free", kinds[0]}, {"unknown", kinds[1]}, {"structure", kinds[2]}, {"object", kinds[3]},
                     {"clutter", kinds[4]}}},
          {"voxels", {{"free", vox[0]}, {"unknown", vox[1]}, {"occupied", vox[2]}}},
          {"largest_objects", objects},
          {"seconds", times},
          {"files", run.files},
          {"removed", run.removed}};
}

void write_segmentation_png(const std::string& path, const std::string& title, const Grid& grid, const Result& r,
                            const std::vector<std::uint8_t>* truth_states, StagedFiles* into, int threads) {
  const Dims& d = grid.dims;
  std::vector<render::Slice> slices;
  if (d.nz >= 4) {
    for (std::size_t k = 0; k < 4; ++k) slices.push_back({2, (2 * k + 1) * d.nz / 8});
  } else {
    for (std::size_t z = 0; z < d.nz; ++z) slices.push_back({2, z});
  }
  if (d.nz > 1) {
    std::size_t x = d.nx / 2, y = d.ny / 2;
    const std::vector<const Segment*> top = largest_objects(r, 1);
    if (!top.empty()) {
      x = std::min(d.nx - 1, static_cast<std::size_t>(std::lround(top[0]->centroid[0])));
      y = std::min(d.ny - 1, static_cast<std::size_t>(std::lround(top[0]->centroid[1])));
    }
    slices.push_back({1, y});
    slices.push_back({0, x});
    slices.push_back({render::kTopView, 0});  // a room's contents seen from above
  }
  // States through the labels (one per segment): the picture reads only the voxels it draws.
  std::vector<std::uint8_t> label_states(r.segments.size());
  for (std::size_t l = 0; l < label_states.size(); ++l) label_states[l] = static_cast<std::uint8_t>(r.segments[l].state);
  std::vector<render::Volume> rows;
  rows.push_back({"map", d, grid.p.data(), nullptr, nullptr, false});
  rows.push_back({"segments", d, nullptr, nullptr, r.labels.data(), true, label_states.data(), label_states.size()});
  if (truth_states) rows.push_back({"ideal state", d, nullptr, truth_states->data(), nullptr, false});
  render::FigureOptions o;
  o.title = title;
  const std::size_t m = std::max({d.nx, d.ny, d.nz});
  o.shrink = static_cast<int>((m + 639) / 640);                        // panels of at most 640 pixels
  o.scale = static_cast<int>(std::clamp<std::size_t>(256 / m, 1, 8));  // small maps magnified
  o.threads = threads;
  render::write_png(path, render::render_figure(rows, slices, o), into);
}

void write_scene_png(const std::string& path, const std::string& title, const Grid& grid, const Result& r,
                     StagedFiles* into) {
  render::SceneOptions o;
  o.title = title;
  render::write_png(path, render::render_scene(r, grid.voxel_size, o), into);
}

}  // namespace occseg::cli
