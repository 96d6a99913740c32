// Stage 4 of vectorization (paper §4, "Color optimization"): all control colors at once, each side
// of a tear separately, by sparse least squares through the subdivision stencils.
//
// Beyond the paper, the default fits every pixel: a pixel centre lies in a refined triangle whose
// color is a fixed sparse combination of control colors (limit stencils x barycentric weights): the
// fitted image is the renderer's, drawn one subdivision level coarser (kFitEdgePixels). Pixels
// within `band` of a tear take target colors filled in from their own side (the paper's hole
// filling), so color never bleeds across a tear.
// The paper's fit at the subdivided vertices is kept as an option for comparison.
#pragma once

#include <atomic>
#include <string>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {

enum class ColorFitTarget { kPixels, kRefinedVertices };

struct ColorFitOptions {
  ColorFitTarget target = ColorFitTarget::kPixels;
  int depth = -1;             // subdivision depth of the fit; -1: default_fit_depth()
  double band = 0.5;          // pixels this close to a tear get hole-filled targets
  double fill_radius = 3.0;   // how far hole filling looks for same-side pixels
  double regularization = 1e-6;  // relative Tikhonov weight toward the current colors
  // Reweighted refits toward the least-absolute-deviations fit (pixel target only; 0: plain least
  // squares). Each weighs a pixel by 1 / max(its mean absolute residual, l1_floor) and costs a
  // second assembly and factorization; the default one lowers the MAE of every shared photograph
  // (docs/vectorize.md, "Large images").
  int l1_iterations = 1;
  double l1_floor = 1.0;  // 0-255 scale
  // Measure the residual (ColorFitStats::rms and mae: one more pass over the pixels); the coarser
  // levels, whose stats nobody reads, skip it.
  bool measure = true;
  // Damped Gauss-Newton steps that move the smooth control vertices (not those of features, creases,
  // the border or corners) to lower the squared pixel error, each kept only when the refit colors
  // lower it (pixel target only; 0: positions as given).
  int relocate_iterations = 0;
  double relocate_damping = 1.0;   // initial Levenberg-Marquardt factor on the diagonal
  double relocate_max_step = 2.0;  // pixels a vertex moves at most per step
  int relocate_cg_iterations = 12; // conjugate-gradient iterations per step
  int relocate_refit_every = 3;    // steps between color refits (and after the last)
  int threads = 0;               // <= 0: all cores; the result does not depend on it
  // When set and true, fit_colors() throws Error(kCancelled) before its solve or at its next
  // relocation or reweighting step (the mesh stays valid and keeps its colors).
  const std::atomic<bool>* cancel = nullptr;
};

struct ColorFitStats {
  int rows = 0;          // pixels or refined vertices fitted
  int filled = 0;        // band pixels given hole-filled targets
  double rms = 0;        // root-mean-square residual over the located pixels, 0-255 scale
  double mae = 0;        // mean absolute error of the 8-bit prediction at pixel centres
  int relocations = 0;   // relocation steps kept
};

// Refits mesh.colors in place against `image` (same size as the domain). Throws kInvalidArgument.
// Throws Error(kInvalidArgument) naming the first field out of range, prefixed by `prefix`;
// fit_colors() calls it.
void validate(const ColorFitOptions& options, const std::string& prefix = {});

ColorFitStats fit_colors(ControlMesh& mesh, int width, int height, const Image8& image,
                         const ColorFitOptions& options = {});

// Refined edges of the fit average at most this many pixels. That is twice the renderer's 2.5 px
// at 1x, one level coarser: the fit's refined triangles carry the color field, which is smooth
// between tears. Fitting at the renderer's level changed the rendered MAE by at most 0.1 % at
// ratio 0.01 and 1 % at 0.03 on the shared photographs, for four times the fit's time and memory
// (docs/vectorize.md, "Fit depth").
inline constexpr double kFitEdgePixels = 5.0;

// The fit's depth rule: smallest k in 0..5 with mean_edge_pixels / 2^k <= kFitEdgePixels.
int fit_depth_for_mean_edge(double mean_edge_pixels);

// The rule for `mesh`: fit_depth_for_mean_edge() of its mean control edge.
int default_fit_depth(const ControlMesh& mesh);

}  // namespace subvec
