// Stage 3 of vectorization (paper §4, "Mesh simplification"): greedy edge collapses ordered by a
// quadric error metric in 5D (x, y, r, g, b; colors as height fields, Garland & Heckbert) with
// the paper's constraints, and after every collapse along a feature a local least-squares refit of
// the feature's control vertices so that the subdivided limit curve follows the detected feature
// (eq. 1); a collapse that leaves the curve more than `max_feature_error` from it is rolled back.
#pragma once

#include <atomic>

#include "subvec/mesh/vector_image.h"

namespace subvec {

struct SimplifyOptions {
  int target_vertices = 0;          // stop when this many control vertices remain
  double max_feature_error = 1.0;   // pixels
  double color_scale = 2.0;         // colors enter the quadrics as color_scale * (0..255)
  int threads = 0;                  // <= 0: all cores; the result does not depend on it
  // When set and true, simplify() stops within a few thousand collapses and throws
  // Error(kCancelled), leaving the mesh as it was.
  const std::atomic<bool>* cancel = nullptr;
};

struct SimplifyStats {
  int collapses = 0;
  int rejected_topology = 0;  // link condition, flips, constraints
  int rejected_feature = 0;   // refit farther than max_feature_error
  double max_feature_error = 0;  // largest parametric distance of a refit curve to its feature
};

// Simplifies a valid single-level mesh in place (it stays valid). The feature chains' initial
// vertex positions are the detected feature polylines that refitting follows. Colors are left at
// the quadric-optimal values; the global color fit (fit.h) replaces them. Throws Error(kCancelled)
// when options.cancel is set.
SimplifyStats simplify(ControlMesh& mesh, int width, int height, const SimplifyOptions& options);

}  // namespace subvec
