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

#include <optional>
#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec {

struct FilterOptions {
  // eta per band, finest first (band 1 = between levels 0 and 1). A list shorter than the bands
  // repeats its last value; empty means 1 (unchanged).
  std::vector<double> geometry_eta;
  std::vector<double> color_eta;
  // Filter this object (edit/objects.h) alone, through its own pyramid (below); default: the levels.
  std::optional<int> object = std::nullopt;
};

// An object's mesh has no levels of its own. It is filtered through a pyramid made from itself:
// filter_bands(image, object) coarser meshes, each removing half the smooth vertices left,
// shortest edge first; its boundary, creases and tears stay (so it still fits its hole in the
// level at every eta), and band b takes band b's eta. The same own pyramid fills a gap in the
// levels' pyramid: a level whose record an edit dropped (make_object cuts its level) is not made
// from the one below it any more, so that one is filtered through its own pyramid, with the bands
// from the gap up.
inline constexpr int kObjectBands = 2;  // at least, or as many as the image has

struct FilterReport {
  int bands = 0;
  int restored_vertices = 0;  // vertices whose filtered position would have flipped a triangle
};

// Whether `image` has a pyramid: two or more levels, each above level 0 with its record.
bool has_pyramid(const VectorImage& image);

// How many bands filter() takes eta values for: the levels' (levels - 1), or an object's
// (kObjectBands at least).
int filter_bands(const VectorImage& image, std::optional<int> object = std::nullopt);

// Filters every level of `image` (the coarsest stays as it is), or with options.object that object
// alone, and returns the result, a normal vector image with the same levels, records, objects and
// strokes (it can be filtered again). Positions whose filtered value would flip a triangle move
// back toward the unfiltered position, as far as needed. Throws Error(kInvalidArgument) when
// `image` has one level (without an object), for an object out of range, more eta values than
// bands or non-finite ones, and Error(kInvalidMesh) when a record does not make its level.
VectorImage filter(const VectorImage& image, const FilterOptions& options, FilterReport* report = nullptr);

}  // namespace subvec
