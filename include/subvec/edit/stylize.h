// Abstraction and stylization (paper §6.3): strokes along the features of one level inside a
// region of interest. Features whose saliency reaches a threshold always get a stroke; those below
// it get one at random (a seeded generator, so the result is a function of the options). A stroke
// follows the feature's limit curve exactly (its points are the feature chain, mesh/curves.h), is
// wider for longer features and tapers linearly at both ends. Strokes are vector paths stored in
// the image (VectorImage::strokes), drawn over the colors by the renderer.
//
// Saliency (paper eq. 2): S(f) = P(f) + w C(f), with P(f) the length of the feature's limit curve
// in pixels and C(f) the mean contrast across it, w = 2 by default. A feature's stored saliency is
// used when it is non-zero; otherwise it is computed from the vector image itself: the level is
// rendered at 1x (without strokes) and C(f) is the mean, over points 1 pixel apart along the curve,
// of the central-difference gradient magnitude across it, |I(p + n) - I(p - n)| / 2 (RGB Euclidean
// norm on the 0-255 scale, n the unit normal), in color units per pixel.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec {

// An axis-aligned rectangle in image coordinates.
struct Rect {
  double x = 0, y = 0, width = 0, height = 0;
};

struct StylizeOptions {
  int level = 0;
  // The object whose features are stroked (edit/objects.h), into its own strokes (Object::strokes),
  // which move with it; `level` is then the object's. Default: the level's own mesh.
  std::optional<int> object = std::nullopt;
  std::optional<Rect> roi = std::nullopt;  // region of interest; default: the whole image (and, for an
                                           // object, its control points' bounding box)
  std::optional<double> threshold = std::nullopt;  // saliency threshold; default: the median over the region
  uint64_t seed = 1;                 // for the features below the threshold
  double probability = 0.3;          // chance that a feature below the threshold gets a stroke
  double contrast_weight = 2;        // w in S(f) = P(f) + w C(f)
  float min_width = 1.0f;            // stroke width of a very short feature, pixels at scale 1
  float max_width = 3.5f;            // ... reached at full_width_length
  double full_width_length = 0;      // pixels; 0: half the larger side of the image
  Color color{20, 20, 20};
  float taper = 0.25f;               // fraction of the length over which each end tapers
};

struct StylizeReport {
  double threshold = 0;  // the threshold used
  int in_region = 0;     // features with at least half their curve inside the region
  int above = 0;         // ... with saliency >= threshold (all stroked)
  int chosen = 0;        // ... below it and chosen at random
  int strokes = 0;       // strokes made (a feature split at corners gives one per piece)
  int replaced = 0;      // strokes of the level in the region that apply_stylize removed
};

// Saliency of every feature of `level`: the stored value where non-zero, else eq. 2 as above.
std::vector<double> feature_saliency(const VectorImage& image, int level,
                                     double contrast_weight = 2);

// The strokes for `options` (not added to the image). Deterministic: the same image and options
// give the same strokes. Throws Error(kInvalidArgument) for a level or object out of range, an empty or
// non-finite region, a negative or non-finite threshold, a probability outside [0, 1] or
// non-positive widths.
std::vector<Stroke> stylize(const VectorImage& image, const StylizeOptions& options,
                            StylizeReport* report = nullptr);

// Stylizes `image` in place, the one policy of `subvec stylize`, the editor's Stylize and the
// Python module: the strokes of options.level (or of options.object) with at least half their
// points in the region are replaced by the ones stylize() makes; other strokes stay. So stylizing twice gives the same
// image as once, and a second region adds to the first.
StylizeReport apply_stylize(VectorImage& image, const StylizeOptions& options);

}  // namespace subvec
