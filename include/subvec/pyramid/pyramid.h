// The vector image pyramid (paper §6.4): filtering and enhancement of a multiresolution vector
// image through its inter-level details.
//
// Every level l >= 1 records how it was made from level l - 1 (ControlMesh::parent_vertices and
// collapses; vectorize/levels.h). Replaying that record gives, for every vertex removed on the way down, the
// coarse neighbourhood it was removed from, and its detail: the difference from its prediction
// R(v) = sum w_i v_i over that neighbourhood with Fujiwara weights w_i ~ 1 / |v' - v'_i| (eq. 3).
// Positions are predicted from the one-ring (from the two neighbours along the chain or the border
// side for a tear or border vertex) with the weights taken at the ring's centroid (v' itself is
// what is being predicted), and their detail is stored in the local frame of the prediction and
// the kept vertex; colors are predicted per wedge, from the same side of any kept tear (along the
// chain for a tear vertex), by the least-squares affine fit of the neighbours with eq. 3's weights
// at v's reconstructed position (the paper takes their weighted mean; the fit reproduces linear
// ramps), and their detail is per channel. The other two steps between levels are details as well: the merge of a dropped
// feature's seam (each side's color minus the mean) and the color refit (each kept color value
// minus the coarse level's). The details are a function of the levels, computed when needed, so
// they follow any edit of a level.
//
// Reconstruction starts at the coarsest level and replays the steps in reverse with
// v' = R(v) + eta d(v) (eq. 4), eta per band (band b is the step from level b - 1 to level b) and
// per channel. eta = 1 gives the levels back; eta < 1 smooths and eta > 1 enhances. Kept features
// stay tears: their sides are predicted only from their own side, and the color details of their
// vertices and one-ring (a quarter of the second ring's) are kept at every eta, so the rendered
// edge profile across them stays (docs/levels.md, "Edge profiles").
#pragma once

#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec {

struct FilterOptions {
  // eta per band, finest first (band 1 = between levels 0 and 1). A list shorter than the bands
  // repeats its last value; empty means 1 (unchanged).
  std::vector<double> geometry_eta;
  std::vector<double> color_eta;
};

struct FilterReport {
  int bands = 0;
  int restored_vertices = 0;  // vertices whose filtered position would have flipped a triangle
};

// Whether `image` has a pyramid: two or more levels, each above level 0 with its record.
bool has_pyramid(const VectorImage& image);

// Filters every level of `image` (the coarsest stays as it is) and returns the result, a normal
// vector image with the same levels, records and strokes (it can be filtered again). Positions
// whose filtered value would flip a triangle move back toward the unfiltered position, as far as
// needed. Throws Error(kInvalidArgument) when `image` has no pyramid, for more eta values than
// bands or non-finite ones, and Error(kInvalidMesh) when a record does not make its level.
VectorImage filter(const VectorImage& image, const FilterOptions& options, FilterReport* report = nullptr);

}  // namespace subvec
