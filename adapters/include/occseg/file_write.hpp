// Writing files all-or-nothing: data goes to a temporary name beside the target and is renamed
// over it only once complete, so a failure or a cancel never leaves a half-written output.
#pragma once
#include <functional>
#include <ostream>
#include <string>

namespace occseg {

// Calls write(stream) on a temporary file next to `path`, then renames it to `path`. Throws
// Error(io) naming the path if it cannot be created, written or renamed; the temporary file is
// removed on any failure, including an exception thrown by `write`.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace occseg
