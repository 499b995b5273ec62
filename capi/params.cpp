// occseg_params_* and occseg_param_*: the parameter table of the C++ core (param_table,
// set_param, get_param) behind typed setters and getters.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "internal.hpp"
#include "occseg/registry.hpp"

using occseg::Error;
using occseg::ParamInfo;
using occseg::Status;
using occseg::capi::copy_text;
using occseg::capi::guard;
using occseg::capi::index_out_of_range;
using occseg::capi::invalid;
using occseg::capi::number;
using occseg::capi::require;

namespace {

// Built-in parameters and those plugins declared (occseg/registry.hpp); the reference stays valid.
const ParamInfo& info_of(const char* name) {
  require(name, "name");
  if (const ParamInfo* i = occseg::find_param(name)) return *i;
  invalid(std::string("parameter '") + name + "': no such parameter");
}

bool is(const ParamInfo& i, const char* kind) { return std::strcmp(i.kind, kind) == 0; }

[[noreturn]] void wrong_kind(const ParamInfo& i, const char* use) {
  invalid(std::string("parameter '") + i.name + "' is of kind " + i.kind + "; use " + use);
}

// Index into the built-in table followed by the declared parameters (a list that only grows).
const ParamInfo* table_entry(uint32_t index) {
  const auto& t = occseg::param_table();
  if (index < t.size()) return &t[index];
  const auto declared = occseg::plugin_params();
  index -= static_cast<uint32_t>(t.size());
  return index < declared.size() ? &declared[index]->info : nullptr;
}

}  // namespace

extern "C" {

int occseg_params_create(occseg_params** out) {
  return guard("occseg_params_create", [&] {
    require(out, "out");
    *out = nullptr;
    *out = new occseg_params();
  });
}

int occseg_params_copy(occseg_params** out, const occseg_params* src) {
  return guard("occseg_params_copy", [&] {
    require(out, "out");
    *out = nullptr;
    require(src, "src");
    *out = new occseg_params(*src);
  });
}

void occseg_params_free(occseg_params* params) { delete params; }

int occseg_params_preset(occseg_params* params, const char* name) {
  return guard("occseg_params_preset", [&] {
    require(params, "params");
    require(name, "name");
    occseg::set_param(params->params, "preset", name);
  });
}

int occseg_params_set(occseg_params* params, const char* name, const char* value) {
  return guard("occseg_params_set", [&] {
    require(params, "params");
    require(value, "value");
    occseg::set_param(params->params, info_of(name).name, value);
  });
}

int occseg_params_set_int(occseg_params* params, const char* name, int64_t value) {
  return guard("occseg_params_set_int", [&] {
    require(params, "params");
    const ParamInfo& i = info_of(name);
    if (is(i, "string")) wrong_kind(i, "occseg_params_set_string");
    occseg::set_param(params->params, i.name, std::to_string(value));
  });
}

int occseg_params_set_double(occseg_params* params, const char* name, double value) {
  return guard("occseg_params_set_double", [&] {
    require(params, "params");
    const ParamInfo& i = info_of(name);
    if (is(i, "string")) wrong_kind(i, "occseg_params_set_string");
    const std::string text = number(value);  // 17 digits: round-trips exactly through strtod
    if (!std::isfinite(value)) invalid(std::string("parameter '") + i.name + "': " + text + " is not a finite number");
    occseg::set_param(params->params, i.name, text);
  });
}

int occseg_params_set_string(occseg_params* params, const char* name, const char* value) {
  return guard("occseg_params_set_string", [&] {
    require(params, "params");
    const ParamInfo& i = info_of(name);
    require(value, "value");
    if (!is(i, "string")) wrong_kind(i, "occseg_params_set_int, occseg_params_set_double or occseg_params_set");
    occseg::set_param(params->params, i.name, value);
  });
}

int occseg_params_get_int(const occseg_params* params, const char* name, int64_t* out) {
  return guard("occseg_params_get_int", [&] {
    require(params, "params");
    const ParamInfo& i = info_of(name);
    require(out, "out");
    if (!is(i, "int")) wrong_kind(i, is(i, "double") ? "occseg_params_get_double" : "occseg_params_get_string");
    *out = std::strtoll(occseg::get_param(params->params, i.name).c_str(), nullptr, 10);
  });
}

int occseg_params_get_double(const occseg_params* params, const char* name, double* out) {
  return guard("occseg_params_get_double", [&] {
    require(params, "params");
    const ParamInfo& i = info_of(name);
    require(out, "out");
    if (is(i, "string")) wrong_kind(i, "occseg_params_get_string");
    *out = std::strtod(occseg::get_param(params->params, i.name).c_str(), nullptr);
  });
}

int occseg_params_get_string(const occseg_params* params, const char* name, char* buf, size_t size,
                             size_t* length) {
  return guard("occseg_params_get_string", [&] {
    require(params, "params");
    const ParamInfo& i = info_of(name);
    if (!is(i, "string")) wrong_kind(i, "occseg_params_get_int, occseg_params_get_double or occseg_params_get");
    copy_text(occseg::get_param(params->params, i.name), buf, size, length);
  });
}

int occseg_params_get(const occseg_params* params, const char* name, char* buf, size_t size, size_t* length) {
  return guard("occseg_params_get", [&] {
    require(params, "params");
    copy_text(occseg::get_param(params->params, info_of(name).name), buf, size, length);
  });
}

int occseg_params_set_progress(occseg_params* params, occseg_progress_fn fn, void* user) {
  return guard("occseg_params_set_progress", [&] {
    require(params, "params");
    params->progress = fn;
    params->progress_user = fn ? user : nullptr;
  });
}

int occseg_params_validate(const occseg_params* params) {
  return guard("occseg_params_validate", [&] {
    require(params, "params");
    params->params.validate();
  });
}

uint32_t occseg_param_count(void) {
  return static_cast<uint32_t>(occseg::param_table().size() + occseg::plugin_params().size());
}

const char* occseg_param_name(uint32_t index) {
  const ParamInfo* i = table_entry(index);
  return i ? i->name : nullptr;
}

const char* occseg_param_kind(uint32_t index) {
  const ParamInfo* i = table_entry(index);
  return i ? i->kind : nullptr;
}

const char* occseg_param_description(uint32_t index) {
  const ParamInfo* i = table_entry(index);
  return i ? i->description : nullptr;
}

int occseg_param_bounds(uint32_t index, double* min, double* max) {
  return guard("occseg_param_bounds", [&] {
    require(min, "min");
    require(max, "max");
    const ParamInfo* i = table_entry(index);
    if (!i) index_out_of_range(index, occseg_param_count(), "parameters");
    *min = i->min;
    *max = i->max;
  });
}

int occseg_param_find(const char* name, uint32_t* index) {
  return guard("occseg_param_find", [&] {
    require(index, "index");
    const ParamInfo& i = info_of(name);
    const auto all = occseg::all_params();
    for (uint32_t k = 0; k < all.size(); ++k)
      if (std::strcmp(all[k].name, i.name) == 0) *index = k;
  });
}

}  // extern "C"
