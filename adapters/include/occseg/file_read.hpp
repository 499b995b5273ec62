// Reading whole input files, with errors that name the file and the problem (missing, not
// permitted, a directory, an I/O error) rather than a stream exception or an empty read.
#pragma once
#include <cstddef>
#include <string>
#include <string_view>

namespace occseg {

// The bytes of `path`. Throws Error(io) "cannot open 'path': <reason>", "'path' is a directory"
// or "cannot read 'path': <reason>".
std::string read_file(const std::string& path);

// Throws the same errors when `path` cannot be opened for reading or is a directory, for
// readers that hand the path on to a library (PCL, OctoMap).
void check_readable(const std::string& path);

// File content as it may appear in a message: printable ASCII is kept, a backslash is doubled,
// and every other byte (control characters, terminal escape sequences, bytes >= 0x80) becomes
// \xNN; at most `max_bytes` bytes of `text` are shown, and "..." marks a cut. Every reader that
// quotes bytes of its file in an error goes through this, so no message carries the file's
// control sequences to a terminal or a log.
std::string printable(std::string_view text, std::size_t max_bytes = 64);

}  // namespace occseg
