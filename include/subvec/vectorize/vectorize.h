// Vectorization of a photograph (paper §4): features -> dense feature-aligned mesh -> constrained
// QEM simplification with curve refitting -> data-dependent refinement -> global least-squares color
// fit -> levels of abstraction (§5). One job, one parameter struct: every front end (CLI, batch,
// server, Python) starts from VectorizeOptions{}, fills the fields its arguments name, and calls
// validate(), whose rules and messages are the only ones.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/vectorize/features.h"
#include "subvec/vectorize/fit.h"
#include "subvec/vectorize/initial_mesh.h"
#include "subvec/vectorize/levels.h"
#include "subvec/vectorize/refine.h"
#include "subvec/vectorize/segment.h"
#include "subvec/vectorize/simplify.h"

namespace subvec {

// The largest raster the front ends read for vectorizing unless told otherwise (their
// --max-pixels): 2^25 pixels, so a 24 MP photograph (6000 x 4000) and a 32 MP one are read. What
// an image may cost is vectorize()'s memory check (VectorizeOptions::max_memory), not this.
inline constexpr int64_t kDefaultMaxInputPixels = int64_t{1} << 25;

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
  // Levels of abstraction built from the fitted mesh (levels.h); with levels.levels = 1 the
  // document has one level and each feature's saliency is stored. The defaults are the document
  // `subvec vectorize` writes. Their color refit keeps its own options (levels.fit), not `fit`.
  LevelOptions levels;
  int threads = 0;       // 0: all cores; the result does not depend on it
  // The memory the job may plan for, in bytes: an image whose estimate_vectorize_bytes() is larger
  // is refused with Error(kLimit) before the job's first large allocation. 0: the memory available
  // when the job starts (available_memory_bytes(), core/memory.h).
  int64_t max_memory = 0;
  // Called with a stage name and the fraction of the whole job done (0..1), at the start of each
  // stage of vectorize_stages() and with "done" and 1 at the end.
  std::function<void(const std::string& stage, double fraction)> progress;
  // When set and true, the job stops at the next check and throws Error(kCancelled): between
  // stages, and inside the long ones (vectorize() gives it to simplify, refine, the fit and the
  // levels in place of their own `cancel`), so a stage of seconds stops within a fraction of one.
  // May be set from another thread or a signal handler.
  const std::atomic<bool>* cancel = nullptr;
};

// Throws Error(kInvalidArgument) for the first option out of its range, in one line that starts
// with the option's field name as written in C++ ("ratio", "levels.reduction",
// "features.blur_sigma", "fit.l1_iterations") and then the rule and the value, e.g.
// "ratio must be in (0, 1], got 2". Front ends may replace the leading field name by their own
// name for it (a flag, a keyword argument). vectorize() calls it first.
void validate(const VectorizeOptions& options);

// A stage of the job and the fraction of the whole job done when it starts (rough shares of the
// run time), in order; "segment" only with a segment rectangle.
struct VectorizeStage {
  const char* name;
  double start;
};
std::vector<VectorizeStage> vectorize_stages(bool segment);

struct StageTime {
  std::string stage;
  double seconds = 0;
};

struct VectorizeReport {
  int vertices = 0, triangles = 0, features = 0, tear_vertices = 0;  // of level 0
  double fit_rms = 0;
  int target_vertices = 0;  // the budget: options.vertices, or ratio x pixels (at least 4)
  int dense_vertices = 0;   // of the dense mesh that simplification starts from
  // How far level 0's feature chains may be from the detected curves, in pixels:
  // max_feature_error, unless the vertex budget needed more (vectorize() then loosens them, up to
  // 3 times, and drops the least salient features; features_dropped counts them).
  double feature_tolerance = 0;
  int features_dropped = 0;
  std::vector<StageTime> stages;  // [segment,] features, mesh, simplify, refine, fit, levels
  SimplifyStats simplify;
  RefineStats refine;
  LevelReport levels;
  // The detected polyline each output feature follows (same order as the mesh's features).
  std::vector<std::vector<Vec2>> feature_targets;
  // With a segment rectangle: the cleaned GrabCut foreground, and the ids of the mesh features
  // that follow its boundary.
  RegionMask segment_mask;
  std::vector<int32_t> segment_feature_ids;
};

// The grid the dense mesh starts from when options.initial_mesh.grid_step is 0 (automatic), for
// images of 2^17 pixels or more: at targets of at most 1/64 of the pixels 4 (8 from 2^21 pixels),
// at targets of at most 1/16 of them 2; else, and for smaller images, 1 (docs/vectorize.md,
// "Large images").
int automatic_grid_step(int64_t pixels, int target_vertices);

// The peak memory of vectorizing a width x height image with `options`, in bytes: an upper bound
// of the peak resident size of `subvec vectorize` (image, job, closing render and comparison),
// from the pixels, the dense mesh's grid and the fit's refined triangles, calibrated on measured
// peaks from 0.25 to 16 MP (docs/performance.md, "Memory"). Options are not validated.
int64_t estimate_vectorize_bytes(int width, int height, const VectorizeOptions& options);

// Throws Error(kLimit) when estimate_vectorize_bytes() exceeds options.max_memory (or, at 0, the
// memory available now), in one line that starts with "max_memory" and gives both figures.
// vectorize() calls it before its first large allocation; a front end that decodes the image
// long before the job starts may call it first.
void check_vectorize_memory(int width, int height, const VectorizeOptions& options);

// Vectorizes an RGB image into a vector image of the same size with options.levels.levels
// levels. Throws Error(kInvalidArgument) for options out of range (validate()), Error(kLimit)
// when the estimate exceeds the memory it may use (check_vectorize_memory()) and
// Error(kCancelled) when options.cancel is set.
VectorImage vectorize(const Image8& image, const VectorizeOptions& options = {}, VectorizeReport* report = nullptr);

}  // namespace subvec
