#include "subvec/vectorize/vectorize.h"

#include <chrono>
#include <cmath>
#include <string>

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

  // Stage 1: features. Stage 2: the dense mesh. Rough shares of the run time drive the progress.
  progress("features", 0.0);
  const std::vector<DetectedFeature> features = detect_features(image, options.features);
  lap("features");
  progress("mesh", 0.02);
  ControlMesh mesh = build_initial_mesh(image, features, options.initial_mesh);
  lap("mesh");

  r.feature_targets.clear();
  for (const Feature& f : mesh.features) {
    std::vector<Vec2> polyline;
    for (int32_t v : f.vertices) polyline.push_back(mesh.positions[v]);
    r.feature_targets.push_back(std::move(polyline));
  }

  // Stage 3: simplification.
  progress("simplify", 0.25);
  SimplifyOptions simplify_options;
  simplify_options.target_vertices = target;
  simplify_options.max_feature_error = options.max_feature_error;
  simplify_options.threads = options.threads;
  r.simplify = simplify(mesh, image.width, image.height, simplify_options);
  lap("simplify");

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
