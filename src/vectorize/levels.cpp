// Levels of abstraction (vectorize/levels.h, paper §5).
#include "subvec/vectorize/levels.h"

#include <algorithm>
#include <chrono>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "core/cancel_p.h"
#include "core/messages_p.h"
#include "mesh/coarsen_p.h"
#include "mesh/collapse_engine_p.h"
#include "mesh/polyline_p.h"
#include "mesh/quadric_p.h"
#include "vectorize/levels_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/curves.h"
#include "subvec/vectorize/simplify.h"

namespace subvec {
namespace {

using detail::Point5;
using detail::polyline_length;
using detail::Quadric5;
using detail::reduce;
using detail::walk;
using coarsen_detail::Coarsener;
using coarsen_detail::Kind;

[[noreturn]] void invalid(const std::string& message) { detail::invalid("levels: " + message); }

// How far a level's collapses may loosen its chains' tolerance when nothing more can go: 8 times.
constexpr double kMaxLoosening = 8;

// The subdivision depth of a coarser level's color fit: its own default (default_fit_depth()), but
// no deeper than gives it half the refined triangles of level 0's fit (at depth `base_depth` on
// `base_triangles`) at most. The default rule steps by whole levels, and a level of half the
// faces often stepped one deeper: twice level 0's refined triangles, and at 4 MP 6 s of the fit
// for 0.5% of its error (docs/vectorize.md, "Levels of abstraction"). A quarter of the faces one
// level deeper, level 0's count again, was allowed until 2026-12-08: at 4 MP 1.2 s of the levels
// for at most 0.6 % of level 2's error.
int level_fit_depth(const ControlMesh& level, int base_depth, int base_triangles) {
  int depth = base_depth;
  for (double faces = level.num_triangles(); 4 * faces <= 0.5 * base_triangles; faces *= 4) ++depth;
  return std::min(depth, default_fit_depth(level));
}

}  // namespace

namespace detail {

std::vector<EdgeVerts> coarsen(Coarsener& c, int target, double& tolerance, double max_loosening,
                               double color_scale, int threads, const std::atomic<bool>* cancel) {
  const int nv = c.num_vertices();
  // Quadrics per merged color value, from the triangles' 5D points.
  const double cs = color_scale;
  std::vector<Quadric5> quadric = detail::color_quadrics(
      static_cast<int>(c.triangles().size()), c.num_merged(), threads, [&](int f, int k, Point5& p) {
        const Vec2 x = c.positions()[c.triangles()[f][k]];
        const int32_t m = c.triangle_colors()[f][k];
        const auto& rgb = c.merged_colors()[m];
        p = {x.x, x.y, cs * rgb[0], cs * rgb[1], cs * rgb[2]};
        return m;
      });
  // The simplifier's queue and greedy loop (mesh/collapse_engine_p.h): cheapest first, ties by the
  // removed and the kept vertex.
  detail::CollapseQueue queue;
  std::vector<uint32_t> version(nv, 0);
  auto plan = [&](int32_t u, int32_t v) {
    if (c.kind(u) == Kind::kCorner) return;
    std::array<std::array<int32_t, 2>, 2> pairs;
    const int n = c.edge_color_pairs(u, v, pairs);
    if (n == 0) return;
    const Vec2 pu = c.positions()[u], pv = c.positions()[v];
    double cost = 1e-8 * ((pu.x - pv.x) * (pu.x - pv.x) + (pu.y - pv.y) * (pu.y - pv.y));
    for (int i = 0; i < n; ++i) {
      Quadric5 q = quadric[pairs[i][0]];
      q += quadric[pairs[i][1]];
      cost += std::max(0.0, reduce(q)(pv.x, pv.y));
    }
    if (std::isfinite(cost)) queue.push(detail::make_entry(cost, u, v, version[u], version[v]));
  };
  std::vector<int32_t> ring, ring2;
  auto plan_around = [&](int32_t v) {
    c.neighbours(v, ring2);
    for (int32_t w : ring2) {
      plan(v, w);
      plan(w, v);
    }
  };
  auto plan_all = [&] {
    for (int32_t v = 0; v < nv; ++v) {
      if (!c.alive(v)) continue;
      c.neighbours(v, ring);
      for (int32_t w : ring) plan(v, w);
    }
  };
  std::vector<EdgeVerts> collapses;
  const auto more = [&] { return c.alive_vertices() > target; };
  const auto live = [&](const detail::Entry& e) { return detail::entry_live(e, c.vertex_alive(), version); };
  const auto step = [&](const detail::Entry& e) {
    const int32_t u = e.remove(), v = e.keep;
    if (!c.can_collapse(u, v, tolerance)) return;
    std::array<std::array<int32_t, 2>, 2> pairs;
    const int n = c.edge_color_pairs(u, v, pairs);
    detail::merge_side_by_side(quadric, pairs, n);
    c.neighbours(u, ring);
    c.collapse(u, v);
    collapses.push_back({u, v});
    for (int32_t w : ring) ++version[w];
    for (int32_t w : ring) plan_around(w);
  };
  const double max_tolerance = tolerance * max_loosening;
  for (plan_all();; plan_all()) {
    if (!detail::run_collapses(queue, cancel, more, live, step)) throw Error(ErrorCode::kCancelled, "cancelled");
    if (!more() || tolerance >= max_tolerance) break;
    tolerance *= 2;
  }
  return collapses;
}

BudgetResult hold_budget(ControlMesh& mesh, int width, int height, const Image8& photo, int target,
                         double tolerance, double saliency_weight, double color_scale,
                         const std::vector<int32_t>& protected_ids, int threads,
                         const std::atomic<bool>* cancel) {
  constexpr double kBudgetLoosening = 2;
  BudgetResult r;
  r.feature_tolerance = tolerance;
  if (mesh.num_vertices() <= target) return r;
  // The order in which features go: protected last, then by saliency, the least first (ties by id).
  const std::vector<double> saliency = measure_saliency(mesh, photo, saliency_weight);
  std::vector<std::pair<double, int32_t>> order;  // (rank key, id)
  for (size_t f = 0; f < mesh.features.size(); ++f) {
    const int32_t id = mesh.features[f].id;
    const bool keep_last =
        std::find(protected_ids.begin(), protected_ids.end(), id) != protected_ids.end();
    order.push_back({keep_last ? std::numeric_limits<double>::infinity() : saliency[f], id});
  }
  std::sort(order.begin(), order.end());
  size_t next = 0;  // order[next] is the next feature to drop
  for (int pass = 0;; ++pass) {
    std::vector<int32_t> kept;
    for (const Feature& f : mesh.features) kept.push_back(f.id);
    if (pass > 0) {
      // Enough of the least salient features that their vertices cover the excess, at least one.
      int64_t freed = 0;
      const int64_t excess = mesh.num_vertices() - int64_t{target};
      while (next < order.size() && (freed == 0 || freed < excess)) {
        const int32_t id = order[next++].second;
        const auto it = std::find_if(mesh.features.begin(), mesh.features.end(),
                                     [&](const Feature& f) { return f.id == id; });
        if (it == mesh.features.end()) continue;  // gone with an earlier pass's collapses
        freed += static_cast<int64_t>(it->vertices.size());
        kept.erase(std::find(kept.begin(), kept.end(), id));
        r.dropped.push_back(id);
      }
    }
    coarsen_detail::Coarsener c(mesh, width, height, kept);
    // The chains start within `tolerance` of their curves and move at most t more.
    double t = pass == 0 ? tolerance : r.feature_tolerance - tolerance;
    coarsen(c, target, t, pass == 0 ? kBudgetLoosening : 1, color_scale, threads, cancel);
    r.feature_tolerance = std::max(r.feature_tolerance, tolerance + t);
    std::vector<int32_t> parents, color_merged;
    mesh = c.result(parents, color_merged);
    if (mesh.num_vertices() <= target) return r;
    if (mesh.features.empty()) {
      // Half-edge collapses keep one end of every edge where it is; the simplifier's placed
      // collapses may still go below them.
      SimplifyOptions o;
      o.target_vertices = target;
      o.color_scale = color_scale;
      o.threads = threads;
      o.cancel = cancel;
      simplify(mesh, width, height, o);
      if (mesh.num_vertices() <= target) return r;
      throw Error(ErrorCode::kInvalidArgument,
                  "a budget of " + std::to_string(target) +
                      " control vertices cannot be met: the image frame needs at least " +
                      std::to_string(mesh.num_vertices()) + " control vertices");
    }
  }
}

}  // namespace detail

double curve_saliency(std::span<const Vec2> curve, const Image8& raster, double weight) {
  const double length = polyline_length(curve);
  double contrast = 0;
  int samples = 0;
  walk(curve, 1.0, [&](Vec2 p, Vec2 t) {
    const auto a = sample_bilinear(raster, p.x - t.y, p.y + t.x);
    const auto b = sample_bilinear(raster, p.x + t.y, p.y - t.x);
    contrast += std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]) / 2;
    ++samples;
  });
  return length + weight * (samples ? contrast / samples : 0.0);
}

std::vector<double> measure_saliency(const ControlMesh& mesh, const Image8& raster, double weight) {
  std::vector<double> out;
  for (const Feature& f : mesh.features) {
    std::vector<Vec2> points;
    const size_t n = f.vertices.size() - (f.closed() ? 1 : 0);
    for (size_t i = 0; i < n; ++i) points.push_back(mesh.positions[f.vertices[i]]);
    const std::vector<Vec2> curve = sample_bspline(points, f.closed(), 8);
    out.push_back(curve_saliency(curve, raster, weight));
  }
  return out;
}

std::vector<int> assign_feature_levels(const ControlMesh& mesh, const std::vector<double>& saliency, int levels,
                                       const std::vector<std::pair<int32_t, int>>& overrides) {
  const int n = static_cast<int>(mesh.features.size());
  if (static_cast<int>(saliency.size()) != n) invalid("one saliency per feature is needed");
  if (levels < 1) invalid("levels must be at least 1, got " + std::to_string(levels));
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    if (saliency[a] != saliency[b]) return saliency[a] > saliency[b];
    return mesh.features[a].id < mesh.features[b].id;
  });
  std::vector<int> level(n, 0);
  // Rank r (0 = most salient) falls in group floor(r L / n); group 0 reaches the coarsest level.
  for (int r = 0; r < n; ++r) level[order[r]] = levels - 1 - static_cast<int>(int64_t{r} * levels / n);
  for (const auto& [id, l] : overrides) {
    if (l < 0 || l >= levels) {
      invalid("feature " + std::to_string(id) + ": level " + std::to_string(l) + " is outside 0.." +
              std::to_string(levels - 1));
    }
    bool found = false;
    for (int i = 0; i < n; ++i) {
      if (mesh.features[i].id == id) level[i] = l, found = true;
    }
    if (!found) invalid("no feature has id " + std::to_string(id));
  }
  return level;
}

void validate(const LevelOptions& l, const std::string& prefix) {
  using detail::check_in;
  check_in(prefix + "levels", l.levels, 1, 16);
  check_in(prefix + "saliency_weight", l.saliency_weight, 0, 1e6);
  check_in(prefix + "reduction", l.reduction, 0.01, 0.95);
  detail::check_positive(prefix + "max_feature_error", l.max_feature_error);
  detail::check_positive(prefix + "color_scale", l.color_scale);
  validate(l.fit, prefix + "fit.");
}

void build_levels(VectorImage& image, const Image8& photo, const LevelOptions& options, LevelReport* report) {
  validate(options);
  if (image.levels.empty()) invalid("the image has no level 0");
  if (photo.width != image.width || photo.height != image.height) {
    invalid("the photograph is " + std::to_string(photo.width) + "x" + std::to_string(photo.height) +
            ", the vector image " + std::to_string(image.width) + "x" + std::to_string(image.height));
  }
  LevelReport local;
  LevelReport& r = report ? *report : local;
  r = {};
  image.levels.resize(1);
  // Reserved so that `base` (and `fine` below) stay valid while coarser levels are appended.
  image.levels.reserve(static_cast<size_t>(options.levels));
  ControlMesh& base = image.levels[0];
  base.parent_vertices.clear();
  base.collapses.clear();
  std::vector<double> saliency = measure_saliency(base, photo, options.saliency_weight);
  for (size_t f = 0; f < base.features.size(); ++f) {
    if (base.features[f].saliency != 0) saliency[f] = base.features[f].saliency;
    else base.features[f].saliency = saliency[f];
  }
  const std::vector<int> feature_level = assign_feature_levels(base, saliency, options.levels, options.feature_levels);
  r.feature_level = feature_level;
  r.vertices.push_back(base.num_vertices());
  r.features.push_back(static_cast<int>(base.features.size()));
  r.seconds.push_back(0);
  const int base_depth = options.fit.depth >= 0 ? options.fit.depth : default_fit_depth(base);
  for (int l = 1; l < options.levels; ++l) {
    detail::check_cancel(options.cancel);
    const auto start = std::chrono::steady_clock::now();
    const ControlMesh& fine = image.levels[l - 1];
    std::vector<int32_t> kept;
    for (size_t f = 0; f < base.features.size(); ++f)
      if (feature_level[f] >= l) kept.push_back(base.features[f].id);
    Coarsener c(fine, image.width, image.height, kept);
    const int target = std::max(4, static_cast<int>(std::ceil(fine.num_vertices() * (1 - options.reduction))));
    // Kept chains may wander 1 px (max_feature_error) from the finer level's at level 1, 2 px at
    // level 2, ...: coarser levels are coarser abstractions of the same curves.
    double tolerance = options.max_feature_error * std::ldexp(1.0, l - 1);
    std::vector<EdgeVerts> collapses = detail::coarsen(c, target, tolerance, kMaxLoosening, options.color_scale,
                                                       options.fit.threads, options.cancel);
    std::vector<int32_t> parents, color_merged;
    ControlMesh coarse = c.result(parents, color_merged);
    ColorFitOptions fit = options.fit;
    if (!fit.cancel) fit.cancel = options.cancel;
    fit.measure = false;
    if (fit.depth < 0) fit.depth = level_fit_depth(coarse, base_depth, base.num_triangles());
    fit_colors(coarse, image.width, image.height, photo, fit);
    coarse.parent_vertices = std::move(parents);
    coarse.collapses = std::move(collapses);
    r.vertices.push_back(coarse.num_vertices());
    r.features.push_back(static_cast<int>(coarse.features.size()));
    image.levels.push_back(std::move(coarse));
    r.seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
}

}  // namespace subvec
