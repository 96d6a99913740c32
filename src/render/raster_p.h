// The rasterizer core: draws a RefinedMesh (limit positions, per-corner limit colors) into an
// output raster. The Renderer (renderer.cpp) chooses what to refine; this file only draws.
//
// Design note. Refined triangles are tiny (about 1-3 output pixels each), so the per-triangle
// setup dominates and everything is integer and branch-light:
//  - vertices are snapped once per frame to 24.8 fixed point in output pixels;
//  - coverage is tested with exact integer edge functions at pixel centres under a top-left fill
//    rule, so a sample on an edge shared by two triangles belongs to exactly one of them, and a
//    sample on a shared vertex to exactly one triangle of the fan;
//  - colors are the barycentric (Gouraud) interpolation of the three corner colors;
//  - triangles with at most 4 x 2 candidate centres (nearly all) are tested, shaded and drawn four
//    at a time in SIMD lanes without data-dependent branches; the others, and the subsamples, one
//    by one. Both give the same bytes.
// The only discontinuities of the limit color field are the tears (and the image border when the
// window leaves the image), so anti-aliasing is local: the pixels crossed by refined tear / border
// segments are marked, and inside those pixels the same triangle pass also tests a 4x4 grid of
// subsamples under the same fill rule; a marked pixel resolves to the mean of its subsamples.
// Work is split into horizontal bands (a multiple of the 8x8 mark tiles); triangles are binned per
// band in triangle order, and every sample is written by exactly one triangle, so the output is
// byte-identical whatever the thread count or band height.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec::detail {

// Image coordinates to output pixel coordinates: ((x - x0) * sx, (y - y0) * sy). Output pixel
// (i, j) is the unit square at (i, j) with its sample at the centre (i + 0.5, j + 0.5).
struct ViewTransform {
  double x0 = 0, y0 = 0;  // window origin in image coordinates
  double sx = 1, sy = 1;  // output pixels per image pixel
  int width = 0, height = 0;

  std::array<double, 2> to_output(double x, double y) const {
    return {(x - x0) * sx, (y - y0) * sy};
  }
};

// One overlay layer: anti-aliased segments and dots (output pixel coordinates) of one color.
// Coverage within a layer is the maximum over its primitives (joints are not drawn twice); layers
// are composited in order with `opacity`.
struct OverlayLayer {
  std::array<uint8_t, 3> color{255, 255, 255};
  float opacity = 1;
  float half_width = 0.5f;                     // segments: half the line width, pixels
  std::vector<std::array<float, 4>> segments;  // x0, y0, x1, y1
  std::vector<std::array<float, 3>> dots;      // x, y, radius
};

// Triangles [begin, end) of a RefinedMesh and the bounding box of their vertices in image
// coordinates.
struct TriangleBlock {
  int32_t begin, end;
  float x0, y0, x1, y1;
};

// A rectangle of a view's output pixels: columns [x0, x1), rows [y0, y1).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

struct RasterOptions {
  int channels = 3;               // 3: RGB; 4: RGBA, uncovered samples transparent
  bool antialias = true;          // supersample pixels crossed by tear edges
  bool antialias_border = false;  // ... and by border edges (when the window leaves the image)
  int threads = 1;                // resolved thread count (>= 1)
  // Ascending, disjoint blocks covering the triangles to draw, small ones (tens of triangles) for
  // good binning; empty: all triangles, in blocks of 64 bounded per frame. A caller that keeps a
  // refinement across frames keeps its blocks too, and blocks out of the view cost nothing.
  std::span<const TriangleBlock> blocks;
  // Draw only these pixels of the view (a tile, renderer.cpp's render_strips): `out` then holds
  // the clip's rows at the view's full width (view.width x (y1 - y0), row 0 = view row y0), is
  // neither cleared nor reallocated, and only the clip's pixels are written. Every pixel comes out
  // as the unclipped frame has it, provided the mesh holds every triangle (and tear or border
  // edge) that meets the clip, and the overlays every primitive near it.
  std::optional<PixelRect> clip;
};

// A vertex in output pixels, 24.8 fixed point.
struct Fixed {
  int32_t x, y;
};

// A block as binned for one frame: pixel columns [x0, x1] and rows [y0, y1] of its bounding box
// (y0 > y1: culled).
struct Unit {
  int32_t begin, end;
  int32_t x0, x1, y0, y1;
};

// Buffers reused from frame to frame (a Renderer keeps one); contents are scratch.
struct RasterScratch {
  std::vector<Fixed> fixed;
  std::vector<Unit> units;
  std::vector<int64_t> band_begin;
  std::vector<int32_t> binned;
};

Image8 rasterize(const RefinedMesh& mesh, const ViewTransform& view, const RasterOptions& options,
                 std::span<const OverlayLayer> overlay = {}, RasterScratch* scratch = nullptr);
// The same into `out`, whose memory is reused when it already has the size (a redraw then
// allocates nothing: fresh pages cost more than the drawing of a 4K frame's last tenth).
void rasterize_into(const RefinedMesh& mesh, const ViewTransform& view, const RasterOptions& options,
                    std::span<const OverlayLayer> overlay, RasterScratch* scratch, Image8& out);

// Composites overlay layers over a finished frame (what rasterize() does band by band), for frames
// drawn elsewhere (the GPU path).
void draw_overlay(Image8& out, std::span<const OverlayLayer> overlay, int threads);
// The same for the pixels of `clip` only, `out` holding the view's rows from clip.y0 (as
// RasterOptions::clip).
void draw_overlay_clipped(Image8& out, const PixelRect& clip, std::span<const OverlayLayer> overlay);

// Test hook: runs the coverage traversal of rasterize() over every triangle and counts how many
// triangles claim each sample. Returns #H*W counts of the pixel-centre samples, or with
// `subsamples` #H*W*16 counts of the 4x4 subsamples of every pixel (row-major within the pixel).
std::vector<int32_t> sample_coverage(const RefinedMesh& mesh, const ViewTransform& view,
                                     bool subsamples);

}  // namespace subvec::detail
