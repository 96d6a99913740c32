// The limit mesh that the vector exports draw (export.h): each control face refined only as deep
// as its own error needs, stitched without cracks.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

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

// How a viewer fills a refined triangle: Gouraud (PDF's free-form meshes interpolate the corner
// colors linearly), flat (one color, the mean of the corners) or linear (SVG's browser target: a
// linear gradient, the rank-one least-squares fit of the limit colors over the triangle).
enum class Shading : uint8_t { kGouraud, kFlat, kLinear };

// A color that varies along one direction: c(p) = mean + ((p - centre) . direction) slope, the
// colors of an SVG linearGradient (one direction for all three channels).
struct LinearColor {
  double centre[2] = {0, 0};
  double mean[3] = {0, 0, 0};
  double direction[2] = {1, 0};  // unit
  double slope[3] = {0, 0, 0};   // levels per pixel along `direction`
  void at(double x, double y, double* out) const {
    const double t = (x - centre[0]) * direction[0] + (y - centre[1]) * direction[1];
    for (int k = 0; k < 3; ++k) out[k] = mean[k] + t * slope[k];
  }
};

// The LinearColor that best fits colors c_i at points (x_i, y_i) in the least-squares sense: of
// all colors that vary along one direction, the one with the smallest sum of squared differences
// (the top eigenvector of a 2 x 2 pencil, see the code). Flat when the points are collinear.
struct ColorSample {
  double x, y, c[3];
};
LinearColor fit_linear_color(std::span<const ColorSample> samples);

// What a face's refined triangles must meet, in image pixels and levels (0-255).
struct FaceTolerance {
  Shading shading = Shading::kGouraud;
  double position = 0.25;  // distance of the chord's midpoint from the limit
  // Gouraud: the limit color at an edge's midpoint against the mean of its ends. Flat: the limit
  // color at a triangle's corners and edge midpoints against the triangle's flat color.
  double color = 1;
  // A refined edge (Gouraud) or triangle (flat, its longest edge) no longer than this is fine
  // whatever its error: near the surface's singular points (tear corners, junctions) the error only
  // halves per level, and pieces under an output pixel cannot show it.
  double small = 1;
};

// Per control face, the smallest depth (0..max_depth) at which its refined triangles meet the
// tolerance. `error`, when given, receives the largest deviations over the chosen depths and the
// fraction of refined edges (Gouraud) or triangles (flat) that still miss the tolerance.
std::vector<uint8_t> face_depths(const LimitEvaluator& evaluator, const ControlMesh& mesh,
                                 const MeshTopology& topology, const FaceTolerance& tolerance,
                                 int max_depth, LinearError* error = nullptr);
// The same for several tolerances at once (one depth vector each, and errors[i] for tolerance i
// where given): each face's grid is refined once, as deep as its most demanding tolerance needs.
std::vector<std::vector<uint8_t>> face_depths(const LimitEvaluator& evaluator, const ControlMesh& mesh,
                                              const MeshTopology& topology, std::span<const FaceTolerance> tolerances,
                                              int max_depth, std::span<LinearError* const> errors = {});

// The limit surface of `mesh` as a triangle mesh, face f refined to depths[f] on the regular grid
// of its parameters, its limit positions and colors evaluated exactly (LimitEvaluator). An edge
// shared by faces of different depths is sampled at the finer depth on both sides; the coarser
// face fans its triangles on that edge to the extra points, so the mesh has no cracks and no
// T-junctions. Vertices are shared where faces meet; color values too, except across tears.
// tear_edges, crease_edges and border_edges list the refined edges along the control mesh's sharp
// edges. With every depth equal to d this is the uniformly refined mesh at depth d.
// With `params`, each refined triangle's corners' parameters in its control face (u, v).
RefinedMesh adaptive_limit_mesh(const ControlMesh& mesh, const MeshTopology& topology,
                                const LimitEvaluator& evaluator, std::span<const uint8_t> depths,
                                std::vector<std::array<float, 6>>* params = nullptr);

// Checks the options and the level (Error as export.h says) and returns the scale.
double check_export_options(const VectorImage& image, const ExportOptions& options);

// Shading::kLinear's colors. The geometry and the colors need different depths: a tear must be
// drawn within a fraction of a pixel, and a face's color may be one linear gradient. So each face
// is cut into color cells, the triangles of the grid of its parameters at its color depth (the
// smallest at which the LinearColor fitted to each cell meets the color tolerance), and refined
// at the deeper of that and its geometry depth; every refined triangle lies in one cell and draws
// that cell's color.
struct LinearCells {
  std::vector<int32_t> cell_of;      // per refined triangle
  std::vector<LinearColor> colors;   // per cell, fitted to the limit at its corners, edge midpoints
                                     // and centre
};

// The mesh an export draws: options.depth everywhere when it is given, else each face at the depth
// of the tolerances for `shading` (report: depths, triangles, errors). Shading::kLinear fills
// `cells`.
RefinedMesh export_mesh(const VectorImage& image, const ExportOptions& options, Shading shading,
                        ExportReport& report, LinearCells* cells = nullptr);

// The visible objects of options.level (mesh/vector_image.h), bottom to top, each refined as
// export_mesh() refines a level; the report adds their triangles, depths, errors and count.
struct ObjectMesh {
  int object = 0;  // index in VectorImage::objects
  RefinedMesh mesh;
  LinearCells cells;  // Shading::kLinear
};
std::vector<ObjectMesh> export_object_meshes(const VectorImage& image, const ExportOptions& options,
                                             Shading shading, ExportReport& report);

}  // namespace subvec::detail
