// Status names and the per-thread last-error text.
#include <cstdio>

#include "internal.hpp"

namespace {

// Fixed-size so that reporting an out-of-memory failure cannot itself fail; long messages are
// cut (paths rarely come near this).
thread_local char g_last_error[2048] = "";

struct StatusText {
  int code;
  const char* name;
  const char* text;
};

const StatusText kStatus[] = {
    {OCCSEG_OK, "OCCSEG_OK", "success"},
    {OCCSEG_EINVAL, "OCCSEG_EINVAL", "invalid argument"},
    {OCCSEG_EDIMS, "OCCSEG_EDIMS", "bad dimensions"},
    {OCCSEG_EVALUE, "OCCSEG_EVALUE", "bad value"},
    {OCCSEG_ENOMEM, "OCCSEG_ENOMEM", "out of memory"},
    {OCCSEG_EIO, "OCCSEG_EIO", "input/output error"},
    {OCCSEG_EFORMAT, "OCCSEG_EFORMAT", "bad file format"},
    {OCCSEG_ERANGE, "OCCSEG_ERANGE", "out of range"},
    {OCCSEG_ECANCELLED, "OCCSEG_ECANCELLED", "cancelled"},
    {OCCSEG_EPLUGIN, "OCCSEG_EPLUGIN", "plugin error"},
    {OCCSEG_EUNSUPPORTED, "OCCSEG_EUNSUPPORTED", "unsupported"},
    {OCCSEG_EINTERNAL, "OCCSEG_EINTERNAL", "internal error"},
};

const StatusText* find(int code) {
  for (const StatusText& s : kStatus)
    if (s.code == code) return &s;
  return nullptr;
}

// The C enum and the C++ enum are two spellings of one table.
static_assert(OCCSEG_EINVAL == static_cast<int>(occseg::Status::invalid_argument));
static_assert(OCCSEG_EDIMS == static_cast<int>(occseg::Status::bad_dims));
static_assert(OCCSEG_EVALUE == static_cast<int>(occseg::Status::bad_value));
static_assert(OCCSEG_ENOMEM == static_cast<int>(occseg::Status::no_memory));
static_assert(OCCSEG_EIO == static_cast<int>(occseg::Status::io));
static_assert(OCCSEG_EFORMAT == static_cast<int>(occseg::Status::format));
static_assert(OCCSEG_ERANGE == static_cast<int>(occseg::Status::out_of_range));
static_assert(OCCSEG_ECANCELLED == static_cast<int>(occseg::Status::cancelled));
static_assert(OCCSEG_EPLUGIN == static_cast<int>(occseg::Status::plugin));
static_assert(OCCSEG_EUNSUPPORTED == static_cast<int>(occseg::Status::unsupported));
static_assert(OCCSEG_EINTERNAL == static_cast<int>(occseg::Status::internal));

}  // namespace

namespace occseg::capi {

void clear_error() noexcept { g_last_error[0] = '\0'; }

int fail(const char* function, int code, const char* message, const char* prefix) noexcept {
  std::snprintf(g_last_error, sizeof g_last_error, "%s: %s%s", function, prefix, message);
  return code;
}

}  // namespace occseg::capi

extern "C" {

const char* occseg_status_string(int code) {
  const StatusText* s = find(code);
  return s ? s->text : "unknown status";
}

const char* occseg_status_name(int code) {
  const StatusText* s = find(code);
  return s ? s->name : "OCCSEG_E?";
}

const char* occseg_last_error(void) { return g_last_error; }

}  // extern "C"
