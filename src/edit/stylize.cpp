// Stylization (edit/stylize.h): saliency (paper eq. 2) and strokes along features (paper §6.3).
#include "subvec/edit/stylize.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
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

}  // namespace

std::vector<double> feature_saliency(const VectorImage& image, int level, double contrast_weight) {
  const ControlMesh& mesh = level_mesh(image, level);
  std::vector<double> saliency(mesh.features.size(), 0);
  bool unknown = false;
  for (size_t f = 0; f < mesh.features.size(); ++f) {
    saliency[f] = mesh.features[f].saliency;
    unknown |= saliency[f] == 0;
  }
  if (!unknown) return saliency;

  const MeshTopology topology = validate_level(mesh, image.width, image.height, level);
  const auto curves = feature_curves(mesh, topology);
  // The colors alone: a copy of the level without strokes, rendered at 1x.
  VectorImage bare;
  bare.width = image.width;
  bare.height = image.height;
  bare.levels = {mesh};
  const Image8 raster = render(bare, RenderOptions{});
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

std::vector<Stroke> stylize(const VectorImage& image, const StylizeOptions& options,
                            StylizeReport* report) {
  const ControlMesh& mesh = level_mesh(image, options.level);
  const Rect roi = options.roi.value_or(Rect{0, 0, double(image.width), double(image.height)});
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

  const MeshTopology topology = validate_level(mesh, image.width, image.height, options.level);
  const auto curves = feature_curves(mesh, topology);
  const std::vector<double> saliency =
      feature_saliency(image, options.level, options.contrast_weight);

  // Features in the region: at least half of the curve inside it.
  std::vector<int> in_region;
  std::vector<double> lengths(mesh.features.size(), 0);
  for (size_t f = 0; f < mesh.features.size(); ++f) {
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
    for (const CurvePiece& piece : feature_pieces(topology, mesh.features[f])) {
      Stroke s;
      s.level = options.level;
      s.points = piece_points(mesh, piece);
      // A closed loop becomes a path from its first vertex around and back: it starts and ends at
      // that vertex (within the tapers) and follows the loop elsewhere.
      if (piece.closed) s.points.push_back(s.points.front());
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
  const Rect roi = options.roi.value_or(Rect{0, 0, double(image.width), double(image.height)});
  const auto in_region = [&](const Stroke& s) {
    if (s.level != options.level) return false;
    size_t inside = 0;
    for (Vec2 p : s.points) {
      inside += p.x >= roi.x && p.x <= roi.x + roi.width && p.y >= roi.y && p.y <= roi.y + roi.height;
    }
    return 2 * inside >= s.points.size();
  };
  const auto old = std::remove_if(image.strokes.begin(), image.strokes.end(), in_region);
  report.replaced = static_cast<int>(image.strokes.end() - old);
  image.strokes.erase(old, image.strokes.end());
  image.strokes.insert(image.strokes.end(), std::make_move_iterator(strokes.begin()),
                       std::make_move_iterator(strokes.end()));
  return report;
}

}  // namespace subvec
