// The built-in stages, registered as the plugin "builtin" through the same host table as every
// external plugin: texture operators lbp6 (the paper's 6-neighbour LBP/C) and lbp8 (the 3x3
// LBP/C of the authors' 2D method), similarities g (eq. 1) and chi2.
#include <cmath>
#include <cstring>
#include <exception>
#include <vector>

#include "occseg/error.hpp"
#include "stages/histogram.hpp"
#include "stages/texture.hpp"
#include "stages/texture2d.hpp"
#include "stages/codes.hpp"
#include "registry/registry_internal.hpp"

namespace occseg {

TextureUnit8 texture_unit8(double centre, const double n[8]) {
  TextureUnit8 u;
  double s1 = 0, s0 = 0;
  int n1 = 0, n0 = 0;
  for (int k = 0; k < 8; ++k) {
    if (n[k] >= centre) {
      u.lbp = static_cast<std::uint8_t>(u.lbp | (1u << k));
      s1 += n[k];
      ++n1;
    } else {
      s0 += n[k];
      ++n0;
    }
  }
  u.contrast = (n1 && n0) ? s1 / n1 - s0 / n0 : 0.0;
  return u;
}

namespace {

int fail(const occseg_plugin_call* call, int code, const std::string& message) {
  call->host->set_error(message.c_str());
  return code;
}

// ---- lbp6 -------------------------------------------------------------------------------------

TextureMap lbp6_native(const Grid& grid, const Params& params) {
  return compute_texture(grid, params.contrast_bins, params.threads);
}

int lbp6_native_into(const Grid& grid, const Params& params, const kernels::Table& k, std::uint16_t* codes,
                     std::uint8_t* scratch, const detail::MapRowSink* rows) {
  detail::compute_texture_into(grid, params.contrast_bins, params.threads, reinterpret_cast<detail::code_t*>(codes),
                               scratch, rows, k);
  return 64 * params.contrast_bins;
}

// The generic path of lbp6 (what a caller of the C callback gets): the same codes as the native
// path, which the pipeline uses instead to avoid copying the map.
int64_t lbp6_compute(const occseg_plugin_call* call, const occseg_plugin_grid* g, uint32_t bins, uint16_t* codes) {
  try {
    Grid grid;
    grid.dims = Dims{g->dims[0], g->dims[1], g->dims[2]};
    grid.p.assign(g->values, g->values + grid.dims.count());
    const TextureMap tm = compute_texture(grid, static_cast<int>(bins), static_cast<int>(call->threads));
    std::memcpy(codes, tm.codes.data(), tm.codes.size() * sizeof(uint16_t));
    return tm.code_count();
  } catch (const Error& e) {
    return fail(call, static_cast<int>(e.status()), e.what());
  } catch (const std::bad_alloc&) {
    return fail(call, OCCSEG_ENOMEM, "lbp6: out of memory");
  }
}

// ---- lbp8 -------------------------------------------------------------------------------------

int64_t lbp8_compute(const occseg_plugin_call* call, const occseg_plugin_grid* g, uint32_t bins, uint16_t* codes) {
  const size_t nx = g->dims[0], ny = g->dims[1], nz = g->dims[2];
  if (nz != 1)
    return fail(call, OCCSEG_EDIMS, "lbp8 is the 2D operator: the map has nz = " + std::to_string(nz) +
                                        " (it needs nz = 1; use lbp6 for 3D maps)");
  try {
    const std::size_t n = nx * ny;
    std::vector<double> contrast(n, std::nan(""));
    std::vector<uint8_t> lbp(n, 0);
    const float* p = g->values;
    for (size_t y = 1; y + 1 < ny; ++y)
      for (size_t x = 1; x + 1 < nx; ++x) {
        const size_t i = x + nx * y;
        double nb[8];
        for (int k = 0; k < 8; ++k) nb[k] = p[(x + kLbp8Dx[k]) + nx * (y + kLbp8Dy[k])];
        const TextureUnit8 u = texture_unit8(p[i], nb);
        lbp[i] = u.lbp;
        contrast[i] = u.contrast;
      }
    if (int rc = call->host->contrast_levels(contrast.data(), n, bins, codes)) return rc;
    for (std::size_t i = 0; i < n; ++i)
      if (codes[i] != OCCSEG_NO_TEXTURE) codes[i] = static_cast<uint16_t>(lbp[i] * bins + codes[i]);
    return 256 * static_cast<int64_t>(bins);
  } catch (const std::bad_alloc&) {
    return fail(call, OCCSEG_ENOMEM, "lbp8: out of memory");
  }
}

// ---- similarities -----------------------------------------------------------------------------

double g_compare(const occseg_plugin_call*, const uint32_t* a, const uint32_t* b, size_t bins) {
  return g_statistic(a, b, bins);
}

// Chi-square of two binned samples of unequal size (Press et al., Numerical Recipes 14.3):
// sum_i (sqrt(Nb/Na) a_i - sqrt(Na/Nb) b_i)^2 / (a_i + b_i) over the bins where a_i + b_i > 0.
// Zero for proportional histograms, like G; the same relative cut removes rounding noise.
double chi2_compare(const occseg_plugin_call*, const uint32_t* a, const uint32_t* b, size_t bins) {
  double na = 0, nb = 0;
  for (size_t i = 0; i < bins; ++i) {
    na += a[i];
    nb += b[i];
  }
  if (na == 0 || nb == 0) return 0.0;
  const double ka = std::sqrt(nb / na), kb = std::sqrt(na / nb);
  double chi = 0;
  for (size_t i = 0; i < bins; ++i) {
    if (a[i] == 0 && b[i] == 0) continue;
    const double d = ka * a[i] - kb * b[i];
    chi += d * d / (double(a[i]) + b[i]);
  }
  return chi > 1e-9 * (na + nb) ? chi : 0.0;
}

int register_builtins(const occseg_plugin_host* host, occseg_plugin_registrar* r) {
  const occseg_plugin_texture textures[] = {
      {sizeof(occseg_plugin_texture), "lbp6",
       "6-neighbour LBP/C of the paper (64 x b codes), for 3D maps (and 2D ones)", lbp6_compute, nullptr},
      {sizeof(occseg_plugin_texture), "lbp8",
       "8-neighbour 3x3 LBP/C of the authors' 2D method (256 x b codes), for 2D maps (nz = 1)", lbp8_compute, nullptr},
  };
  const occseg_plugin_similarity sims[] = {
      {sizeof(occseg_plugin_similarity), "g", "G-statistic (log-likelihood ratio) of eq. (1)", g_compare, nullptr},
      {sizeof(occseg_plugin_similarity), "chi2", "chi-square of two binned samples of unequal size", chi2_compare, nullptr},
  };
  for (const auto& t : textures)
    if (int rc = host->register_texture(r, &t)) return rc;
  for (const auto& s : sims)
    if (int rc = host->register_similarity(r, &s)) return rc;
  return 0;
}

const occseg_plugin_descriptor kBuiltin = {
    OCCSEG_PLUGIN_ABI_MAJOR, OCCSEG_PLUGIN_ABI_MINOR, sizeof(occseg_plugin_descriptor), kBuiltinPlugin,
    OCCSEG_CORE_VERSION, "built-in texture operators and similarities", register_builtins};

}  // namespace

const occseg_plugin_descriptor* builtin_stages_descriptor() { return &kBuiltin; }

void attach_builtin_natives() { set_native_texture("lbp6", lbp6_native, lbp6_native_into); }

}  // namespace occseg
