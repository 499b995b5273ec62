// The version of the library actually loaded (the header's macros give the compiled-against one).
#include "internal.hpp"

extern "C" {

uint32_t occseg_version_number(void) { return OCCSEG_VERSION_NUMBER; }

const char* occseg_version_string(void) { return OCCSEG_VERSION_STRING; }

}  // extern "C"
