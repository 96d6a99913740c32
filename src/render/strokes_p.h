// Strokes (paper §6.3; mesh/vector_image.h) drawn over a rendered frame.
#pragma once

#include <span>

#include "render/raster_p.h"
#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::detail {

// Draws the strokes of `level` (in order) over `out`, the frame of `view`: each is the clamped
// cubic B-spline of its points (mesh/curves.h), `width` image pixels wide (scaled with the view),
// tapering linearly to zero over `taper` of its length at both ends, anti-aliased and composited
// source-over with straight alpha.
void draw_strokes(std::span<const Stroke> strokes, int level, const ViewTransform& view, Image8& out);
// The same for the pixels of `clip` only, `out` holding the view's rows from clip.y0 at full width
// (RasterOptions::clip): each pixel as draw_strokes() over the whole frame gives it.
void draw_strokes(std::span<const Stroke> strokes, int level, const ViewTransform& view,
                  const PixelRect& clip, Image8& out);

}  // namespace subvec::detail
