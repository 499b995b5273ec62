// occseg_result_write_outputs: the files of `occseg segment --out` that liboccseg can write
// itself, chosen by name, replaced together (occseg::StagedFiles) as occseg_result_write does.
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "internal.hpp"
#include "occseg/file_write.hpp"
#include "occseg/map_yaml.hpp"
#include "occseg/npy.hpp"
#include "occseg/nrrd.hpp"
#include "occseg/segments_json.hpp"
#include "occseg/voxel_mesh.hpp"

using occseg::Error;
using occseg::Status;
using occseg::capi::guard;
using occseg::capi::make_dir;
using occseg::capi::require;

namespace {

using Writer = std::function<void(const std::string&, occseg::StagedFiles&)>;

// The writer of `name`, or throws: Error(unsupported) for the command's outputs that need
// libraries liboccseg does not link, Error(invalid_argument) for any other name.
Writer writer_of(const occseg_result* r, const occseg::Grid& frame, const std::string& name) {
  const occseg::Result& res = r->result;
  if (name == "labels.npy")
    return [&res](const std::string& f, occseg::StagedFiles& s) { occseg::write_labels_npy(f, res.dims, res.labels, &s); };
  if (name == "labels.nrrd")
    return [&res, &frame, r](const std::string& f, occseg::StagedFiles& s) {
      occseg::NrrdWriteOptions gz;  // gzip-encoded, byte for byte as the command writes it
      gz.gzip = true;
      occseg::write_labels_nrrd(f, frame, res.labels, r->nrrd_space, &s, gz);
    };
  if (name == "segments.json")
    return [&res, r](const std::string& f, occseg::StagedFiles& s) {
      occseg::write_file_atomically(
          f,
          [&](std::ostream& out) {
            occseg::write_segments_json(out, res, r->preset, {r->voxel_size, r->origin, &r->boxes()});
          },
          &s);
    };
  if (name == "segments.ply")
    return [&res, r](const std::string& f, occseg::StagedFiles& s) {
      occseg::write_segments_ply(f, res, r->voxel_size, r->origin, &s);
    };
  if (name == "segmentation.pgm" || name == "segmentation.yaml") {
    if (res.dims.nz != 1)
      throw Error(Status::invalid_argument, "'" + name + "' is written for 2D maps (nz = 1) only; this one has nz = " +
                                                std::to_string(res.dims.nz));
    if (name == "segmentation.yaml")
      return [&frame](const std::string& f, occseg::StagedFiles& s) {
        occseg::write_map_yaml(f, "segmentation.pgm", frame, &s);
      };
    return [&res](const std::string& f, occseg::StagedFiles& s) {
      occseg::write_state_pgm(f, res.dims, occseg::voxel_states(res), &s);
    };
  }
  if (name == "segmentation.png" || name == "scene.png" || name == "segments.ot" || name == "segments.pcd" ||
      name == "map.nrrd" || name == "points.pcd" || name == "points.labels.npy" || name == "map.npy")
    throw Error(Status::unsupported, "'" + name +
                                         "' is written by the occseg command only (it needs the map or libraries "
                                         "liboccseg does not link: libpng, OctoMap, PCL)");
  throw Error(Status::invalid_argument, "'" + name + "' is not an output file of occseg");
}

}  // namespace

extern "C" {

int occseg_result_write_outputs(const occseg_result* result, const char* dir, const char* const* names) {
  return guard("occseg_result_write_outputs", [&] {
    require(result, "result");
    require(dir, "dir");
    std::vector<std::string> wanted;
    if (names) {
      for (const char* const* n = names; *n; ++n) wanted.emplace_back(*n);
    } else {
      wanted = {"labels.nrrd", "segments.json"};
      if (result->result.dims.nz == 1) {
        wanted.emplace_back("segmentation.pgm");
        wanted.emplace_back("segmentation.yaml");
      }
    }
    // The map's frame for the writers that need a Grid's geometry (its values are not needed).
    occseg::Grid frame;
    frame.dims = result->result.dims;
    frame.voxel_size = result->voxel_size;
    frame.origin = result->origin;
    std::vector<std::pair<std::string, Writer>> writers;
    for (const std::string& w : wanted) {
      for (const auto& done : writers)
        if (done.first == w) throw Error(Status::invalid_argument, "'" + w + "' is named twice");
      if (w.empty() || w.find('/') != std::string::npos)
        throw Error(Status::invalid_argument, "'" + w + "' is not an output file of occseg");
      writers.emplace_back(w, writer_of(result, frame, w));
    }
    const bool made = make_dir(dir);
    try {
      occseg::StagedFiles files;
      for (const auto& w : writers) w.second(std::string(dir) + "/" + w.first, files);
      files.commit();
    } catch (...) {
      if (made) ::rmdir(dir);
      throw;
    }
  });
}

}  // extern "C"
