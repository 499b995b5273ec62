// Reading whole input files, with errors that name the file and the problem (missing, not
// permitted, a directory, an I/O error) rather than a stream exception or an empty read.
#pragma once
#include <string>

namespace occseg {

// The bytes of `path`, a regular file (or a symbolic link to one). Throws Error(io) "cannot open
// 'path': <reason>", "cannot read 'path': it is a directory", "... it is not a regular file but
// a FIFO (named pipe)" (or a device, a socket: refused without reading or blocking), or "cannot
// read 'path': <reason>".
std::string read_file(const std::string& path);

// Throws the same errors when `path` cannot be opened for reading or is not a regular file, for
// readers that hand the path on to a library (PCL, OctoMap).
void check_readable(const std::string& path);

}  // namespace occseg
