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
  // 1: a vertex at every pixel centre. 2, 4 or 8: away from the features, a quadtree of blocks
  // from step x step pixels down: a block is one vertex at its centre (a pixel corner; for 2 x 2 its
  // bilinear color is the block's mean) unless it has a pixel within `fine_band` of a feature or
  // its centre is within min_grid_distance of one; then it is its four quarters, down to the pixel
  // centres. 0: automatic in vectorize() (automatic_grid_step(), vectorize.h); here, 1.
  int grid_step = 0;
  double fine_band = 0.5;
};

// Whether `step` is a grid step InitialMeshOptions accepts: 0 (automatic), 1, 2, 4 or 8.
constexpr bool valid_grid_step(int step) { return step >= 0 && step <= 8 && (step & (step - 1)) == 0; }

// Returns a valid single-level mesh (validate_level holds) over the image domain.
ControlMesh build_initial_mesh(const Image8& image, const std::vector<DetectedFeature>& features,
                               const InitialMeshOptions& options = {});

}  // namespace subvec
