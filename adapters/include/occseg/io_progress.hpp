// Progress of the file readers and writers: the fraction done (0..1), reported from the calling
// thread; a callback that returns false cancels the read or write, which then throws
// Error(cancelled) and leaves no file behind (writes are staged, see file_write.hpp).
#pragma once
#include <functional>

namespace occseg {

using IoProgress = std::function<bool(double fraction)>;

// Calls `progress` (when set) with `fraction`; throws Error(cancelled) when it returns false.
void report_progress(const IoProgress& progress, double fraction);

}  // namespace occseg
