// The options `subvec vectorize` and `subvec batch` share (vectorize_options.h).
#include "vectorize_options.h"

#include <charconv>
#include <cmath>

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
  options.threads = params.threads;
  if (!params.segment.empty()) {
    subvec::PixelRect rect;
    parse_rect(params.segment, rect);  // already validated by CLI11
    options.segment = rect;
  }
  return options;
}

}  // namespace subvec_cli
