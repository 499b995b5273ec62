// occseg_context_*: the C face of occseg::Context, a caller-owned thread pool.
#include <string>

#include "internal.hpp"

using occseg::Error;
using occseg::Status;
using occseg::capi::guard;
using occseg::capi::require;

extern "C" {

int occseg_context_new(occseg_context** out, int threads) {
  return guard("occseg_context_new", [&] {
    require(out, "out");
    *out = nullptr;
    if (threads < 0 || threads > 1024)
      throw Error(Status::invalid_argument, "threads = " + std::to_string(threads) + " is outside [0, 1024]");
    *out = new occseg_context(threads);
  });
}

void occseg_context_free(occseg_context* context) { delete context; }

int occseg_context_threads(const occseg_context* context) { return context ? context->context.threads() : 0; }

void occseg_context_recycle(occseg_context* context, occseg_result* result) {
  if (context && result) {
    try {
      context->context.recycle(std::move(result->result));
    } catch (...) {
      // Only a mutex that cannot be locked could throw here: the array is then simply freed.
    }
  }
  delete result;
}

}  // extern "C"
