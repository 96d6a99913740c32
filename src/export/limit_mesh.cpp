// The depth rule of the vector exports. Drawing the limit surface as flat-sided triangles (PDF's
// Gouraud shading interpolates colors linearly too) errs by the distance between the surface and
// its chords; refining one level more divides that by about four where the surface is smooth, but
// only by two at its singular points (tear corners, junctions, extraordinary vertices), so the rule
// asks the tolerances of all but 1% of the refined edges rather than of every one. It measures the
// error instead of estimating it: for depth k it evaluates the exact limit (LimitEvaluator:
// OpenSubdiv's Loop patches) at the parametric midpoints of the refined edges of every control face
// and compares with the mean of the edge's ends, which are the refined vertices' limit values.
#include "export/limit_mesh_p.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/messages_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/validate.h"

namespace subvec::detail {
namespace {

using detail::invalid;
using detail::num;

constexpr int64_t kMaxTriangles = int64_t{1} << 24;
// The tolerance may be exceeded at this fraction of the refined edges: at the few singular points
// of the limit surface (corners of tears, junctions) the error only halves per level.
constexpr double kAllowedOver = 0.01;

}  // namespace

LinearError linear_error(const LimitEvaluator& evaluator, const ControlMesh& mesh, int depth,
                         double position_tolerance, double color_tolerance,
                         std::vector<double>* positions) {
  const int n = 1 << depth, fine = 2 * n;
  // Values at the parameters (i / fine, j / fine), i + j <= fine, of one face.
  struct Value {
    double x, y, c[3];
  };
  std::vector<Value> grid(size_t(fine + 1) * (fine + 1));
  auto at = [&](int i, int j) -> Value& { return grid[size_t(j) * (fine + 1) + i]; };
  LinearError error;
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    for (int j = 0; j <= fine; ++j) {
      for (int i = 0; i + j <= fine; ++i) {
        const LimitEvaluator::Sample s = evaluator.evaluate(f, double(i) / fine, double(j) / fine);
        at(i, j) = {s.position.x, s.position.y, {s.color[0], s.color[1], s.color[2]}};
      }
    }
    auto edge = [&](int i0, int j0, int i1, int j1) {
      const Value &a = at(2 * i0, 2 * j0), &b = at(2 * i1, 2 * j1), &m = at(i0 + i1, j0 + j1);
      const double position = std::hypot(m.x - 0.5 * (a.x + b.x), m.y - 0.5 * (a.y + b.y));
      double color = 0;
      for (int k = 0; k < 3; ++k)
        color = std::max(color, std::abs(m.c[k] - 0.5 * (a.c[k] + b.c[k])));
      if (positions) positions->push_back(position);
      error.max_position = std::max(error.max_position, position);
      error.max_color = std::max(error.max_color, color);
      error.over += position > position_tolerance || color > color_tolerance;
      ++error.edges;
    };
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i + j < n; ++i) {
        edge(i, j, i + 1, j);
        edge(i, j, i, j + 1);
        edge(i + 1, j, i, j + 1);
      }
    }
  }
  return error;
}

int export_depth(const VectorImage& image, const ExportOptions& options, ExportReport& report) {
  const int levels = static_cast<int>(image.levels.size());
  if (options.level < 0 || options.level >= levels) {
    invalid("level " + std::to_string(options.level) + " is out of range (the image has " +
            std::to_string(levels) + (levels == 1 ? " level)" : " levels)"));
  }
  if (!(options.scale > 0) || !std::isfinite(options.scale))
    invalid("scale " + num(options.scale) + " is not a positive number");
  if (options.width < 0) invalid("width " + std::to_string(options.width) + " is negative");
  const double scale = export_scale(options, image.width);
  // The page, in output units: PDF viewers and SVG renderers draw nothing sensible outside these
  // bounds (the numbers of a page 1e300 units wide print with hundreds of digits).
  const double page_width = image.width * scale, page_height = image.height * scale;
  if (!(page_width <= Limits::kMaxDimension && page_height <= Limits::kMaxDimension)) {
    throw Error(ErrorCode::kLimit, "output size " + num(page_width) + "x" + num(page_height) +
                                       " is too large (at most " +
                                       std::to_string(Limits::kMaxDimension) + " units a side)");
  }
  if (page_width < 1 || page_height < 1) {
    invalid("output size " + num(page_width) + "x" + num(page_height) +
            " is too small (at least 1 unit a side)");
  }
  if (!(options.tolerance > 0) || !std::isfinite(options.tolerance))
    invalid("tolerance " + num(options.tolerance) + " is not a positive number");
  if (!(options.color_tolerance > 0) || !std::isfinite(options.color_tolerance))
    invalid("color tolerance " + num(options.color_tolerance) + " is not a positive number");
  if (options.depth > 8) invalid("depth " + std::to_string(options.depth) + " is over 8");
  if (options.max_depth < 0 || options.max_depth > 8)
    invalid("max depth " + std::to_string(options.max_depth) + " is out of range (0 to 8)");

  const ControlMesh& mesh = image.levels[options.level];
  const MeshTopology topology = validate_level(mesh, image.width, image.height, options.level);
  const int64_t faces = mesh.num_triangles();
  int depth = options.depth;
  if (depth >= 0) {
    if (faces << (2 * depth) > kMaxTriangles) {
      throw Error(ErrorCode::kLimit, "depth " + std::to_string(depth) + " over " +
                                         std::to_string(faces) +
                                         " faces would make more than 2^24 triangles");
    }
  } else {
    const LimitEvaluator evaluator(mesh, topology);
    for (depth = 0;; ++depth) {
      const LinearError e = linear_error(evaluator, mesh, depth, options.tolerance / scale,
                                         options.color_tolerance);
      report.max_position_error = e.max_position * scale;
      report.max_color_error = e.max_color;
      report.over_tolerance = e.edges ? double(e.over) / double(e.edges) : 0;
      if (report.over_tolerance <= kAllowedOver || depth >= options.max_depth ||
          (faces << (2 * (depth + 1))) > kMaxTriangles)
        break;
    }
  }
  report.depth = depth;
  return depth;
}

RefinedMesh export_limit_mesh(const VectorImage& image, int level, int depth,
                              ExportReport& report) {
  const ControlMesh& mesh = image.levels[level];
  const MeshTopology topology = MeshTopology::build(mesh, image.width, image.height);
  const Subdivision subdivision(mesh, topology, depth);
  RefinedMesh refined;
  subdivision.evaluate(mesh.positions, mesh.colors, refined);
  report.depth = depth;
  report.triangles = refined.num_triangles();
  return refined;
}

}  // namespace subvec::detail
