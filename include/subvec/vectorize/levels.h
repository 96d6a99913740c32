// Levels of abstraction (paper §5). Features are ranked by saliency S(f) = P(f) + w C(f) and
// grouped uniformly into L subsets; level 0 is the finest mesh with every feature, and level l is
// made from level l-1 by dropping the least salient subset still present (the seams close: the
// two colors of each tear vertex merge into their mean), simplifying away a share of the vertices
// by half-edge collapses (5D quadric error; vertices of the kept features only along their chain,
// within max_feature_error of it; border vertices along their side; corners stay), then refitting
// every color to the image (vectorize/fit.h). Each level records how it was made
// (ControlMesh::parent_vertices, collapses), which the vector image pyramid replays (pyramid.h).
//
// Units of eq. 2: P(f) is the length of the feature's limit curve in pixels and C(f) the mean,
// over points 1 pixel apart along it, of |I(p + n) - I(p - n)| / 2 (RGB Euclidean norm on the
// 0-255 scale, n the unit normal), in color levels per pixel. A 100-pixel feature across a jump of
// 50 levels then scores 100 + 2 x 25 = 150 with w = 2: length dominates, contrast separates
// features of similar length (as in the paper, whose default w is 2).
#pragma once

#include <atomic>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/vectorize/fit.h"

namespace subvec {

// S(f) = P(f) + w C(f) of one curve (a polyline of the limit curve, ~1 px or finer), measured on
// `raster` as described above. Edit's stylization uses the same measure on a rendered level.
double curve_saliency(std::span<const Vec2> curve, const Image8& raster, double weight);

// S(f) of every feature of `mesh` (the limit curve of its whole chain, clamped at its ends),
// measured on `raster`, which has the mesh's image size.
std::vector<double> measure_saliency(const ControlMesh& mesh, const Image8& raster, double weight);

struct LevelOptions {
  int levels = 3;                  // L: level 0 plus L - 1 coarser ones
  double saliency_weight = 2;      // w in eq. 2
  double reduction = 0.5;          // share of the vertices each level removes
  double max_feature_error = 1.0;  // pixels: kept chains stay this close to the previous level's
  double color_scale = 2.0;        // colors enter the quadrics as color_scale * (0..255)
  // (feature id, level) overrides: the feature is present in levels 0 .. level and no coarser.
  std::vector<std::pair<int32_t, int>> feature_levels;
  ColorFitOptions fit;             // the color refit of each new level
  // When set and true, build_levels() throws Error(kCancelled) before its next level or inside
  // that level's color refit (which takes this flag when fit.cancel is null).
  const std::atomic<bool>* cancel = nullptr;
};

struct LevelReport {
  std::vector<int> vertices, features;      // per level
  std::vector<double> seconds;              // per level (0 for level 0)
  std::vector<int> feature_level;           // per feature of level 0: the coarsest level it is in
};

// The coarsest level each feature of `mesh` reaches: saliencies sorted in descending order (ties
// by id) and cut into `levels` equal groups, the most salient group reaching level levels - 1;
// then the overrides. Throws Error(kInvalidArgument) for an override naming no feature or a level
// outside 0 .. levels - 1.
std::vector<int> assign_feature_levels(const ControlMesh& mesh, const std::vector<double>& saliency,
                                       int levels, const std::vector<std::pair<int32_t, int>>& overrides);

// Replaces levels 1 and up of `image` by `options.levels - 1` coarser levels built from level 0
// against `photo` (the raster image it was vectorized from, of the same size). Stores each
// feature's saliency in level 0 when it has none. Deterministic. Throws Error(kInvalidArgument)
// for options out of range.
// Throws Error(kInvalidArgument) naming the first field out of range, prefixed by `prefix` (its
// color refit's fields as prefix + "fit."); build_levels() calls it.
void validate(const LevelOptions& options, const std::string& prefix = {});

void build_levels(VectorImage& image, const Image8& photo, const LevelOptions& options = {},
                  LevelReport* report = nullptr);

}  // namespace subvec
