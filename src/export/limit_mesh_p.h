// The limit mesh that the vector exports draw (export.h): the depth rule and the refinement.
#pragma once

#include <cstdint>

#include "subvec/export/export.h"
#include "subvec/mesh/topology.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec::detail {

struct LinearError {
  double max_position = 0;  // image pixels
  double max_color = 0;     // levels, the largest channel difference
  int64_t edges = 0, over = 0;  // refined edges, and those over a tolerance
};

// Deviation of the limit surface of `mesh` from the piecewise-linear surface through its limit
// points at `depth`: over every control face, the limit at the midpoint (in the face's
// parameters) of each edge of the face's depth-`depth` triangles against the mean of the edge's
// ends. Counts the edges whose position (image pixels) or color deviation exceeds a tolerance; with
// `positions`, also appends each edge's position deviation there.
LinearError linear_error(const LimitEvaluator& evaluator, const ControlMesh& mesh, int depth,
                         double position_tolerance, double color_tolerance,
                         std::vector<double>* positions = nullptr);

// Checks the options and the level and returns the depth: options.depth, or the smallest that
// meets the tolerances, up to options.max_depth and 2^24 triangles (report: depth and errors).
int export_depth(const VectorImage& image, const ExportOptions& options, ExportReport& report);

// The limit mesh of `level` (valid) at `depth` (report: depth and triangles).
RefinedMesh export_limit_mesh(const VectorImage& image, int level, int depth,
                              ExportReport& report);

}  // namespace subvec::detail
