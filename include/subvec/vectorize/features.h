// Stage 1 of vectorization (paper §4): curvilinear features. Canny edges, thinned to one pixel,
// linked into chains that junctions split, spurs pruned, small gaps bridged, then located at
// subpixel accuracy (the gradient-magnitude maximum along the edge normal).
#pragma once

#include <string>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {

struct FeatureOptions {
  double blur_sigma = 1.0;       // Gaussian pre-smoothing, pixels
  // Canny thresholds relative to the image's own gradient statistics: the high threshold is this
  // quantile of the gradient magnitude, but at least `min_high_threshold` (gray levels per pixel)
  // so that flat or noisy images do not sprout features.
  double high_quantile = 0.85;
  double min_high_threshold = 10.0;
  double low_ratio = 0.45;       // low threshold = low_ratio * high threshold
  double min_length = 20.0;      // shortest feature kept, pixels
  double spur_length = 4.0;      // branches shorter than this at a junction are pruned
  double max_gap = 2.5;          // endpoints closer than this are bridged
};

struct DetectedFeature {
  std::vector<Vec2> points;  // subpixel polyline, ~1 px spacing; closed: front() == back()
  double length = 0;         // pixels
  double contrast = 0;       // mean gradient magnitude across the feature, gray levels per pixel
  int start_node = -1;       // junction id shared with other features ending there, or -1
  int end_node = -1;
  bool closed() const { return points.size() > 2 && points.front() == points.back(); }
};

// Throws Error(kInvalidArgument) naming the first field out of range, prefixed by `prefix`
// ("features." from validate(VectorizeOptions)); detect_features() calls it.
void validate(const FeatureOptions& options, const std::string& prefix = {});

std::vector<DetectedFeature> detect_features(const Image8& image, const FeatureOptions& options = {});

}  // namespace subvec
