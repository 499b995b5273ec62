#include "occseg/refine.hpp"

#include <algorithm>
#include <memory>

#include "occseg/parallel.hpp"

namespace occseg {

const ScanDirection kSixDirections[6] = {{0, +1}, {0, -1}, {1, +1}, {1, -1}, {2, +1}, {2, -1}};

namespace {

constexpr std::uint8_t kFree = static_cast<std::uint8_t>(State::free);
constexpr std::uint8_t kUnknown = static_cast<std::uint8_t>(State::unknown);
constexpr std::uint8_t kOccupied = static_cast<std::uint8_t>(State::occupied);

// Runs fn(first, stride, length) over every line of the map along `dir`; `first` is the index
// where the scan starts and `stride` the signed step between successive voxels.
template <class F>
void for_each_line(const Grid& g, ScanDirection dir, int threads, F&& fn) {
  const std::size_t n[3] = {g.dims.nx, g.dims.ny, g.dims.nz};
  const std::ptrdiff_t s[3] = {1, static_cast<std::ptrdiff_t>(n[0]), static_cast<std::ptrdiff_t>(n[0] * n[1])};
  const int a = dir.axis, b = (a + 1) % 3, c = (a + 2) % 3;
  const std::size_t len = n[a];
  const std::ptrdiff_t stride = s[a] * dir.step;
  parallel_for(n[c], threads, [&](std::size_t c0, std::size_t c1) {
    for (std::size_t ic = c0; ic < c1; ++ic)
      for (std::size_t ib = 0; ib < n[b]; ++ib) {
        std::ptrdiff_t first = static_cast<std::ptrdiff_t>(ib) * s[b] + static_cast<std::ptrdiff_t>(ic) * s[c];
        if (dir.step < 0) first += static_cast<std::ptrdiff_t>(len - 1) * s[a];
        fn(first, stride, len);
      }
  });
}

}  // namespace

void refine_unknown(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  const float* p = g.p.data();
  for (const ScanDirection dir : kSixDirections)
    for_each_line(g, dir, params.threads, [&](std::ptrdiff_t i, std::ptrdiff_t stride, std::size_t len) {
      std::uint8_t prev = st[i];
      for (std::size_t k = 1; k < len; ++k) {
        i += stride;
        if (prev == kUnknown && st[i] == kFree && params.at_half(p[i])) st[i] = kUnknown;
        prev = st[i];
      }
    });
}

void classify_window(const float* p, int n, std::uint8_t from, std::uint8_t into,
                     const Params& params, bool* reassign) {
  bool low = false, high = false;
  for (int k = 0; k < n; ++k) {
    low = low || p[k] < params.free_below;
    high = high || p[k] > params.occupied_above;
    reassign[k] = false;
  }
  // The entered segment's "other side": values that argue for the state we came from.
  const bool other = (from == kFree) ? low : high;
  const bool own = (from == kFree) ? high : low;
  if (!other) return;  // cases i and ii: all at 0.5, or only the entered state's own evidence
  for (int k = 0; k < n; ++k) {
    if (!own) {
      reassign[k] = true;  // case iii: the window argues only for `from`
    } else {               // case iv: mixed; values on `from`'s side or at 0.5 move
      reassign[k] = (from == kFree) ? !(p[k] > params.occupied_above) : !(p[k] < params.free_below);
    }
  }
  (void)into;
}

void refine_boundaries(std::vector<std::uint8_t>& st, const Grid& g, const Params& params) {
  const int look = std::max(1, params.lookahead);
  const float* pg = g.p.data();
  for (int pass = 0; pass < params.refine_passes; ++pass)
    for (const ScanDirection dir : kSixDirections)
      for_each_line(g, dir, params.threads, [&](std::ptrdiff_t first, std::ptrdiff_t stride, std::size_t len) {
        std::vector<float> win(static_cast<std::size_t>(look));
        std::vector<std::ptrdiff_t> at(static_cast<std::size_t>(look));
        std::unique_ptr<bool[]> re(new bool[static_cast<std::size_t>(look)]);
        std::size_t k = 1;
        while (k < len) {
          const std::ptrdiff_t i = first + static_cast<std::ptrdiff_t>(k) * stride;
          const std::uint8_t a = st[i - stride], s = st[i];
          const bool boundary = (a == kFree && s == kOccupied) || (a == kOccupied && s == kFree);
          if (!boundary) {
            ++k;
            continue;
          }
          int n = 0;  // the window: up to `look` voxels of the entered segment
          while (n < look && k + n < len && st[i + n * stride] == s) {
            at[n] = i + n * stride;
            win[n] = pg[at[n]];
            ++n;
          }
          classify_window(win.data(), n, a, s, params, re.get());
          for (int w = 0; w < n; ++w)
            if (re[w]) st[at[w]] = a;
          k += static_cast<std::size_t>(n);  // resume after the window: no cascade through it
        }
      });
}

}  // namespace occseg
