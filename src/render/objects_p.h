// Objects (mesh/vector_image.h, edit/objects.h) drawn over a rendered frame of their level.
#pragma once

#include "render/raster_p.h"
#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::detail {

// Draws the visible objects of `level`, bottom to top, over `out` (the frame of `view`, 3 or 4
// channels): each object's mesh refined `depth` levels and pushed to the limit, rasterized into
// an RGBA layer whose alpha is its coverage (its boundary supersampled when `antialias`), and
// composited source-over, then its strokes drawn over it. With `clip`, only those pixels, `out` holding the view's rows from
// clip.y0 at full width (RasterOptions::clip); each pixel as the whole frame has it.
void draw_objects(const VectorImage& image, int level, const ViewTransform& view, int depth,
                  bool antialias, int threads, const PixelRect* clip, Image8& out);

}  // namespace subvec::detail
