// The options `subvec vectorize` and `subvec batch` share (vectorize_options.h).
#include "vectorize_options.h"

#include <charconv>
#include <sstream>

#include "validators.h"

namespace subvec_cli {

void add_vertex_count_options(CLI::App* command, VectorizeParams& params) {
  CLI::Option* ratio =
      command
          ->add_option("--ratio", params.ratio,
                       "Control vertices as a fraction of the pixel count (default 0.01)")
          ->check(fraction());
  CLI::Option* vertices =
      command->add_option("--vertices", params.vertices, "Control vertex count instead of --ratio")
          ->check(CLI::Range(4, 1 << 26));
  ratio->excludes(vertices);
}

void add_quality_options(CLI::App* command, VectorizeParams& params) {
  command
      ->add_option("--fit", params.fit,
                   "Color fit: every pixel (default) or the paper's subdivided vertices")
      ->check(CLI::IsMember({"pixels", "vertices"}))
      ->default_str("pixels");
  command
      ->add_option("--l1-iterations", params.l1_iterations,
                   "Reweighted refits of the pixel fit toward least absolute deviations; 0 is plain "
                   "least squares (default)")
      ->check(CLI::Range(0, 20));
  command
      ->add_option("--relocate", params.relocate,
                   "Gauss-Newton steps that move the smooth control vertices to lower the pixel "
                   "error before the final color fit; 0 keeps the simplified positions (default)")
      ->check(CLI::Range(0, 50));
  command
      ->add_option("--refine", params.refine,
                   "Rounds of data-dependent vertex moves and edge flips after simplification (default " +
                       std::to_string(subvec::RefineOptions{}.rounds) + "; 0 keeps the simplified mesh)")
      ->check(CLI::Range(0, 50));
  command
      ->add_option("--grid-step", params.grid_step,
                   "Dense mesh away from features: 1 a vertex per pixel, 2 per 2x2 block, 0 "
                   "automatic (default: 2 from 2^18 pixels, 512x512, at ratios up to 1/16)")
      ->check(CLI::Range(0, 2));

  // The feature detector (FeatureOptions, features.h), defaults as the library's, and the
  // simplifier's feature bound: finite numbers in a range.
  const subvec::FeatureOptions d;
  auto text = [](double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  };
  struct NumberOption {
    const char* flag;
    double* value;
    std::string help;
    double lo, hi;
  };
  subvec::FeatureOptions& f = params.features;
  const NumberOption feature_options[] = {
      {"--edge-blur", &f.blur_sigma,
       "Gaussian blur before the color gradient, pixels (default " + text(d.blur_sigma) + ")", 0, 20},
      {"--edge-quantile", &f.high_quantile,
       "Canny's high threshold as this quantile of the image's gradient magnitudes (default " +
           text(d.high_quantile) + ")",
       0.01, 0.999},
      {"--edge-min-threshold", &f.min_high_threshold,
       "Floor on the high threshold, gray levels per pixel, so that flat or noisy images do not "
       "sprout features (default " + text(d.min_high_threshold) + ")",
       0, 1e4},
      {"--edge-low-ratio", &f.low_ratio,
       "Canny's low threshold as a fraction of the high one (default " + text(d.low_ratio) + ")", 0.01, 1},
      {"--min-feature-length", &f.min_length,
       "Shorter features are dropped, pixels (default " + text(d.min_length) +
           "; a length beyond the image keeps none)",
       0, 1e6},
      {"--spur-length", &f.spur_length,
       "Branches shorter than this at a junction are pruned, pixels (default " + text(d.spur_length) + ")", 0,
       1e3},
      {"--max-gap", &f.max_gap, "Feature ends closer than this are joined, pixels (default " + text(d.max_gap) + ")",
       0, 100},
      {"--max-feature-error", &params.max_feature_error,
       "Simplification keeps every feature's limit curve this close to the detected edge, pixels "
       "(default 1)",
       0.05, 100},
  };
  for (const NumberOption& o : feature_options) {
    command->add_option(o.flag, *o.value, o.help)->check(number_in(o.lo, o.hi))->group("Features");
  }
}

std::string parse_rect(const std::string& text, subvec::PixelRect& r) {
  const std::string usage = "expected four integers X,Y,W,H, got '" + text + "'";
  int v[4];
  const char* p = text.data();
  const char* const end = text.data() + text.size();
  for (int k = 0; k < 4; ++k) {
    const auto [next, ec] = std::from_chars(p, end, v[k]);
    if (ec != std::errc() || next == p) return usage;
    p = next;
    if (k < 3) {
      if (p == end || *p != ',') return usage;
      ++p;
    }
  }
  if (p != end) return usage;
  if (v[2] <= 0 || v[3] <= 0)
    return "the rectangle '" + text + "' is empty (W and H must be positive)";
  r = {v[0], v[1], v[2], v[3]};
  return "";
}

subvec::VectorizeOptions vectorize_options(const VectorizeParams& params) {
  subvec::VectorizeOptions options;
  options.ratio = params.ratio;
  options.vertices = params.vertices;
  options.initial_mesh.grid_step = params.grid_step;
  options.fit.target = params.fit == "vertices" ? subvec::ColorFitTarget::kRefinedVertices
                                                : subvec::ColorFitTarget::kPixels;
  options.fit.l1_iterations = params.l1_iterations;
  options.fit.relocate_iterations = params.relocate;
  options.refine.rounds = params.refine;
  options.features = params.features;
  options.max_feature_error = params.max_feature_error;
  options.threads = params.threads;
  if (!params.segment.empty()) {
    subvec::PixelRect rect;
    parse_rect(params.segment, rect);  // already validated by CLI11
    options.segment = rect;
  }
  return options;
}

}  // namespace subvec_cli
