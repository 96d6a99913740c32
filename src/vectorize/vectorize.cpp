#include "subvec/vectorize/vectorize.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "core/cancel_p.h"
#include "core/messages_p.h"
#include "subvec/core/error.h"
#include "subvec/core/memory.h"
#include "subvec/mesh/topology.h"
#include "vectorize/levels_p.h"

namespace subvec {
namespace {

// The stages of the job and the share of the whole job done when each starts: the stage times of
// `--json` at the defaults, about the same from the 512-class photographs to 4 MP (docs/
// performance.md); the CLI's progress line makes its estimate of the time left from them.
constexpr VectorizeStage kStages[] = {{"features", 0.0}, {"mesh", 0.04}, {"simplify", 0.14},
                                      {"refine", 0.38},  {"fit", 0.62},  {"levels", 0.81}};
constexpr VectorizeStage kSegmentStages[] = {{"segment", 0.0},   {"features", 0.08}, {"mesh", 0.12},
                                             {"simplify", 0.21}, {"refine", 0.43},   {"fit", 0.65},
                                             {"levels", 0.83}};

// The budget: options.vertices, or ratio x pixels; at least 4 (the corners).
int target_vertex_count(const VectorizeOptions& options, double pixels) {
  return std::max(4, options.vertices > 0 ? options.vertices : static_cast<int>(std::lround(options.ratio * pixels)));
}

// estimate_vectorize_bytes(): bytes of the process (binary, libraries, thread stacks), of each pixel
// (the image, the features' and the fit's per-pixel arrays), of each dense mesh vertex with its
// quadrics, and of each refined triangle and control vertex of the fit. Fitted to the peak
// resident sizes of `subvec vectorize` from 0.26 to 16 MP and ratios 0.003 to 0.1, and raised
// until the estimate bounds every one (docs/performance.md, "Memory"). The simplified meshes' mean
// edges measured up to kEdgeShare times the equilateral one (ratio 0.06 on 1 MP: the fit refined
// one level deeper than equilateral triangles would).
constexpr double kProcessBytes = 80e6, kPerPixel = 90, kPerDenseVertex = 440, kPerRefinedTriangle = 650,
                 kPerControlVertex = 500, kBandShare = 0.6, kEdgeShare = 1.4142;

}  // namespace

void validate(const VectorizeOptions& o) {
  using detail::check_in;
  if (!(o.ratio > 0 && o.ratio <= 1)) detail::out_of_range("ratio", "in (0, 1]", o.ratio);
  if (o.vertices != 0 && !(o.vertices >= 4 && o.vertices <= (1 << 26))) {
    detail::out_of_range("vertices", "0 (use ratio) or in [4, " + std::to_string(1 << 26) + "]", o.vertices);
  }
  validate(o.features, "features.");
  if (!valid_grid_step(o.initial_mesh.grid_step)) {
    detail::out_of_range("initial_mesh.grid_step", "0 (automatic), 1, 2, 4 or 8", o.initial_mesh.grid_step);
  }
  check_in("max_feature_error", o.max_feature_error, 0.05, 100);
  validate(o.refine, "refine.");
  validate(o.fit, "fit.");
  validate(o.levels, "levels.");
  check_in("threads", o.threads, 0, 1024);
  if (o.max_memory < 0) {
    throw Error(ErrorCode::kInvalidArgument,
                "max_memory must be 0 (the memory available) or a byte count, got " + std::to_string(o.max_memory));
  }
}

int automatic_grid_step(int64_t pixels, int target_vertices) {
  const double p = double(pixels);
  if (p < double(1 << 17) || 16.0 * target_vertices > p) return 1;
  if (64.0 * target_vertices > p) return 2;
  return p >= double(1 << 21) ? 8 : 4;
}

int64_t estimate_vectorize_bytes(int width, int height, const VectorizeOptions& options) {
  const double pixels = double(width) * height;
  // Simplification cannot add vertices: a budget over the dense mesh's keeps it whole.
  const double target = std::min<double>(target_vertex_count(options, pixels), pixels);
  const int step = options.initial_mesh.grid_step > 0 ? options.initial_mesh.grid_step
                                                      : automatic_grid_step(int64_t(pixels), int(target));
  // The two peaks: the dense mesh while it is simplified, and the color fit. The dense mesh has a
  // vertex per grid block and one per pixel in the features' band, which is not known before the
  // features are: taken as kBandShare of the pixels (the most feature-rich of the photographs
  // measured, OneStandsOut, keeps about 60 % of them).
  const double dense = pixels / (step * step) + kBandShare * pixels * (1 - 1.0 / (step * step));
  // The fit's refined triangles: twice the target at the depth rule's depth (default_fit_depth(),
  // which measures the real mesh's mean edge) for a mean edge of kEdgeShare times that of
  // equilateral triangles of the image's mean area.
  const int depth = options.fit.depth >= 0
                        ? options.fit.depth
                        : fit_depth_for_mean_edge(kEdgeShare * std::sqrt(2 * pixels / (std::sqrt(3.0) * target)));
  const double refined = 2.0 * target * std::pow(4.0, depth);
  const double mesh_peak = kPerDenseVertex * dense;
  const double fit_peak = kPerRefinedTriangle * refined + kPerControlVertex * target;
  return static_cast<int64_t>(kProcessBytes + kPerPixel * pixels + std::max(mesh_peak, fit_peak));
}

std::vector<VectorizeStage> vectorize_stages(bool segment) {
  return segment ? std::vector<VectorizeStage>(std::begin(kSegmentStages), std::end(kSegmentStages))
                 : std::vector<VectorizeStage>(std::begin(kStages), std::end(kStages));
}

void check_vectorize_memory(int width, int height, const VectorizeOptions& options) {
  const int64_t need = estimate_vectorize_bytes(width, height, options);
  const int64_t room = options.max_memory > 0 ? options.max_memory : available_memory_bytes();
  if (need <= room) return;
  throw Error(ErrorCode::kLimit, "max_memory is " + format_bytes(room) +
                                     (options.max_memory > 0 ? "" : " (the memory available now)") +
                                     ", and vectorizing this " + std::to_string(width) + "x" +
                                     std::to_string(height) + " image needs an estimated " +
                                     format_bytes(need));
}

VectorImage vectorize(const Image8& image, const VectorizeOptions& options, VectorizeReport* report) {
  validate(options);
  if (image.width < 2 || image.height < 2) {
    throw Error(ErrorCode::kInvalidArgument, "image of " + std::to_string(image.width) + "x" +
                                                 std::to_string(image.height) + " pixels is too small to vectorize");
  }
  const double pixels = double(image.width) * image.height;
  const int target = target_vertex_count(options, pixels);
  check_vectorize_memory(image.width, image.height, options);  // before the first large allocation
  VectorizeReport local;
  VectorizeReport& r = report ? *report : local;
  r = {};
  r.target_vertices = target;
  const std::vector<VectorizeStage> stages = vectorize_stages(options.segment.has_value());
  // Each stage starts here: a cancelled job stops, and the progress callback hears of it. The long
  // stages (simplify, refine, fit, levels) also check the flag inside their loops.
  auto begin = [&](const char* stage) {
    detail::check_cancel(options.cancel);
    const auto at = std::find_if(stages.begin(), stages.end(),
                                 [&](const VectorizeStage& s) { return std::string(s.name) == stage; });
    if (options.progress) options.progress(stage, at->start);
  };
  using Clock = std::chrono::steady_clock;
  auto t = Clock::now();
  auto lap = [&](const char* stage) {
    const auto now = Clock::now();
    r.stages.push_back({stage, std::chrono::duration<double>(now - t).count()});
    t = now;
  };

  // Stage 1: features, GrabCut's region boundary (first: it checks the rectangle) and Canny.
  // Stage 2: the dense mesh.
  std::vector<DetectedFeature> boundary;
  if (options.segment) {
    begin("segment");
    r.segment_mask = segment_foreground(image, *options.segment, options.segment_options);
    boundary = region_boundary_features(r.segment_mask, options.segment_options);
    lap("segment");
  }
  begin("features");
  std::vector<DetectedFeature> features = detect_features(image, options.features);
  const size_t num_boundary = boundary.size();
  if (num_boundary > 0) {
    clear_features_near(features, boundary, options.segment_options.clearance, options.features.min_length);
    // First, so that the boundary keeps every edge it shares with nothing else and gets the first ids.
    features.insert(features.begin(), std::make_move_iterator(boundary.begin()),
                    std::make_move_iterator(boundary.end()));
  }
  lap("features");
  begin("mesh");
  // Images from 2^17 pixels up start from a quadtree of 4-pixel blocks away from the features (2 at
  // targets over 1/64 of the pixels), and from 2 MP up of 8-pixel ones (docs/vectorize.md, "Large
  // images"): about the same error in half the time; the fit still sees every pixel.
  InitialMeshOptions mesh_options = options.initial_mesh;
  if (mesh_options.grid_step == 0) mesh_options.grid_step = automatic_grid_step(int64_t(pixels), target);
  ControlMesh mesh = build_initial_mesh(image, features, mesh_options);
  r.dense_vertices = mesh.num_vertices();
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
  std::vector<int32_t> target_ids;
  for (const Feature& f : mesh.features) {
    target_ids.push_back(f.id);
    std::vector<Vec2> polyline;
    for (int32_t v : f.vertices) polyline.push_back(mesh.positions[v]);
    r.feature_targets.push_back(std::move(polyline));
  }

  // Stage 3: simplification.
  begin("simplify");
  SimplifyOptions simplify_options;
  simplify_options.target_vertices = target;
  simplify_options.max_feature_error = options.max_feature_error;
  simplify_options.threads = options.threads;
  simplify_options.cancel = options.cancel;
  r.simplify = simplify(mesh, image.width, image.height, simplify_options);
  // The budget holds: where the features kept more vertices than the target, their chains loosen
  // and the least salient of them go (levels_p.h), the segment's boundary last.
  detail::BudgetResult budget;
  try {
    budget = detail::hold_budget(mesh, image.width, image.height, image, target,
                                 options.max_feature_error, options.levels.saliency_weight,
                                 simplify_options.color_scale, r.segment_feature_ids,
                                 options.threads, options.cancel);
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kInvalidArgument) throw;
    // Named after the option that set the budget, as validate() names its fields.
    std::string why = e.what();
    why = why.substr(why.find(": ") + 2);  // after "a budget of N control vertices cannot be met"
    throw Error(ErrorCode::kInvalidArgument,
                (options.vertices > 0 ? "vertices " + std::to_string(options.vertices)
                                      : "ratio " + detail::num(options.ratio) + " (" +
                                            std::to_string(target) + " control vertices)") +
                    " cannot be met: " + why);
  }
  r.feature_tolerance = budget.feature_tolerance;
  r.features_dropped = static_cast<int>(budget.dropped.size());
  if (!budget.dropped.empty()) {
    // Keep the targets and segment ids of the features left.
    std::map<int32_t, size_t> index;  // feature id -> its target
    for (size_t k = 0; k < target_ids.size(); ++k) index[target_ids[k]] = k;
    std::vector<std::vector<Vec2>> targets;
    for (const Feature& f : mesh.features) targets.push_back(std::move(r.feature_targets[index.at(f.id)]));
    r.feature_targets = std::move(targets);
    std::erase_if(r.segment_feature_ids, [&](int32_t id) {
      return std::find(budget.dropped.begin(), budget.dropped.end(), id) != budget.dropped.end();
    });
  }
  lap("simplify");

  // Stage 3b: data-dependent flips and vertex moves.
  begin("refine");
  RefineOptions refine_options = options.refine;
  refine_options.threads = options.threads;
  refine_options.cancel = options.cancel;
  r.refine = refine_mesh(mesh, image, refine_options);
  lap("refine");

  // Stage 4: colors.
  begin("fit");
  ColorFitOptions fit_options = options.fit;
  fit_options.threads = options.threads;
  fit_options.cancel = options.cancel;
  const ColorFitStats fit = fit_colors(mesh, image.width, image.height, image, fit_options);
  lap("fit");

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

  // Stage 5: levels of abstraction (paper §5); with one level, each feature's saliency only.
  begin("levels");
  LevelOptions level_options = options.levels;
  level_options.fit.threads = options.threads;
  level_options.cancel = options.cancel;
  level_options.fit.cancel = options.cancel;
  build_levels(out, image, level_options, &r.levels);
  lap("levels");
  detail::check_cancel(options.cancel);
  if (options.progress) options.progress("done", 1.0);
  return out;
}

}  // namespace subvec
