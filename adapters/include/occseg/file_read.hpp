// Reading whole input files, with errors that name the file and the problem (missing, not
// permitted, a directory, an I/O error) rather than a stream exception or an empty read.
#pragma once
#include <string>

namespace occseg {

// The bytes of `path`. Throws Error(io) "cannot open 'path': <reason>", "'path' is a directory"
// or "cannot read 'path': <reason>".
std::string read_file(const std::string& path);

// Throws the same errors when `path` cannot be opened for reading or is a directory, for
// readers that hand the path on to a library (PCL, OctoMap).
void check_readable(const std::string& path);

}  // namespace occseg
