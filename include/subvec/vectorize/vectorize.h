// Vectorization of a photograph (paper §4): features -> dense feature-aligned mesh -> constrained
// QEM simplification with curve refitting -> data-dependent refinement -> global least-squares color
// fit.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/vectorize/features.h"
#include "subvec/vectorize/fit.h"
#include "subvec/vectorize/initial_mesh.h"
#include "subvec/vectorize/refine.h"
#include "subvec/vectorize/segment.h"
#include "subvec/vectorize/simplify.h"

namespace subvec {

struct VectorizeOptions {
  double ratio = 0.01;   // control vertices as a fraction of the pixel count
  int vertices = 0;      // > 0: an absolute vertex count instead of `ratio`
  FeatureOptions features;
  // GrabCut from this rectangle: the foreground's boundary becomes a feature (closed unless the
  // foreground touches the image border), and Canny features are cut back from it (segment.h).
  std::optional<PixelRect> segment;
  SegmentOptions segment_options;
  InitialMeshOptions initial_mesh;
  double max_feature_error = 1.0;  // pixels (simplification rolls back collapses beyond it)
  RefineOptions refine;            // data-dependent flips and vertex moves (refine.h)
  ColorFitOptions fit;
  int threads = 0;       // <= 0: all cores; the result does not depend on it
  // Called with a stage name and the fraction of the whole job done (0..1).
  std::function<void(const std::string& stage, double fraction)> progress;
};

struct StageTime {
  std::string stage;
  double seconds = 0;
};

struct VectorizeReport {
  int vertices = 0, triangles = 0, features = 0, tear_vertices = 0;
  double fit_rms = 0;
  std::vector<StageTime> stages;  // [segment,] features, mesh, simplify, refine, fit
  SimplifyStats simplify;
  RefineStats refine;
  // The detected polyline each output feature follows (same order as the mesh's features).
  std::vector<std::vector<Vec2>> feature_targets;
  // With a segment rectangle: the cleaned GrabCut foreground, and the ids of the mesh features
  // that follow its boundary.
  RegionMask segment_mask;
  std::vector<int32_t> segment_feature_ids;
};

// Vectorizes an RGB image into a one-level vector image of the same size. Throws
// Error(kInvalidArgument) for options out of range.
VectorImage vectorize(const Image8& image, const VectorizeOptions& options = {}, VectorizeReport* report = nullptr);

}  // namespace subvec
