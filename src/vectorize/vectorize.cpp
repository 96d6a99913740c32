#include "subvec/vectorize/vectorize.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <string>
#include <utility>

#include "subvec/core/error.h"
#include "subvec/mesh/topology.h"

namespace subvec {

VectorImage vectorize(const Image8& image, const VectorizeOptions& options, VectorizeReport* report) {
  if (image.width < 2 || image.height < 2) {
    throw Error(ErrorCode::kInvalidArgument, "image of " + std::to_string(image.width) + "x" +
                                                 std::to_string(image.height) + " pixels is too small to vectorize");
  }
  if (options.vertices <= 0 && !(options.ratio > 0 && options.ratio <= 1)) {
    throw Error(ErrorCode::kInvalidArgument, "ratio must be in (0, 1], got " + std::to_string(options.ratio));
  }
  const double pixels = double(image.width) * image.height;
  const int target = std::max(4, options.vertices > 0 ? options.vertices
                                                      : static_cast<int>(std::lround(options.ratio * pixels)));
  VectorizeReport local;
  VectorizeReport& r = report ? *report : local;
  r = {};
  auto progress = [&](const char* stage, double fraction) {
    if (options.progress) options.progress(stage, fraction);
  };
  using Clock = std::chrono::steady_clock;
  auto t = Clock::now();
  auto lap = [&](const char* stage) {
    const auto now = Clock::now();
    r.stages.push_back({stage, std::chrono::duration<double>(now - t).count()});
    t = now;
  };

  // Stage 1: features, GrabCut's region boundary (first: it checks the rectangle) and Canny.
  // Stage 2: the dense mesh. Rough shares of the run time drive the progress.
  std::vector<DetectedFeature> boundary;
  if (options.segment) {
    progress("segment", 0.0);
    r.segment_mask = segment_foreground(image, *options.segment, options.segment_options);
    boundary = region_boundary_features(r.segment_mask, options.segment_options);
    lap("segment");
  }
  progress("features", options.segment ? 0.08 : 0.0);
  std::vector<DetectedFeature> features = detect_features(image, options.features);
  const size_t num_boundary = boundary.size();
  if (num_boundary > 0) {
    clear_features_near(features, boundary, options.segment_options.clearance, options.features.min_length);
    // First, so that the boundary keeps every edge it shares with nothing else and gets the first ids.
    features.insert(features.begin(), std::make_move_iterator(boundary.begin()),
                    std::make_move_iterator(boundary.end()));
  }
  lap("features");
  progress("mesh", options.segment ? 0.1 : 0.02);
  // Images from 512 x 512 up start from a 2-pixel grid away from the features (docs/vectorize.md,
  // "Large images"): about the same error for a third less time; the fit still sees every pixel.
  InitialMeshOptions mesh_options = options.initial_mesh;
  if (mesh_options.grid_step == 0) {
    mesh_options.grid_step = pixels >= double(1 << 18) && 16.0 * target <= pixels ? 2 : 1;
  }
  ControlMesh mesh = build_initial_mesh(image, features, mesh_options);
  lap("mesh");
  if (num_boundary > 0) {
    // The mesh features whose vertices are the boundary's points (the dense mesh keeps positions).
    std::set<std::pair<double, double>> on_boundary;
    for (size_t k = 0; k < num_boundary; ++k)
      for (const Vec2& p : features[k].points) on_boundary.insert({p.x, p.y});
    for (const Feature& f : mesh.features) {
      const auto hits = std::count_if(f.vertices.begin(), f.vertices.end(), [&](int32_t v) {
        return on_boundary.count({mesh.positions[v].x, mesh.positions[v].y}) > 0;
      });
      if (2 * hits > static_cast<std::ptrdiff_t>(f.vertices.size())) r.segment_feature_ids.push_back(f.id);
    }
  }

  r.feature_targets.clear();
  for (const Feature& f : mesh.features) {
    std::vector<Vec2> polyline;
    for (int32_t v : f.vertices) polyline.push_back(mesh.positions[v]);
    r.feature_targets.push_back(std::move(polyline));
  }

  // Stage 3: simplification.
  progress("simplify", options.segment ? 0.3 : 0.25);
  SimplifyOptions simplify_options;
  simplify_options.target_vertices = target;
  simplify_options.max_feature_error = options.max_feature_error;
  simplify_options.threads = options.threads;
  r.simplify = simplify(mesh, image.width, image.height, simplify_options);
  lap("simplify");

  // Stage 3b: data-dependent flips and vertex moves.
  progress("refine", 0.7);
  RefineOptions refine_options = options.refine;
  refine_options.threads = options.threads;
  r.refine = refine_mesh(mesh, image, refine_options);
  lap("refine");

  // Stage 4: colors.
  progress("fit", 0.8);
  ColorFitOptions fit_options = options.fit;
  fit_options.threads = options.threads;
  const ColorFitStats fit = fit_colors(mesh, image.width, image.height, image, fit_options);
  lap("fit");
  progress("done", 1.0);

  r.vertices = mesh.num_vertices();
  r.triangles = mesh.num_triangles();
  r.features = static_cast<int>(mesh.features.size());
  r.fit_rms = fit.rms;
  const MeshTopology topo = MeshTopology::build(mesh, image.width, image.height);
  for (VertexTag tag : topo.vertex_tags) r.tear_vertices += tag == VertexTag::kTear;

  VectorImage out;
  out.width = image.width;
  out.height = image.height;
  out.levels.push_back(std::move(mesh));
  return out;
}

}  // namespace subvec
