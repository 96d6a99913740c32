// Stylization (edit/stylize.h): saliency (paper eq. 2) and strokes along features (paper §6.3).
#include "subvec/edit/stylize.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <string>

#include "core/messages_p.h"
#include "mesh/polyline_p.h"
#include "subvec/core/error.h"
#include "subvec/core/image.h"
#include "subvec/edit/selection.h"
#include "subvec/mesh/curves.h"
#include "subvec/mesh/validate.h"
#include "subvec/vectorize/levels.h"
#include "subvec/render/renderer.h"

namespace subvec {
namespace {

using detail::num;

using detail::polyline_length;
using detail::walk;

constexpr int kSamplesPerSpan = 16;

[[noreturn]] void invalid(const std::string& message) { detail::invalid("stylize: " + message); }

const ControlMesh& level_mesh(const VectorImage& image, int level) {
  if (level < 0 || level >= static_cast<int>(image.levels.size())) {
    invalid("level " + std::to_string(level) + " is out of range (" +
            std::to_string(image.levels.size()) + " levels)");
  }
  return image.levels[level];
}

// The region of interest: the given one, else the whole image, or for an object the bounding box
// of its control points and the image together (an object moved partly off the image keeps its
// strokes there).
Rect region(const VectorImage& image, const StylizeOptions& options) {
  if (options.roi) return *options.roi;
  double x0 = 0, y0 = 0, x1 = image.width, y1 = image.height;
  if (options.object && *options.object >= 0 && *options.object < static_cast<int>(image.objects.size())) {
    for (const Vec2& p : image.objects[*options.object].mesh.positions) {
      x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
    }
  }
  return {x0, y0, x1 - x0, y1 - y0};
}

// The limit curve of every feature, as polylines (one per piece).
std::vector<std::vector<std::vector<Vec2>>> feature_curves(const ControlMesh& mesh,
                                                           const MeshTopology& topology) {
  std::vector<std::vector<std::vector<Vec2>>> curves(mesh.features.size());
  for (size_t f = 0; f < mesh.features.size(); ++f) {
    for (const CurvePiece& piece : feature_pieces(topology, mesh.features[f])) {
      curves[f].push_back(sample_bspline(piece_points(mesh, piece), piece.closed, kSamplesPerSpan));
    }
  }
  return curves;
}

// The colors alone, at 1x: level `level` without strokes and, for object >= 0, that object over it.
Image8 colors_raster(const VectorImage& image, int level, int object) {
  VectorImage bare;
  bare.width = image.width;
  bare.height = image.height;
  bare.levels = {image.levels[level]};
  if (object >= 0) {
    bare.objects = {image.objects[object]};
    bare.objects[0].level = 0;
    bare.objects[0].visible = true;
    bare.objects[0].strokes.clear();
  }
  return render(bare, RenderOptions{});
}

// The control polygons of `mesh`'s boundary loops (an object's outline), each from its smallest
// vertex, in the order of the triangles' boundary half-edges (a validated object: one outgoing
// boundary half-edge per boundary vertex).
std::vector<std::vector<Vec2>> outline_loops(const ControlMesh& mesh) {
  std::map<std::pair<int32_t, int32_t>, int> directed;
  for (const Tri& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  std::map<int32_t, int32_t> next;
  for (const auto& [e, n] : directed)
    if (!directed.count({e.second, e.first})) next[e.first] = e.second;
  std::vector<std::vector<Vec2>> loops;
  std::set<int32_t> seen;
  for (const auto& [start, unused] : next) {
    if (seen.count(start)) continue;
    std::vector<Vec2> loop;
    for (int32_t v = start; !seen.count(v) && next.count(v); v = next.at(v)) {
      seen.insert(v);
      loop.push_back(mesh.positions[v]);
    }
    if (loop.size() >= 3) loops.push_back(std::move(loop));
  }
  return loops;
}

// Saliency of every feature of `mesh`, level `level`'s mesh (object < 0) or object `object`'s: the
// stored value where non-zero, else eq. 2 measured on the colors alone (the level without strokes
// and, for an object, that object over it), rendered at 1x. `topology` builds the mesh's topology
// (validating it) when a saliency must be measured.
template <class Topology>
std::vector<double> mesh_saliency(const VectorImage& image, int level, int object, const ControlMesh& mesh,
                                  Topology topology, double contrast_weight) {
  std::vector<double> saliency(mesh.features.size(), 0);
  bool unknown = false;
  for (size_t f = 0; f < mesh.features.size(); ++f) {
    saliency[f] = mesh.features[f].saliency;
    unknown |= saliency[f] == 0;
  }
  if (!unknown) return saliency;

  const auto curves = feature_curves(mesh, topology());
  const Image8 raster = colors_raster(image, level, object);
  for (size_t f = 0; f < mesh.features.size(); ++f) {
    if (saliency[f] != 0) continue;
    // Eq. 2 as vectorization measures it (vectorize/levels.h), per piece: lengths add, and the
    // contrast is the length-weighted mean of the pieces' contrasts.
    double length = 0, weighted = 0;
    for (const auto& line : curves[f]) {
      const double piece = polyline_length(line);
      length += piece;
      weighted += piece * (curve_saliency(line, raster, contrast_weight) - piece);
    }
    saliency[f] = length + (length > 0 ? weighted / length : 0.0);
  }
  return saliency;
}

}  // namespace

std::vector<double> feature_saliency(const VectorImage& image, int level, double contrast_weight) {
  const ControlMesh& mesh = level_mesh(image, level);
  return mesh_saliency(image, level, -1, mesh,
                       [&] { return validate_level(mesh, image.width, image.height, level); },
                       contrast_weight);
}

std::vector<Stroke> stylize(const VectorImage& image, const StylizeOptions& options,
                            StylizeReport* report) {
  const int object = options.object.value_or(-1);
  if (options.object && (object < 0 || object >= static_cast<int>(image.objects.size()))) {
    invalid("object " + std::to_string(object) + " is out of range (" + std::to_string(image.objects.size()) +
            " objects)");
  }
  const int level = options.object ? image.objects[object].level : options.level;
  const ControlMesh& mesh = options.object ? image.objects[object].mesh : level_mesh(image, level);
  const Rect roi = region(image, options);
  if (!std::isfinite(roi.x) || !std::isfinite(roi.y) || !std::isfinite(roi.width) ||
      !std::isfinite(roi.height) || !(roi.width > 0) || !(roi.height > 0)) {
    invalid("the region " + num(roi.x) + "," + num(roi.y) + "," + num(roi.width) + "," +
            num(roi.height) + " is empty or not finite");
  }
  if (!(options.probability >= 0 && options.probability <= 1)) {
    invalid("probability " + num(options.probability) + " is outside [0, 1]");
  }
  if (!(options.min_width > 0) || !(options.max_width >= options.min_width) ||
      !std::isfinite(options.max_width)) {
    invalid("stroke widths " + num(options.min_width) + " to " + num(options.max_width) +
            " are not positive and increasing");
  }
  if (!(options.taper >= 0 && options.taper <= 0.5f)) invalid("taper " + num(options.taper) + " is outside [0, 0.5]");
  if (options.threshold && !std::isfinite(*options.threshold)) invalid("the threshold is not finite");
  if (options.threshold && *options.threshold < 0) {
    invalid("the threshold " + num(*options.threshold) + " is negative (saliency is 0 or more)");
  }

  const MeshTopology topology =
      options.object ? validate_object(image.objects[object], image.width, image.height,
                                       static_cast<int>(image.levels.size()), object)
                     : validate_level(mesh, image.width, image.height, level);
  auto curves = feature_curves(mesh, topology);
  std::vector<double> saliency =
      mesh_saliency(image, level, object, mesh, [&] { return topology; }, options.contrast_weight);
  // What each stroke follows: the control points of each piece, and whether it is closed.
  std::vector<std::vector<std::pair<std::vector<Vec2>, bool>>> controls(mesh.features.size());
  for (size_t f = 0; f < mesh.features.size(); ++f)
    for (const CurvePiece& piece : feature_pieces(topology, mesh.features[f]))
      controls[f].push_back({piece_points(mesh, piece), piece.closed});
  // An object's outline is stroked like a closed feature: it was one of the level's.
  if (options.object) {
    const Image8 raster = colors_raster(image, level, object);
    for (std::vector<Vec2>& loop : outline_loops(mesh)) {
      std::vector<Vec2> line = sample_bspline(loop, true, kSamplesPerSpan);
      saliency.push_back(curve_saliency(line, raster, options.contrast_weight));
      curves.push_back({std::move(line)});
      controls.push_back({{std::move(loop), true}});
    }
  }

  // Features in the region: at least half of the curve inside it.
  std::vector<int> in_region;
  std::vector<double> lengths(curves.size(), 0);
  for (size_t f = 0; f < curves.size(); ++f) {
    double inside = 0;
    for (const auto& line : curves[f]) {
      lengths[f] += polyline_length(line);
      walk(line, 0.5, [&](Vec2 p, Vec2) {
        inside += (p.x >= roi.x && p.x <= roi.x + roi.width && p.y >= roi.y &&
                   p.y <= roi.y + roi.height) ? 0.5 : 0.0;
      });
    }
    if (lengths[f] > 0 && inside >= lengths[f] / 2) in_region.push_back(static_cast<int>(f));
  }
  StylizeReport r;
  r.in_region = static_cast<int>(in_region.size());
  if (options.threshold) {
    r.threshold = *options.threshold;
  } else if (!in_region.empty()) {
    std::vector<double> s;
    for (int f : in_region) s.push_back(saliency[f]);
    std::sort(s.begin(), s.end());
    const size_t m = s.size() / 2;
    r.threshold = s.size() % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
  }

  // A portable uniform draw in [0, 1): the top 53 bits of mt19937_64 (std::uniform_real_distribution
  // is implementation-defined).
  std::mt19937_64 rng(options.seed);
  const double full = options.full_width_length > 0
                          ? options.full_width_length
                          : std::max(image.width, image.height) / 2.0;
  std::vector<Stroke> strokes;
  for (int f : in_region) {
    bool take = saliency[f] >= r.threshold;
    if (take) {
      ++r.above;
    } else {
      const double u = double(rng() >> 11) * 0x1.0p-53;
      take = u < options.probability;
      r.chosen += take;
    }
    if (!take) continue;
    const float width = options.min_width + (options.max_width - options.min_width) *
                                                static_cast<float>(std::min(1.0, lengths[f] / full));
    for (const auto& [points, closed] : controls[f]) {
      Stroke s;
      s.level = level;
      s.points = points;
      // A closed loop becomes a path from its first vertex around and back: it starts and ends at
      // that vertex (within the tapers) and follows the loop elsewhere.
      if (closed) s.points.push_back(s.points.front());
      s.width = width;
      s.color = options.color;
      s.taper = options.taper;
      strokes.push_back(std::move(s));
    }
  }
  r.strokes = static_cast<int>(strokes.size());
  if (report) *report = r;
  return strokes;
}

StylizeReport apply_stylize(VectorImage& image, const StylizeOptions& options) {
  StylizeReport report;
  std::vector<Stroke> strokes = stylize(image, options, &report);
  const Rect roi = region(image, options);
  const int level = options.object ? image.objects[*options.object].level : options.level;
  std::vector<Stroke>& owned = options.object ? image.objects[*options.object].strokes : image.strokes;
  const auto in_region = [&](const Stroke& s) {
    if (s.level != level) return false;
    size_t inside = 0;
    for (Vec2 p : s.points) {
      inside += p.x >= roi.x && p.x <= roi.x + roi.width && p.y >= roi.y && p.y <= roi.y + roi.height;
    }
    return 2 * inside >= s.points.size();
  };
  const auto old = std::remove_if(owned.begin(), owned.end(), in_region);
  report.replaced = static_cast<int>(owned.end() - old);
  owned.erase(old, owned.end());
  owned.insert(owned.end(), std::make_move_iterator(strokes.begin()), std::make_move_iterator(strokes.end()));
  return report;
}

}  // namespace subvec
