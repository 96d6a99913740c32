// The options `subvec vectorize`, `subvec batch` and `subvec serve` share (vectorize_options.h).
#include "vectorize_options.h"

#include <charconv>
#include <sstream>

#include "subvec/core/error.h"
#include "validators.h"

namespace subvec_cli {
namespace {

std::string text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The library's field names (subvec::validate()'s messages) and the flags that set them.
struct FlagName {
  const char* field;
  const char* flag;
};
constexpr FlagName kFlagNames[] = {
    {"ratio", "--ratio"},
    {"vertices", "--vertices"},
    {"features.blur_sigma", "--edge-blur"},
    {"features.high_quantile", "--edge-quantile"},
    {"features.min_high_threshold", "--edge-min-threshold"},
    {"features.low_ratio", "--edge-low-ratio"},
    {"features.min_length", "--min-feature-length"},
    {"features.spur_length", "--spur-length"},
    {"features.max_gap", "--max-gap"},
    {"max_feature_error", "--max-feature-error"},
    {"initial_mesh.grid_step", "--grid-step"},
    {"refine.rounds", "--refine"},
    {"fit.l1_iterations", "--l1-iterations"},
    {"fit.relocate_iterations", "--relocate"},
    {"levels.levels", "--levels"},
    {"levels.saliency_weight", "--saliency-weight"},
    {"levels.reduction", "--level-reduction"},
    {"threads", "--threads"},
    {"max_memory", "--max-memory"},
};

// "ID=L" with integers; returns an error message or "" and fills id and level. Which levels
// and ids exist is the library's check (build_levels), once the image is vectorized.
std::string parse_feature_level(const std::string& text, int& id, int& level) {
  const auto eq = text.find('=');
  const std::string expected = "expected ID=LEVEL (two integers), got '" + text + "'";
  if (eq == std::string::npos) return expected;
  auto integer = [](const std::string& s, int& out) {
    if (s.empty()) return false;
    char* end = nullptr;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (*end != '\0' || v < -(1L << 30) || v > (1L << 30)) return false;
    out = static_cast<int>(v);
    return true;
  };
  if (!integer(text.substr(0, eq), id) || !integer(text.substr(eq + 1), level)) return expected;
  return "";
}

}  // namespace

void add_vertex_count_options(CLI::App* command, VectorizeParams& params) {
  const subvec::VectorizeOptions d;
  CLI::Option* ratio =
      command
          ->add_option("--ratio", params.options.ratio,
                       "Control vertices as a fraction of the pixel count (default " +
                           text(d.ratio) + ")")
          ->check(finite_number());
  CLI::Option* vertices =
      command
          ->add_option("--vertices", params.options.vertices,
                       "Control vertex count instead of --ratio (at least 4; 0: use --ratio)")
          ->check(integer());
  ratio->excludes(vertices);
}

void add_quality_options(CLI::App* command, VectorizeParams& params) {
  const subvec::VectorizeOptions d;
  subvec::VectorizeOptions& o = params.options;
  command
      ->add_option("--fit", params.fit,
                   "Color fit: every pixel (default) or the paper's subdivided vertices")
      ->check(CLI::IsMember({"pixels", "vertices"}))
      ->default_str("pixels");
  command
      ->add_option("--l1-iterations", o.fit.l1_iterations,
                   "Reweighted refits of the pixel fit toward least absolute deviations, 0 to 20; 0 is "
                   "plain least squares (default " + std::to_string(d.fit.l1_iterations) + ")")
      ->check(integer());
  command
      ->add_option("--relocate", o.fit.relocate_iterations,
                   "Gauss-Newton steps, 0 to 50, that move the smooth control vertices to lower the "
                   "pixel error before the final color fit; 0 keeps the simplified positions (default " +
                       std::to_string(d.fit.relocate_iterations) + ")")
      ->check(integer());
  command
      ->add_option("--refine", o.refine.rounds,
                   "Rounds of data-dependent vertex moves and edge flips after simplification, 0 to 50 "
                   "(default " + std::to_string(d.refine.rounds) + "; 0 keeps the simplified mesh)")
      ->check(integer());
  command
      ->add_option("--grid-step", o.initial_mesh.grid_step,
                   "Dense mesh away from features: 1 a vertex per pixel, 2, 4 or 8 a quadtree of blocks "
                   "from 2x2, 4x4 or 8x8 pixels down to pixels at the features, 0 automatic (default: "
                   "from 2^17 pixels, 4 at ratios up to 1/64 (8 from 2^21 pixels), 2 up to 1/16)")
      ->check(integer());

  // The feature detector (FeatureOptions, features.h) and the simplifier's feature bound.
  struct NumberOption {
    const char* flag;
    double* value;
    std::string help;
  };
  const subvec::FeatureOptions& df = d.features;
  subvec::FeatureOptions& f = o.features;
  const NumberOption feature_options[] = {
      {"--edge-blur", &f.blur_sigma,
       "Gaussian blur before the color gradient, pixels (default " + text(df.blur_sigma) + ")"},
      {"--edge-quantile", &f.high_quantile,
       "Canny's high threshold as this quantile of the image's gradient magnitudes (default " +
           text(df.high_quantile) + ")"},
      {"--edge-min-threshold", &f.min_high_threshold,
       "Floor on the high threshold, gray levels per pixel, so that flat or noisy images do not "
       "sprout features (default " + text(df.min_high_threshold) + ")"},
      {"--edge-low-ratio", &f.low_ratio,
       "Canny's low threshold as a fraction of the high one (default " + text(df.low_ratio) + ")"},
      {"--min-feature-length", &f.min_length,
       "Shorter features are dropped, pixels (default " + text(df.min_length) +
           "; a length beyond the image keeps none)"},
      {"--spur-length", &f.spur_length,
       "Branches shorter than this at a junction are pruned, pixels (default " + text(df.spur_length) + ")"},
      {"--max-gap", &f.max_gap,
       "Feature ends closer than this are joined, pixels (default " + text(df.max_gap) + ")"},
      {"--max-feature-error", &o.max_feature_error,
       "Simplification keeps every feature's limit curve this close to the detected edge, pixels "
       "(default " + text(d.max_feature_error) + ")"},
  };
  for (const NumberOption& n : feature_options) {
    command->add_option(n.flag, *n.value, n.help)->check(finite_number())->group("Features");
  }
}

void add_level_options(CLI::App* command, VectorizeParams& params, bool levels_only) {
  const subvec::LevelOptions d;
  subvec::LevelOptions& o = params.options.levels;
  command
      ->add_option("--levels", o.levels,
                   "Levels of abstraction, 1 to 16, level 0 the finest with every feature (default " +
                       std::to_string(d.levels) + "; 1: a single level)")
      ->check(integer());
  if (levels_only) return;
  command
      ->add_option("--saliency-weight", o.saliency_weight,
                   "w in the saliency S = length + w * contrast that orders features (default " +
                       text(d.saliency_weight) + ")")
      ->check(finite_number());
  command
      ->add_option("--level-reduction", o.reduction,
                   "Share of the vertices each coarser level removes (default " + text(d.reduction) + ")")
      ->check(finite_number());
  command
      ->add_option("--feature-level", params.feature_levels,
                   "ID=L: feature ID stays up to level L (repeatable; ids as `subvec info --json` lists)")
      ->check(CLI::Validator(
          [](std::string& text) {
            int id = 0, level = 0;
            return parse_feature_level(text, id, level);
          },
          "ID=L", "feature-level"));
}

void add_limit_options(CLI::App* command, VectorizeParams& params, int64_t& max_pixels) {
  max_pixels = subvec::kDefaultMaxInputPixels;
  command
      ->add_option("--max-pixels", max_pixels,
                   "Refuse larger images (default " + std::to_string(max_pixels) +
                       ", 2^25: a 24 MP photograph is read; what it may cost is --max-memory)")
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 30));
  command
      ->add_option("--max-memory", params.options.max_memory,
                   "Refuse an image whose estimated peak memory is larger (6G, 800MB, bytes; default "
                   "0: the memory available when the job starts)")
      ->transform(CLI::AsSizeValue(/*kb_is_1000=*/true))
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 50));
}

void add_vectorize_options(CLI::App* command, VectorizeParams& params) {
  add_vertex_count_options(command, params);
  command
      ->add_option("--segment", params.segment,
                   "GrabCut from this rectangle (image pixels X,Y,W,H); the foreground's boundary "
                   "becomes a closed tear")
      ->check(CLI::Validator(
          [](std::string& text) {
            subvec::PixelRect r;
            return parse_rect(text, r);
          },
          "X,Y,W,H", "rect"));
  add_quality_options(command, params);
  command
      ->add_option("--threads", params.options.threads,
                   "Worker threads; 0 (default) uses all cores; the output does not depend on it")
      ->check(integer());
  add_level_options(command, params);
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

std::string with_flag_names(const std::string& message) {
  for (const FlagName& n : kFlagNames) {
    const std::string field = std::string(n.field) + " ";
    if (message.rfind(field, 0) == 0) return n.flag + message.substr(field.size() - 1);
  }
  return message;
}

subvec::VectorizeOptions vectorize_options(const VectorizeParams& params) {
  subvec::VectorizeOptions options = params.options;
  options.fit.target = params.fit == "vertices" ? subvec::ColorFitTarget::kRefinedVertices
                                                : subvec::ColorFitTarget::kPixels;
  if (!params.segment.empty()) {
    subvec::PixelRect rect;
    parse_rect(params.segment, rect);  // already validated by CLI11
    options.segment = rect;
  }
  for (const std::string& text : params.feature_levels) {
    int id = 0, level = 0;
    parse_feature_level(text, id, level);  // already validated by CLI11
    options.levels.feature_levels.push_back({id, level});
  }
  try {
    subvec::validate(options);
  } catch (const subvec::Error& e) {
    throw CLI::ValidationError(with_flag_names(e.what()));
  }
  return options;
}

}  // namespace subvec_cli
