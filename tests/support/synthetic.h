// Synthetic vector images for tests and benchmarks: a jittered grid triangulation with closed and
// open tear features and a smooth random color field that jumps across the tears.
#pragma once

#include <cstdint>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::test {

struct SyntheticOptions {
  int width = 512, height = 512;
  int vertices = 3000;   // approximate control vertex count (a grid of about this many)
  uint32_t seed = 1;     // colors and jitter
  bool features = true;  // two closed tears (circles) and two open ones (an arc and a segment)
  double jitter = 0.2;   // interior non-feature vertices move up to this fraction of a cell
};

// A valid one-level VectorImage: border vertices on the border, the 4 corners present, positive
// triangles tiling the domain, features that are chains of interior edges, face-varying colors
// split along the features (corners on each side of a tear use that side's color value; an open
// tear's jump fades to zero at its endpoints). Without features, color i belongs to vertex i.
VectorImage make_synthetic_image(const SyntheticOptions& options = {});

// A photograph-like RGB image: a disk (a tear once vectorized) of radius h/4 at the centre over a
// smooth background with a ripple, so that vertex positions matter; w x h.
Image8 textured_disk(int w, int h);

}  // namespace subvec::test
