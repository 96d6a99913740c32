// The options `subvec vectorize` and `subvec batch` share (vectorize_options.h).
#include "vectorize_options.h"

#include <charconv>
#include <cmath>
#include <sstream>

namespace subvec_cli {

void add_vertex_count_options(CLI::App* command, VectorizeParams& params) {
  CLI::Option* ratio =
      command
          ->add_option("--ratio", params.ratio,
                       "Control vertices as a fraction of the pixel count (default 0.01)")
          ->check(CLI::Validator(
              [](std::string& text) {
                double v = 0;
                const bool ok =
                    CLI::detail::lexical_cast(text, v) && std::isfinite(v) && v > 0 && v <= 1;
                return ok ? std::string() : "expected a number in (0, 1], got '" + text + "'";
              },
              "RATIO", "ratio"));
  CLI::Option* vertices =
      command->add_option("--vertices", params.vertices, "Control vertex count instead of --ratio")
          ->check(CLI::Range(4, 1 << 26));
  ratio->excludes(vertices);
}

namespace {

// A finite number in [lo, hi], named in the error.
CLI::Validator number_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) {
        double v = 0;
        if (CLI::detail::lexical_cast(text, v) && std::isfinite(v) && v >= lo && v <= hi) return std::string();
        std::ostringstream s;
        s << "expected a number in [" << lo << ", " << hi << "], got '" << text << "'";
        return s.str();
      },
      [lo, hi] {
        std::ostringstream s;
        s << "FLOAT in [" << lo << " - " << hi << "]";
        return s.str();
      }(),
      "number_in");
}

}  // namespace

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
                   "automatic (default: 2 over 2^20 pixels at ratios up to 1/16)")
      ->check(CLI::Range(0, 2));

  // The feature detector (FeatureOptions, features.h); defaults as the library's.
  const subvec::FeatureOptions d;
  auto text = [](double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  };
  const std::string group = "Features";
  command
      ->add_option("--edge-blur", params.features.blur_sigma,
                   "Gaussian blur before the color gradient, pixels (default " + text(d.blur_sigma) +
                       ")")
      ->check(number_in(0, 20))
      ->group(group);
  command
      ->add_option("--edge-quantile", params.features.high_quantile,
                   "Canny's high threshold as this quantile of the image's gradient magnitudes "
                   "(default " + text(d.high_quantile) + ")")
      ->check(number_in(0.01, 0.999))
      ->group(group);
  command
      ->add_option("--edge-min-threshold", params.features.min_high_threshold,
                   "Floor on the high threshold, gray levels per pixel, so that flat or noisy "
                   "images do not sprout features (default " + text(d.min_high_threshold) + ")")
      ->check(number_in(0, 1e4))
      ->group(group);
  command
      ->add_option("--edge-low-ratio", params.features.low_ratio,
                   "Canny's low threshold as a fraction of the high one (default " +
                       text(d.low_ratio) + ")")
      ->check(number_in(0.01, 1))
      ->group(group);
  command
      ->add_option("--min-feature-length", params.features.min_length,
                   "Shorter features are dropped, pixels (default " + text(d.min_length) +
                       "; a length beyond the image keeps none)")
      ->check(number_in(0, 1e6))
      ->group(group);
  command
      ->add_option("--spur-length", params.features.spur_length,
                   "Branches shorter than this at a junction are pruned, pixels (default " +
                       text(d.spur_length) + ")")
      ->check(number_in(0, 1e3))
      ->group(group);
  command
      ->add_option("--max-gap", params.features.max_gap,
                   "Feature ends closer than this are joined, pixels (default " + text(d.max_gap) +
                       ")")
      ->check(number_in(0, 100))
      ->group(group);
  command
      ->add_option("--max-feature-error", params.max_feature_error,
                   "Simplification keeps every feature's limit curve this close to the detected "
                   "edge, pixels (default 1)")
      ->check(number_in(0.05, 100))
      ->group(group);
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
