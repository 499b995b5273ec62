#include "sim_io.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "format.hpp"
#include "occseg/error.hpp"
#include "occseg/file_read.hpp"
#include "occseg/file_write.hpp"
#include "occseg/npy.hpp"
#include "occseg/sim/baseline.hpp"
#include "stages/label.hpp"

namespace occseg::cli {

namespace {

using nlohmann::json;

json vec(const Vec3& v) { return json::array({v[0], v[1], v[2]}); }

json per_state(const std::array<std::uint64_t, 3>& a) {
  return {{"free", a[0]}, {"unknown", a[1]}, {"occupied", a[2]}};
}

// An integer volume [z, y, x] (C or Fortran order) widened to uint32, x fastest.
std::vector<std::uint32_t> read_integer_volume(const std::string& path, Dims* dims, const Dims* expected) {
  const NpyArray a = read_npy(path);
  if (a.descr != "|u1" && a.descr != "<u1" && a.descr != "<u2" && a.descr != "<u4")
    throw Error(Status::format, "'" + path + "' holds " + a.descr + ", expected unsigned integers (uint8, uint16, uint32)");
  if (a.shape.size() != 3)
    throw Error(Status::bad_dims, "'" + path + "' has " + std::to_string(a.shape.size()) + " dimensions, expected [z, y, x]");
  const Dims d{a.shape[2], a.shape[1], a.shape[0]};
  check_dims(d);
  if (expected && !(d == *expected))
    throw Error(Status::bad_dims, "'" + path + "' is " + std::to_string(d.nx) + " x " + std::to_string(d.ny) + " x " +
                                      std::to_string(d.nz) + " (x, y, z), expected " + std::to_string(expected->nx) +
                                      " x " + std::to_string(expected->ny) + " x " + std::to_string(expected->nz));
  if (dims) *dims = d;
  const std::size_t isz = a.descr == "<u4" ? 4 : a.descr == "<u2" ? 2 : 1;
  std::vector<std::uint32_t> out(d.count());
  auto value = [&](std::size_t k) -> std::uint32_t {
    const unsigned char* e = a.data.data() + k * isz;
    std::uint32_t v = 0;
    for (std::size_t b = 0; b < isz; ++b) v |= std::uint32_t(e[b]) << (8 * b);
    return v;
  };
  for (std::size_t z = 0, i = 0; z < d.nz; ++z)
    for (std::size_t y = 0; y < d.ny; ++y)
      for (std::size_t x = 0; x < d.nx; ++x, ++i) out[i] = value(a.fortran_order ? z + d.nz * (y + d.ny * x) : i);
  return out;
}

std::string object_name(const std::vector<std::string>& names, std::uint16_t id) {
  return id >= 1 && id <= names.size() ? names[id - 1] : "object " + std::to_string(id);
}

}  // namespace

void make_directory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(Status::io, "cannot create '" + dir + "': " + ec.message());
  if (!std::filesystem::is_directory(dir, ec)) throw Error(Status::io, "'" + dir + "' is not a directory");
}

json scene_json(const sim::Scene& scene, const sim::ScanConfig& config, const sim::Truth& truth) {
  json shapes = json::array(), views = json::array(), objects = json::array();
  for (const sim::Shape& s : scene.shapes)
    shapes.push_back({{"kind", sim::shape_kind_name(s.kind)}, {"object", s.object}, {"lo", vec(s.lo)}, {"hi", vec(s.hi)}});
  for (const sim::Viewpoint& v : scene.viewpoints)
    views.push_back({{"position", vec(v.position)},
                     {"heading_deg", v.heading_deg},
                     {"fov_deg", v.fov_deg},
                     {"pitch_deg", {v.pitch_min_deg, v.pitch_max_deg}}});
  std::vector<std::uint64_t> count(scene.objects.size() + 1, 0);
  for (std::uint16_t o : truth.objects)
    if (o < count.size()) ++count[o];
  for (std::size_t k = 0; k < scene.objects.size(); ++k)
    objects.push_back({{"id", k + 1}, {"name", scene.objects[k]}, {"voxels", count[k + 1]}});
  std::array<std::uint64_t, 3> states{};
  for (std::uint8_t s : truth.state) ++states[s];
  const Dims& d = scene.frame.dims;
  json sensor = {{"range_sigma", config.range_sigma},
                 {"angle_step_deg", config.angle_step_deg},
                 {"max_range", config.max_range},
                 {"noise", "mt19937_64 + Box-Muller, scan k of layer z seeded with splitmix(seed, z, k)"}};
  if (config.mode == sim::ScanMode::rings) sensor["ring_step_deg"] = config.ring_step_deg;
  return {{"scene", scene.name},
          {"construction", sim::scan_mode_name(config.mode)},
          {"seed", config.seed},
          {"dims", {d.nx, d.ny, d.nz}},
          {"array_order", "[z, y, x]"},
          {"voxel_size", scene.frame.voxel_size},
          {"origin", vec(scene.frame.origin)},
          {"sensor", sensor},
          {"fusion",
           {{"p_hit", config.model.p_hit},
            {"p_miss", config.model.p_miss},
            {"clamp_min", config.model.clamp_min},
            {"clamp_max", config.model.clamp_max}}},
          {"viewpoints", views},
          {"objects", objects},
          {"shapes", shapes},
          {"truth_states", per_state(states)},
          {"files",
           {{"map", "map.npy"}, {"truth_state", "truth_state.npy"}, {"truth_objects", "truth_objects.npy"}}}};
}

void write_simulation(const std::string& dir, const sim::Scene& scene, const sim::ScanConfig& config,
                      const Grid& map, const sim::Truth& truth, StagedFiles* into) {
  make_directory(dir);
  const Dims& d = map.dims;
  const std::vector<std::size_t> shape{d.nz, d.ny, d.nx};
  const std::string text = scene_json(scene, config, truth).dump(1) + "\n";
  StagedFiles own;
  StagedFiles* set = into ? into : &own;
  const std::string m = dir + "/map.npy", s = dir + "/truth_state.npy", o = dir + "/truth_objects.npy";
  write_grid_npy(m, map, set);
  write_npy(s, "|u1", shape, truth.state.data(), truth.state.size(), set);
  if (scene.objects.size() <= 255) {
    const std::vector<std::uint8_t> small(truth.objects.begin(), truth.objects.end());
    write_npy(o, "|u1", shape, small.data(), small.size(), set);
  } else {
    write_npy(o, "<u2", shape, truth.objects.data(), truth.objects.size() * 2, set);
  }
  write_file_atomically(dir + "/scene.json", [&](std::ostream& out) { out << text; }, set);
  if (!into) own.commit();
}

TruthDir read_truth(const std::string& dir) {
  TruthDir t;
  Dims d;
  const std::vector<std::uint32_t> st = read_integer_volume(dir + "/truth_state.npy", &d, nullptr);
  const std::vector<std::uint32_t> ob = read_integer_volume(dir + "/truth_objects.npy", nullptr, &d);
  t.truth.dims = d;
  t.truth.state.resize(st.size());
  t.truth.objects.resize(ob.size());
  const std::size_t nx = d.nx, sxy = d.nx * d.ny;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (st[i] > 2)
      throw Error(Status::bad_value, "'" + dir + "/truth_state.npy': voxel (" + std::to_string(i % nx) + ", " +
                                         std::to_string((i / nx) % d.ny) + ", " + std::to_string(i / sxy) + ") holds " +
                                         std::to_string(st[i]) + ", not a state (0 free, 1 unknown, 2 occupied)");
    if (ob[i] > 65535) throw Error(Status::bad_value, "'" + dir + "/truth_objects.npy': object id above 65535");
    t.truth.state[i] = static_cast<std::uint8_t>(st[i]);
    t.truth.objects[i] = static_cast<std::uint16_t>(ob[i]);
  }
  struct stat info {};
  if (::stat((dir + "/scene.json").c_str(), &info) == 0) {  // optional; read_file refuses a FIFO
    const std::string text = read_file(dir + "/scene.json");
    try {
      const json j = json::parse(text);
      t.scene = j.value("scene", "");
      t.voxel_size = j.value("voxel_size", 1.0);
      for (const json& o : j.at("objects")) {
        const std::size_t id = o.at("id").get<std::size_t>();
        if (id == 0 || id > 65535) throw Error(Status::format, "object id " + std::to_string(id) + " out of range");
        if (t.object_names.size() < id) t.object_names.resize(id);
        t.object_names[id - 1] = o.at("name").get<std::string>();
      }
    } catch (const json::exception& e) {
      throw Error(Status::format, "'" + dir + "/scene.json' is malformed: " + e.what());
    }
  }
  return t;
}

LabelArray read_labels(const std::string& path, const Dims& dims) {
  const std::vector<std::uint32_t> v = read_integer_volume(path, nullptr, &dims);
  return LabelArray(v.begin(), v.end());
}

std::vector<State> read_segment_states(const std::string& path) {
  const std::string text = read_file(path);  // a regular file only: a FIFO would block
  std::vector<State> out;
  try {
    const json j = json::parse(text);
    const json& segs = j.at("segments");
    for (std::size_t k = 0; k < segs.size(); ++k) {
      const json& s = segs[k];
      if (s.at("id").get<std::size_t>() != k)
        throw Error(Status::format, "'" + path + "': segment " + std::to_string(k) + " has id " + s.at("id").dump());
      const std::string st = s.at("state").get<std::string>();
      if (st == "free") out.push_back(State::free);
      else if (st == "unknown") out.push_back(State::unknown);
      else if (st == "occupied") out.push_back(State::occupied);
      else throw Error(Status::format, "'" + path + "': segment " + std::to_string(k) + " has state '" + st + "'");
    }
  } catch (const json::exception& e) {
    throw Error(Status::format, "'" + path + "' is not a segments.json: " + e.what());
  }
  return out;
}

const std::vector<std::string>& method_names() {
  static const std::vector<std::string> m = {"paper", "default", "baseline", "ideal"};
  return m;
}

Result run_method(const std::string& method, const Grid& map, const sim::Truth& truth, int threads, bool keep_stages) {
  Params p = method == "paper" ? Params::paper() : Params::defaults();
  p.threads = threads;
  if (method == "paper" || method == "default") return segment(map, p, keep_stages);
  if (method == "baseline") return sim::threshold_segmentation(map, p);
  if (method == "ideal") {
    if (!(truth.dims == map.dims)) throw Error(Status::bad_dims, "ground truth and map dims differ");
    Result r;
    r.dims = map.dims;
    label_components(truth.state, map, r.labels, r.segments);
    return r;
  }
  throw Error(Status::invalid_argument, "unknown method '" + method + "' (paper, default, baseline, ideal)");
}

std::vector<State> segment_states(const Result& r) {
  std::vector<State> s;
  s.reserve(r.segments.size());
  for (const Segment& seg : r.segments) s.push_back(seg.state);
  return s;
}

json scores_json(const sim::Scores& s, const std::vector<std::string>& names) {
  json objects = json::array();
  for (const sim::ObjectScore& o : s.objects)
    objects.push_back({{"id", o.id},
                       {"name", object_name(names, o.id)},
                       {"voxels", o.voxels},
                       {"labelled_free", o.labelled_free},
                       {"surface", o.surface},
                       {"surface_found", o.surface_found},
                       {"surface_recall", o.surface ? double(o.surface_found) / double(o.surface) : 0.0},
                       {"occupied_segments", o.segments},
                       {"largest_segment_share", o.largest_share}});
  std::array<std::uint64_t, 3> segs{s.segments_by_state[0], s.segments_by_state[1], s.segments_by_state[2]};
  return {{"voxels", s.voxels},
          {"accuracy", s.accuracy},
          {"iou", {{"free", s.iou[0]}, {"unknown", s.iou[1]}, {"occupied", s.iou[2]}}},
          {"truth_voxels", per_state(s.truth_voxels)},
          {"labelled_voxels", per_state(s.labelled_voxels)},
          {"object_voxels", s.object_voxels},
          {"object_free", s.object_free},
          {"object_free_share", s.object_free_share},
          {"unknown_voxels", s.unknown_voxels},
          {"unknown_free", s.unknown_free},
          {"unknown_free_share", s.unknown_free_share},
          {"segments", s.segments},
          {"segments_by_state", per_state(segs)},
          {"spanning_segments", s.spanning_segments},
          {"stray_segments", s.stray_segments},
          {"objects", objects}};
}

std::string scores_table(const std::vector<std::string>& methods, const std::vector<sim::Scores>& scores,
                         const std::vector<std::string>& names) {
  std::vector<std::pair<std::string, std::vector<std::string>>> rows;
  auto row = [&](const std::string& label, auto cell) {
    std::vector<std::string> cells;
    for (const sim::Scores& s : scores) cells.push_back(cell(s));
    rows.emplace_back(label, cells);
  };
  row("voxel accuracy", [&](const sim::Scores& s) { return percent(s.accuracy); });
  const char* st[3] = {"free", "unknown", "occupied"};
  for (int k = 0; k < 3; ++k) row(std::string("IoU ") + st[k], [&](const sim::Scores& s) { return fixed(s.iou[k], 3); });
  row("object voxels labelled free", [&](const sim::Scores& s) { return percent(s.object_free_share); });
  row("unknown voxels labelled free", [&](const sim::Scores& s) { return percent(s.unknown_free_share); });
  row("segments (free/unk/occ)", [&](const sim::Scores& s) {
    return std::to_string(s.segments) + " (" + std::to_string(s.segments_by_state[0]) + "/" +
           std::to_string(s.segments_by_state[1]) + "/" + std::to_string(s.segments_by_state[2]) + ")";
  });
  row("occupied segments spanning 2+ objects", [&](const sim::Scores& s) { return std::to_string(s.spanning_segments); });
  row("occupied segments near no object", [&](const sim::Scores& s) { return std::to_string(s.stray_segments); });
  if (!scores.empty())
    for (std::size_t k = 0; k < scores[0].objects.size(); ++k) {
      const std::string n = object_name(names, scores[0].objects[k].id);
      row(n + ": occupied segments", [&](const sim::Scores& s) { return std::to_string(s.objects[k].segments); });
      row(n + ": share in largest segment", [&](const sim::Scores& s) { return percent(s.objects[k].largest_share); });
      row(n + ": seen surface found", [&](const sim::Scores& s) {
        const auto& o = s.objects[k];
        return percent(o.surface ? double(o.surface_found) / double(o.surface) : 0.0);
      });
    }
  std::size_t w0 = 0;
  std::vector<std::size_t> w(methods.size());
  for (std::size_t c = 0; c < methods.size(); ++c) w[c] = methods[c].size();
  for (const auto& r : rows) {
    w0 = std::max(w0, r.first.size());
    for (std::size_t c = 0; c < r.second.size(); ++c) w[c] = std::max(w[c], r.second[c].size());
  }
  std::ostringstream o;
  o << std::left << std::setw(int(w0)) << "";
  for (std::size_t c = 0; c < methods.size(); ++c) o << "  " << std::right << std::setw(int(w[c])) << methods[c];
  o << "\n";
  for (const auto& r : rows) {
    o << std::left << std::setw(int(w0)) << r.first;
    for (std::size_t c = 0; c < r.second.size(); ++c) o << "  " << std::right << std::setw(int(w[c])) << r.second[c];
    o << "\n";
  }
  return o.str();
}

}  // namespace occseg::cli
