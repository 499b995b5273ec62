// occseg_result_write: labels.npy and segments.json, the files of `occseg segment --out`, replaced
// together (occseg::StagedFiles): the old pair stays whole or the new pair replaces it whole.
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "internal.hpp"
#include "occseg/file_write.hpp"
#include "occseg/npy.hpp"
#include "occseg/segments_json.hpp"

using occseg::Error;
using occseg::Status;
using occseg::capi::guard;
using occseg::capi::make_dir;
using occseg::capi::require;

namespace occseg::capi {

bool make_dir(const std::string& dir) {
  const bool made = ::mkdir(dir.c_str(), 0777) == 0;
  if (!made && errno != EEXIST) throw Error(Status::io, "cannot create '" + dir + "': " + std::strerror(errno));
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) throw Error(Status::io, "'" + dir + "' is not a directory");
  return made;
}

}  // namespace occseg::capi

extern "C" {

int occseg_result_write(const occseg_result* result, const char* dir) {
  return guard("occseg_result_write", [&] {
    require(result, "result");
    require(dir, "dir");
    const bool made = make_dir(dir);
    try {
      occseg::StagedFiles files;
      occseg::write_labels_npy(std::string(dir) + "/labels.npy", result->result.dims, result->result.labels, &files);
      occseg::write_file_atomically(
          std::string(dir) + "/segments.json",
          [&](std::ostream& out) {
            // With the map's frame and the boxes, as `occseg segment` writes it.
            occseg::write_segments_json(out, result->result, result->preset,
                                        {result->voxel_size, result->origin, &result->boxes()});
          },
          &files);
      files.commit();
    } catch (...) {
      if (made) ::rmdir(dir);  // ours and empty again: nothing of this call is left
      throw;
    }
  });
}

}  // extern "C"
