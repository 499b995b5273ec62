// scene.png: the occupied segments of a segmentation as shaded voxels in an oblique view from
// above, one colour per segment (occseg::segment_colour, as in every other output), free and
// unknown space left out, with a scale bar in metres, the axes and a legend of the largest
// segments. Drawn in software (a painter's algorithm over the visible faces), written with the
// PNG writer of render_png.
//
// The view (docs/cli.md, "The 3D picture"): orthographic, from azimuth 30 degrees (the camera
// on the -y side, turned 30 degrees towards -x) and 35 degrees above the horizon. With p a point
// in voxel units (x, y, z), R = (cos a, -sin a, 0) and U = (sin a sin e, cos a sin e, cos e), it
// is drawn at u = u0 + s (p . R), v = v0 - s (p . U) (pixels, v down). s and (u0, v0) fit the
// box of the occupied segments (the whole map when there is none) into the view, centred.
// Only three faces of a voxel can be seen: +z (top, full colour), -y (front, 0.80) and -x
// (left, 0.62), each a shade of the segment's colour (render::shade).
#pragma once
#include <cstddef>
#include <string>

#include "occseg/result.hpp"
#include "render_png.hpp"

namespace occseg::render {

struct SceneOptions {
  std::string title;        // "" for none
  std::size_t legend = 8;   // the largest occupied segments listed
};

// Fixed picture size and the view's rectangle in it (the legend is on its right).
constexpr int kSceneWidth = 960, kSceneHeight = 720;
constexpr int kViewX = 6, kViewY = 30, kViewWidth = 700, kViewHeight = 640;
constexpr double kSceneAzimuthDeg = 30, kSceneElevationDeg = 35;
constexpr double kShadeTop = 1.0, kShadeFront = 0.80, kShadeLeft = 0.62;

// The projection of a map: voxel units to pixels, and the coarsening that keeps the work bounded:
// `coarsen` voxels along each axis drawn as one cell (occupied when any of its voxels is), the
// smallest for which min(occupied voxels, cells) sprites fit the pixel budget; 1 for all but maps
// of millions of occupied voxels. render_scene draws voxel by voxel all the same while the
// sprites it really draws (the visible voxels') stay within the budget, and only past it the
// coarsened grid.
struct SceneProjection {
  double scale = 1;          // pixels per voxel edge
  double u0 = 0, v0 = 0;     // where the voxel corner (0, 0, 0) is drawn
  std::size_t coarsen = 1;
  double u(double x, double y, double z) const;
  double v(double x, double y, double z) const;
};

// The projection scene.png uses for this result (fit and coarsening as described above).
SceneProjection scene_projection(const Result& r);

// Draws the picture; voxel_size (metres) sizes the scale bar and the legend's boxes.
Image render_scene(const Result& r, double voxel_size, const SceneOptions& options);

}  // namespace occseg::render
