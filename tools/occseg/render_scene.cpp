#include "render_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include "occseg/segment_colour.hpp"

namespace occseg::render {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kText{30, 30, 30};
constexpr Rgb kFaint{200, 200, 200};    // the floor outline under the segments
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr double kMaxScale = 96;        // pixels per voxel: a map of a few voxels is not drawn larger
constexpr double kMargin = 12;          // pixels between the fitted box and the view's edges
constexpr double kPixelBudget = 32e6;   // sprite pixels drawn at most (bounds time for any map)

struct Axes {
  double rx, ry, rz, ux, uy, uz;  // R and U (render_scene.hpp)
};

Axes view_axes() {
  const double a = kSceneAzimuthDeg * kPi / 180, e = kSceneElevationDeg * kPi / 180;
  return {std::cos(a), -std::sin(a), 0.0, std::sin(a) * std::sin(e), std::cos(a) * std::sin(e), std::cos(e)};
}

// The box in voxel units the view is fitted to: the occupied segments' voxels, or the map.
void fit_box(const Result& r, double lo[3], double hi[3]) {
  bool any = false;
  for (const Segment& s : r.segments) {
    if (s.state != State::occupied || s.voxels == 0) continue;
    for (int k = 0; k < 3; ++k) {
      lo[k] = any ? std::min(lo[k], double(s.bbox_min[k])) : double(s.bbox_min[k]);
      hi[k] = any ? std::max(hi[k], double(s.bbox_max[k]) + 1) : double(s.bbox_max[k]) + 1;
    }
    any = true;
  }
  if (!any) {
    lo[0] = lo[1] = lo[2] = 0;
    hi[0] = double(r.dims.nx), hi[1] = double(r.dims.ny), hi[2] = double(r.dims.nz);
  }
}

// One pixel of a voxel's picture, relative to where its corner (0, 0, 0) is drawn.
struct SpritePixel {
  int du, dv;
  std::uint8_t face;  // 0 top, 1 front, 2 left
};

// The pixels of a cube of edge `e` voxels: for each of the three visible faces, each pixel whose
// centre lies within half a pixel of it (so neighbouring cubes, drawn at rounded positions, leave
// no cracks between them). A pixel near several faces has an entry for each, the face it lies
// deepest in last.
std::vector<SpritePixel> cube_sprite(const Axes& A, double s, double e) {
  const double k = s * e;
  const double ex[2] = {k * A.rx, -k * A.ux}, ey[2] = {k * A.ry, -k * A.uy}, ez[2] = {k * A.rz, -k * A.uz};
  struct Face {
    double o[2], a[2], b[2];
  };
  const Face faces[3] = {{{ez[0], ez[1]}, {ex[0], ex[1]}, {ey[0], ey[1]}},  // +z at z = e
                         {{0, 0}, {ex[0], ex[1]}, {ez[0], ez[1]}},          // -y at y = 0
                         {{0, 0}, {ey[0], ey[1]}, {ez[0], ez[1]}}};         // -x at x = 0
  double umin = 0, umax = 0, vmin = 0, vmax = 0;
  for (int i = 0; i < 8; ++i) {
    const double u = (i & 1 ? ex[0] : 0) + (i & 2 ? ey[0] : 0) + (i & 4 ? ez[0] : 0);
    const double v = (i & 1 ? ex[1] : 0) + (i & 2 ? ey[1] : 0) + (i & 4 ? ez[1] : 0);
    umin = std::min(umin, u), umax = std::max(umax, u), vmin = std::min(vmin, v), vmax = std::max(vmax, v);
  }
  std::vector<SpritePixel> out;
  for (int dv = int(std::floor(vmin - 1)); dv <= int(std::ceil(vmax + 1)); ++dv)
    for (int du = int(std::floor(umin - 1)); du <= int(std::ceil(umax + 1)); ++du) {
      const double pu = du + 0.5, pv = dv + 0.5;
      std::pair<double, int> in[3];
      int count = 0;
      for (int f = 0; f < 3; ++f) {
        const Face& F = faces[f];
        const double cross = F.a[0] * F.b[1] - F.a[1] * F.b[0];
        if (std::fabs(cross) < 1e-12) continue;
        const double qu = pu - F.o[0], qv = pv - F.o[1];
        const double alpha = (qu * F.b[1] - qv * F.b[0]) / cross, beta = (F.a[0] * qv - F.a[1] * qu) / cross;
        const double la = std::hypot(F.a[0], F.a[1]), lb = std::hypot(F.b[0], F.b[1]);
        const double ha = std::fabs(cross) / lb, hb = std::fabs(cross) / la;  // distance per unit alpha, beta
        const double depth = std::min({alpha * ha, (1 - alpha) * ha, beta * hb, (1 - beta) * hb});
        if (depth > -0.5) in[count++] = {depth, f};  // signed distance inside the face, in pixels
      }
      // Shallowest first: of the faces a cell draws, the one the pixel lies deepest in is written last.
      std::sort(in, in + count);
      for (int i = 0; i < count; ++i) out.push_back({du, dv, std::uint8_t(in[i].second)});
    }
  return out;
}

void draw_line(Image& img, double u0, double v0, double u1, double v1, Rgb c) {
  const int n = int(std::ceil(std::max(std::fabs(u1 - u0), std::fabs(v1 - v0)))) + 1;
  for (int i = 0; i <= n; ++i) {
    const double t = double(i) / n;
    img.set(int(std::floor(u0 + t * (u1 - u0))), int(std::floor(v0 + t * (v1 - v0))), c);
  }
}

std::string metres(double m) {
  char b[32];
  if (m >= 1) std::snprintf(b, sizeof b, "%g m", m);
  else if (m >= 0.01) std::snprintf(b, sizeof b, "%g cm", m * 100);
  else std::snprintf(b, sizeof b, "%g mm", m * 1000);
  return b;
}

std::string fixed(double v, int digits) {
  char b[40];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

// The largest scale-bar length (1, 2 or 5 times a power of ten metres) at most `max_m`.
double nice_length(double max_m) {
  const double p = std::pow(10.0, std::floor(std::log10(max_m)));
  for (double f : {5.0, 2.0, 1.0})
    if (f * p <= max_m * (1 + 1e-9)) return f * p;
  return p;
}

// Per row (y, z) of the map, the x range [lo, hi] that holds the boxes of occupied segments (none:
// lo > hi), so the scans skip what no occupied segment reaches. Left empty (full rows) for maps
// whose rows are too short to gain, or when listing the boxes' rows would cost more than a scan.
struct RowRanges {
  std::vector<std::uint32_t> lo, hi;
  bool empty() const { return lo.empty(); }
};

RowRanges occupied_rows(const Result& r) {
  RowRanges R;
  const Dims& d = r.dims;
  const std::size_t rows = d.ny * d.nz;
  if (d.nx < 32) return R;
  std::uint64_t work = 0;
  for (const Segment& s : r.segments)
    if (s.state == State::occupied && s.voxels > 0)
      work += std::uint64_t(s.bbox_max[1] - s.bbox_min[1] + 1) * (s.bbox_max[2] - s.bbox_min[2] + 1);
  if (work > 4 * std::uint64_t(rows)) return R;
  R.lo.assign(rows, std::numeric_limits<std::uint32_t>::max());
  R.hi.assign(rows, 0);
  for (const Segment& s : r.segments) {
    if (s.state != State::occupied || s.voxels == 0) continue;
    for (std::uint32_t z = s.bbox_min[2]; z <= s.bbox_max[2]; ++z)
      for (std::uint32_t y = s.bbox_min[1]; y <= s.bbox_max[1]; ++y) {
        const std::size_t i = y + d.ny * std::size_t(z);
        R.lo[i] = std::min(R.lo[i], s.bbox_min[0]);
        R.hi[i] = std::max(R.hi[i], s.bbox_max[0]);
      }
  }
  return R;
}

// Calls visit(x, y, z, label, faces) for every cell that can be seen, in an order where every cell
// comes after all it can hide: z ascending, then y and x descending (the view looks along +x, +y
// and -z). `cells` holds a label per cell of `d`, x fastest; `shown(l)` says whether label l is
// drawn. `faces` has bit 0 for a top face, 1 for a front (-y), 2 for a left (-x) face whose
// neighbour is not drawn; a cell with none is covered by its neighbours and skipped. A visit that
// returns false stops the walk (then false is returned).
template <class Shown, class Visit>
bool for_each_visible(const Dims& d, const std::uint32_t* cells, const RowRanges& ranges, const Shown& shown,
                      const Visit& visit) {
  const std::size_t nx = d.nx, plane = d.nx * d.ny;
  for (std::size_t z = 0; z < d.nz; ++z) {
    const bool top_layer = z + 1 == d.nz;
    for (std::size_t y = d.ny; y-- > 0;) {
      // (An index, not a row pointer: `row[x - nx]` would add a wrapped unsigned offset to the
      // pointer, undefined behaviour that UBSan reports.)
      const std::size_t row = nx * y + plane * z;
      std::size_t x_lo = 0, x_end = nx;  // x in [x_lo, x_end)
      if (!ranges.empty()) {
        const std::size_t i = y + d.ny * z;
        if (ranges.lo[i] > ranges.hi[i]) continue;
        x_lo = ranges.lo[i], x_end = std::size_t(ranges.hi[i]) + 1;
      }
      for (std::size_t x = x_end; x-- > x_lo;) {
        const std::size_t i = row + x;
        const std::uint32_t l = cells[i];
        if (!shown(l)) continue;
        const unsigned faces = (top_layer || !shown(cells[i + plane]) ? 1u : 0u) |
                               (y == 0 || !shown(cells[i - nx]) ? 2u : 0u) | (x == 0 || !shown(cells[i - 1]) ? 4u : 0u);
        if (faces && !visit(x, y, z, l, faces)) return false;
      }
    }
  }
  return true;
}

// Occupied segments by id (1) among all (0).
std::vector<std::uint8_t> occupied_table(const Result& r) {
  std::vector<std::uint8_t> t(r.segments.size(), 0);
  for (const Segment& s : r.segments)
    if (s.state == State::occupied && s.voxels > 0 && s.id < t.size()) t[s.id] = 1;
  return t;
}

// The projected area of a cube of edge e pixels, with the half pixel around each face: the
// pixels a cell's sprite writes, about.
double sprite_pixels(double e) { return 1.7 * (e + 1) * (e + 1); }

}  // namespace

double SceneProjection::u(double x, double y, double z) const {
  const Axes A = view_axes();
  return u0 + scale * (x * A.rx + y * A.ry + z * A.rz);
}

double SceneProjection::v(double x, double y, double z) const {
  const Axes A = view_axes();
  return v0 - scale * (x * A.ux + y * A.uy + z * A.uz);
}

SceneProjection scene_projection(const Result& r) {
  const Axes A = view_axes();
  double lo[3], hi[3];
  fit_box(r, lo, hi);
  double umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
  for (int i = 0; i < 8; ++i) {
    const double x = i & 1 ? hi[0] : lo[0], y = i & 2 ? hi[1] : lo[1], z = i & 4 ? hi[2] : lo[2];
    const double u = x * A.rx + y * A.ry + z * A.rz, v = -(x * A.ux + y * A.uy + z * A.uz);
    umin = std::min(umin, u), umax = std::max(umax, u), vmin = std::min(vmin, v), vmax = std::max(vmax, v);
  }
  SceneProjection P;
  P.scale = std::min({(kViewWidth - 2 * kMargin) / std::max(umax - umin, 1e-9),
                      (kViewHeight - 2 * kMargin) / std::max(vmax - vmin, 1e-9), kMaxScale});
  P.u0 = kViewX + kViewWidth / 2.0 - P.scale * (umin + umax) / 2;
  P.v0 = kViewY + kViewHeight / 2.0 - P.scale * (vmin + vmax) / 2;
  // Work: the visible cells times their sprites. A grid has at most as many visible cells as it
  // has cells, and, at any coarsening, at most as many as there are occupied voxels (a visible
  // coarse cell borders an empty block, so a voxel of its own borders empty space).
  std::uint64_t visible = 0;
  for (const Segment& s : r.segments)
    if (s.state == State::occupied) visible += s.voxels;
  const Dims& d = r.dims;
  const std::size_t longest = std::max({d.nx, d.ny, d.nz, std::size_t(1)});
  for (std::size_t k = 1;; ++k) {
    const double cells = double((d.nx + k - 1) / k) * double((d.ny + k - 1) / k) * double((d.nz + k - 1) / k);
    if (std::min(double(visible), cells) * sprite_pixels(P.scale * double(k)) <= kPixelBudget || k >= longest) {
      P.coarsen = k;
      break;
    }
  }
  return P;
}

Image render_scene(const Result& r, double voxel_size, const SceneOptions& o) {
  const Axes A = view_axes();
  const SceneProjection P = scene_projection(r);
  Image img(kSceneWidth, kSceneHeight, kWhite);
  const Dims& d = r.dims;
  const std::vector<std::uint8_t> occupied = occupied_table(r);
  std::vector<const Segment*> occ;
  for (const Segment& s : r.segments)
    if (s.state == State::occupied && s.voxels > 0) occ.push_back(&s);
  if (!o.title.empty()) draw_text(img, 6, 8, o.title.substr(0, (kSceneWidth - 12) / 6), kText);

  // The floor of the fitted box, faint, under everything.
  double lo[3], hi[3];
  fit_box(r, lo, hi);
  const double fx[4] = {lo[0], hi[0], hi[0], lo[0]}, fy[4] = {lo[1], lo[1], hi[1], hi[1]};
  auto draw_floor = [&] {
    for (int i = 0; i < 4; ++i)
      draw_line(img, P.u(fx[i], fy[i], lo[2]), P.v(fx[i], fy[i], lo[2]), P.u(fx[(i + 1) % 4], fy[(i + 1) % 4], lo[2]),
                P.v(fx[(i + 1) % 4], fy[(i + 1) % 4], lo[2]), kFaint);
  };
  draw_floor();
  std::size_t coarsened = 1;  // what was drawn as one cell

  if (occ.empty()) {
    const std::string t = "no occupied segment";
    draw_text(img, kViewX + (kViewWidth - text_width(t)) / 2, kViewY + kViewHeight / 2, t, kText);
  } else if (d.count() > 0 && r.labels.size() == d.count()) {
    // Voxel by voxel first: the bound on the visible voxels is loose (a solid block shows only its
    // surface), so try, and coarsen only when the sprites really pass the budget.
    std::size_t k = 1;
    std::vector<SpritePixel> sprite;
    // The sprite's pixels for each set of faces drawn (bits as `faces`), in the sprite's order,
    // and the box they cover: a cell drawn wholly inside the view needs no test per pixel.
    std::vector<SpritePixel> by_faces[8];
    int su0 = 0, su1 = 0, sv0 = 0, sv1 = 0;
    auto set_sprite = [&](double edge) {
      sprite = cube_sprite(A, P.scale, edge);
      for (unsigned f = 0; f < 8; ++f) {
        by_faces[f].clear();
        for (const SpritePixel& p : sprite)
          if (f >> p.face & 1u) by_faces[f].push_back(p);
      }
      su0 = sv0 = std::numeric_limits<int>::max(), su1 = sv1 = std::numeric_limits<int>::min();
      for (const SpritePixel& p : sprite)
        su0 = std::min(su0, p.du), su1 = std::max(su1, p.du), sv0 = std::min(sv0, p.dv), sv1 = std::max(sv1, p.dv);
    };
    set_sprite(1.0);
    double budget = P.coarsen > 1 ? kPixelBudget : std::numeric_limits<double>::infinity();
    std::uint32_t cached = kNone;
    Rgb shades[3];
    // Only the faces without a drawn neighbour: a covered face's pixels, rounded differently from
    // the neighbour's, would show through it as specks.
    auto draw = [&](std::size_t x, std::size_t y, std::size_t z, std::uint32_t l, unsigned faces) {
      if (l != cached) {
        const Rgb c = segment_colour(l);
        shades[0] = shade(c, kShadeTop), shades[1] = shade(c, kShadeFront), shades[2] = shade(c, kShadeLeft);
        cached = l;
      }
      const double fx = double(x * k), fy = double(y * k), fz = double(z * k);
      const int iu = int(std::lround(P.u0 + P.scale * (fx * A.rx + fy * A.ry + fz * A.rz)));
      const int iv = int(std::lround(P.v0 - P.scale * (fx * A.ux + fy * A.uy + fz * A.uz)));
      const std::vector<SpritePixel>& drawn = by_faces[faces & 7u];
      if (iu + su0 >= kViewX && iu + su1 < kViewX + kViewWidth && iv + sv0 >= kViewY && iv + sv1 < kViewY + kViewHeight) {
        std::uint8_t* at = img.rgb.data() + (std::size_t(iv) * std::size_t(img.width) + std::size_t(iu)) * 3;
        for (const SpritePixel& p : drawn) {
          std::uint8_t* q = at + (std::ptrdiff_t(p.dv) * img.width + p.du) * 3;
          const Rgb c = shades[p.face];
          q[0] = c.r, q[1] = c.g, q[2] = c.b;
        }
      } else {
        for (const SpritePixel& p : drawn) {
          const int u = iu + p.du, v = iv + p.dv;
          if (u >= kViewX && u < kViewX + kViewWidth && v >= kViewY && v < kViewY + kViewHeight) img.set(u, v, shades[p.face]);
        }
      }
      budget -= double(sprite.size());
      return budget > 0;
    };
    const std::uint32_t* labels = r.labels.data();
    const std::uint8_t* t = occupied.data();
    const std::size_t n = occupied.size();
    if (!for_each_visible(d, labels, occupied_rows(r), [t, n](std::uint32_t l) { return l < n && t[l]; }, draw)) {
      // Past the budget: start again on the coarser grid, whose work the bound does hold.
      k = coarsened = P.coarsen;
      set_sprite(double(k));
      budget = std::numeric_limits<double>::infinity();
      img.fill_rect(kViewX, kViewY, kViewWidth, kViewHeight, kWhite);
      draw_floor();
      // Cells of k^3 voxels, each holding the label of its topmost occupied voxel.
      const Dims c{(d.nx + k - 1) / k, (d.ny + k - 1) / k, (d.nz + k - 1) / k};
      std::vector<std::uint32_t> cells(c.count(), kNone);
      const RowRanges ranges = occupied_rows(r);
      for (std::size_t z = 0; z < d.nz; ++z)
        for (std::size_t y = 0; y < d.ny; ++y) {
          const std::uint32_t* row = labels + d.nx * (y + d.ny * z);
          std::uint32_t* crow = cells.data() + c.nx * (y / k + c.ny * (z / k));
          std::size_t x0 = 0, x1 = d.nx;
          if (!ranges.empty()) {
            const std::size_t i = y + d.ny * z;
            x0 = ranges.lo[i], x1 = ranges.lo[i] > ranges.hi[i] ? x0 : std::size_t(ranges.hi[i]) + 1;
          }
          for (std::size_t x = x0; x < x1; ++x) {
            const std::uint32_t l = row[x];
            if (l < occupied.size() && occupied[l]) crow[x / k] = l;
          }
        }
      for_each_visible(c, cells.data(), RowRanges{}, [](std::uint32_t l) { return l != kNone; }, draw);
    }
  }

  // Axes, bottom right of the view.
  const double ax = kViewX + kViewWidth - 50, ay = kViewY + kViewHeight - 24;
  const char* names[3] = {"x", "y", "z"};
  const double dirs[3][2] = {{A.rx, -A.ux}, {A.ry, -A.uy}, {A.rz, -A.uz}};
  for (int i = 0; i < 3; ++i) {
    const double eu = ax + 26 * dirs[i][0], ev = ay + 26 * dirs[i][1];
    draw_line(img, ax, ay, eu, ev, kText);
    draw_text(img, int(ax + 34 * dirs[i][0]) - 2, int(ay + 34 * dirs[i][1]) - 3, names[i], kText);
  }

  // Scale bar under the view: lengths across the picture (the view's horizontal is level in the
  // map, so it is not foreshortened).
  const double metres_per_pixel = voxel_size / P.scale;
  const double bar_m = nice_length(200 * metres_per_pixel);
  const int bar_px = std::max(1, int(std::lround(bar_m / metres_per_pixel)));
  const int bx = kViewX + 10, by = kViewY + kViewHeight + 14;
  img.fill_rect(bx, by, bar_px, 3, kText);
  img.fill_rect(bx, by - 4, 1, 11, kText);
  img.fill_rect(bx + bar_px - 1, by - 4, 1, 11, kText);
  draw_text(img, bx + bar_px + 8, by - 2, metres(bar_m) + " (across the picture)", kText);

  // Legend: the largest occupied segments with their colour, voxels and box size.
  const int lx = kViewX + kViewWidth + 10;
  int ly = kViewY;
  std::sort(occ.begin(), occ.end(), [](const Segment* a, const Segment* b) {
    return a->voxels != b->voxels ? a->voxels > b->voxels : a->id < b->id;
  });
  draw_text(img, lx, ly, occ.empty() ? "no occupied segment" : "largest segments", kText);
  ly += 16;
  const int digits = voxel_size >= 0.1 ? 1 : voxel_size >= 0.01 ? 2 : 3;
  for (std::size_t i = 0; i < std::min(o.legend, occ.size()); ++i) {
    const Segment& s = *occ[i];
    const Rgb c = segment_colour(s.id);
    img.fill_rect(lx, ly, 14, 14, shade(c, kShadeLeft));
    img.fill_rect(lx + 1, ly + 1, 12, 12, c);
    draw_text(img, lx + 20, ly, "id " + std::to_string(s.id) + ": " + std::to_string(s.voxels) + " voxels", kText);
    std::string size;
    for (int a = 0; a < 3; ++a)
      size += (a ? " x " : "") + fixed(double(s.bbox_max[a] - s.bbox_min[a] + 1) * voxel_size, digits);
    draw_text(img, lx + 20, ly + 10, size + " m", kText);
    ly += 28;
  }
  if (!occ.empty()) {
    draw_text(img, lx, ly, std::to_string(occ.size()) + " occupied segment" + (occ.size() == 1 ? "" : "s"), kText);
    ly += 10;
  }
  draw_text(img, lx, ly, "free, unknown: not drawn", kText);
  ly += 10;
  if (coarsened > 1)
    draw_text(img, lx, ly, "each " + std::to_string(coarsened) + " x " + std::to_string(coarsened) + " x " +
                               std::to_string(coarsened) + " voxels drawn as one", kText);
  return img;
}

}  // namespace occseg::render
