// The limit mesh that the vector exports draw (export.h): each control face refined only as deep
// as its own error needs, stitched without cracks.
#pragma once

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
// colors linearly) or flat (SVG: one color, the mean of the corners).
enum class Shading : uint8_t { kGouraud, kFlat };

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

// The limit surface of `mesh` as a triangle mesh, face f refined to depths[f] on the regular grid
// of its parameters, its limit positions and colors evaluated exactly (LimitEvaluator). An edge
// shared by faces of different depths is sampled at the finer depth on both sides; the coarser
// face fans its triangles on that edge to the extra points, so the mesh has no cracks and no
// T-junctions. Vertices are shared where faces meet; color values too, except across tears.
// tear_edges, crease_edges and border_edges list the refined edges along the control mesh's sharp
// edges. With every depth equal to d this is the uniformly refined mesh at depth d.
RefinedMesh adaptive_limit_mesh(const ControlMesh& mesh, const MeshTopology& topology,
                                const LimitEvaluator& evaluator, std::span<const uint8_t> depths);

// Checks the options and the level (Error as export.h says) and returns the scale.
double check_export_options(const VectorImage& image, const ExportOptions& options);

// The mesh an export draws: options.depth everywhere when it is given, else each face at the depth
// of the tolerances for `shading` (report: depths, triangles, errors).
RefinedMesh export_mesh(const VectorImage& image, const ExportOptions& options, Shading shading,
                        ExportReport& report);

// The visible objects of options.level (mesh/vector_image.h), bottom to top, each refined as
// export_mesh() refines a level; the report adds their triangles, depths, errors and count.
struct ObjectMesh {
  int object = 0;  // index in VectorImage::objects
  RefinedMesh mesh;
};
std::vector<ObjectMesh> export_object_meshes(const VectorImage& image, const ExportOptions& options,
                                             Shading shading, ExportReport& report);

}  // namespace subvec::detail
