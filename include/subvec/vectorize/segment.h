// Stage 1 of vectorization, second source of features (paper §4: "If image segmentation (we use
// GrabCut) is performed to partition an image into regions, region boundaries are always closed
// and are also treated as features"). GrabCut from a user rectangle gives a foreground mask; its
// boundary becomes a closed feature at subpixel positions; Canny features that come near it are
// cut back so that no two feature constraints cross or run within a pixel of each other.
#pragma once

#include <cstdint>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/vectorize/features.h"

namespace subvec {

// A rectangle of whole pixels: columns x .. x + width - 1, rows y .. y + height - 1.
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
};

struct SegmentOptions {
  int iterations = 5;      // GrabCut iterations
  uint64_t seed = 0x5eed;  // GrabCut's GMM initialisation draws from cv::theRNG(), seeded with this
  // [1 2 1]/4 passes over the pixel-edge boundary. One keeps it within 0.4 px of GrabCut's
  // pixels; the fitted subdivision curve smooths the rest (more passes cut corners further).
  int smoothing_passes = 1;
  double clearance = 1.5;  // Canny feature parts closer than this to the boundary are cut, px
};

// A binary image: 1 inside the region, 0 outside; width * height values, rows top to bottom.
struct RegionMask {
  int width = 0, height = 0;
  std::vector<uint8_t> inside;

  bool at(int x, int y) const { return inside[size_t(y) * width + x] != 0; }
  int64_t area() const;
};

// Runs GrabCut with everything outside `rect` as background and everything inside as probable
// foreground, then cleans the result: opening and closing with a 3 x 3 square (no spikes or
// slits narrower than 3 px), the largest 4-connected component, holes filled. Deterministic: the
// caller's cv::theRNG() state is saved, seeded with `options.seed` and restored. Throws
// Error(kInvalidArgument) when `rect` is empty, leaves the image, covers all of it (GrabCut needs
// background samples) or when no foreground remains.
RegionMask segment_foreground(const Image8& image, const PixelRect& rect,
                              const SegmentOptions& options = {});

// The boundary of `mask` as features, in image coordinates: the crack between inside and outside
// pixels (corner cells cut diagonally, as marching squares at level 1/2), smoothed by
// `options.smoothing_passes` and resampled to about 1 px spacing. A region that stays off the image
// border gives one closed feature. Where it touches the border the boundary is the border itself,
// which is not a feature: the rest comes out as open features that end exactly on the border.
// Pieces shorter than 3 px are dropped. Their `contrast` is 0 (not measured) and they have no
// junction nodes.
std::vector<DetectedFeature> region_boundary_features(const RegionMask& mask,
                                                      const SegmentOptions& options = {});

// Cuts every part of `features` that passes within `clearance` px of a polyline of `boundary`:
// points on a segment that comes that close are removed and the feature is split there (a cut end
// is no junction). Pieces shorter than `min_length` are dropped. Afterwards no remaining segment is
// within `clearance` of the boundary, so the constraints of the dense mesh neither cross nor touch.
void clear_features_near(std::vector<DetectedFeature>& features,
                         const std::vector<DetectedFeature>& boundary, double clearance,
                         double min_length);

}  // namespace subvec
