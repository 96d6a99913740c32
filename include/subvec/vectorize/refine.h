// Stage 3b of vectorization (beyond the paper): data-dependent refinement of the simplified mesh.
//
// Simplification picks the control vertices by collapse cost; where each one ends up and which
// diagonal each quadrilateral takes can still be improved against the image. Both steps measure
// the squared error, over the pixel centres a triangle covers, of the linear interpolation of its
// corner colors: a cheap stand-in for the subdivided color field that the final fit (fit.h) makes.
//  - Edge flips (Dyn, Levin & Rippa, "Data dependent triangulations for piecewise linear
//    interpolation", 1990): a smooth interior edge is flipped when the two new triangles follow
//    the image better by at least `min_gain`; the largest gains go first, each triangle at most
//    once per pass.
//  - Vertex moves: one damped Gauss-Newton step per vertex on its position and its colors at
//    once, over the pixels of its one-ring, kept only when the ring's error falls. Smooth vertices
//    move freely, border vertices along the border; tears, corners and creases keep their
//    positions (so the feature curves do not change) and adapt only their colors. Every accepted step lowers the total error, no triangle becomes
// flipped or thinner than `min_area`, and the result does not depend on the thread count
// (vertices move in color classes of the vertex graph, a class at a time).
#pragma once

#include <atomic>
#include <string>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {

struct RefineOptions {
  // Rounds of vertex moves, each followed by flip passes; the first flips come before any move.
  // 0 leaves the mesh as it is.
  int rounds = 8;
  int flip_passes = 4;     // at most this many flip passes at a time (they stop when none flips)
  double min_gain = 0.01;  // a flip must lower its two triangles' error by this fraction
  double min_area = 0.5;   // square pixels every changed triangle keeps at least
  // No flip may make a triangle of shape quality (4 sqrt(3) area / sum of squared edges; 1 for
  // equilateral) under min_quality, and no move one under min_move_quality, unless one as poor
  // was already there. Slivers cost little error here but draw badly where a viewer rounds
  // vertices to whole pixels (poppler's PDF meshes, docs/export.md): the flip guard keeps the
  // pdftoppm median of the photographs at 0.73 instead of 0.88. The move guard is off by
  // default: 0.25 cost apple its floor (4.785), and 0.1 made the pyramid's high-frequency
  // energy on rocket dip at eta 0.1 (docs/vectorize.md, "Refinement").
  double min_quality = 0.25;
  double min_move_quality = 0;
  double max_step = 2.0;   // pixels a vertex moves at most per round
  // A vertex's Gauss-Newton step is tried this much longer first, then halved until the error
  // falls (successive over-relaxation: the sweeps converge faster). In [1, 2].
  double over_relaxation = 1.5;
  int threads = 0;         // <= 0: all cores; the result does not depend on it
  // When set and true, refine_mesh() throws Error(kCancelled) at its next flip pass or vertex
  // class (the mesh is then part-refined, still valid).
  const std::atomic<bool>* cancel = nullptr;
};

struct RefineStats {
  int flips = 0;
  int moves = 0;          // vertex moves kept, over all rounds
  double error_before = 0;  // the interpolation error summed over all pixels and channels
  double error_after = 0;
};

// Refines a valid single-level mesh in place (it stays valid). The colors it starts from are the
// corner colors after simplification (quadric-optimal); smooth vertices' colors change with their
// moves. `image` covers the mesh domain. Throws Error(kInvalidArgument) for options out of range.
// Throws Error(kInvalidArgument) naming the first field out of range, prefixed by `prefix`;
// refine_mesh() calls it.
void validate(const RefineOptions& options, const std::string& prefix = {});

RefineStats refine_mesh(ControlMesh& mesh, const Image8& image, const RefineOptions& options = {});

}  // namespace subvec
