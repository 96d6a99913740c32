// Stage 2 of vectorization (paper §4): the dense feature-aligned control mesh. One vertex per
// pixel centre, vertices along the image border, and the feature polylines at their subpixel
// positions, as a constrained Delaunay triangulation whose constraints are the features. Feature
// edges become tears, the border a crease, the 4 corners corners; every corner of every triangle
// gets the image color sampled on its own side of any tear.
#pragma once

#include <vector>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/vectorize/features.h"

namespace subvec {

struct InitialMeshOptions {
  double min_grid_distance = 0.5;  // grid vertices closer than this to a feature are dropped, px
  double side_offset = 0.75;       // tear-side colors are sampled this far into each side, px
  // 1: a vertex at every pixel centre. 2 (or 4): away from the features, one vertex per 2 x 2
  // (4 x 4) block at its centre (for 2 a pixel corner, whose bilinear color is the block's mean);
  // blocks with a pixel within `fine_band` of a feature keep their pixel centres. 0: automatic in
  // vectorize() (4 for images of 2^21 pixels or more when the target is at most 1/64 of the
  // pixels, else 2 from 2^18 pixels (512 x 512) when it is at most 1/16, else 1); here, 1.
  int grid_step = 0;
  double fine_band = 3.0;
};

// Returns a valid single-level mesh (validate_level holds) over the image domain.
ControlMesh build_initial_mesh(const Image8& image, const std::vector<DetectedFeature>& features,
                               const InitialMeshOptions& options = {});

}  // namespace subvec
