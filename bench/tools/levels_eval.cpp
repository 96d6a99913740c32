// subvec_levels_eval: levels of abstraction and the pyramid on one photograph, for scripts/eval and
// docs/levels.md. Not a test: the seconds are only meaningful on an idle machine.
//
//   subvec_levels_eval PHOTO [--runs N] [--figures PREFIX] [--features]
//
// Prints one JSON line: the median seconds over N runs (default 3) of single-level vectorization,
// of building levels 1 and 2 on top of it and of `filter` with eta = 0.3; per level its vertices,
// features and MAE against the photo; and the contrast across every feature of the coarsest level
// (points 1 px apart along its limit curve, colors 1.5 px to each side) after eta = 0.3 and after a
// Gaussian blur of the vector image whose sigma removes as much high-frequency energy (the mean
// squared Laplacian over pixels 3 px or more from every feature): the mean and worst relative
// change, the smallest contrast, the worst change in levels, and how many features changed by more
// than 5 % and by more than both 5 % and one color level (--features lists them on stderr). Then
// that high-frequency energy after color filtering at eta = 0, 0.1, ..., 1, 1.25, 1.5, 2 and
// whether it rises throughout. With --figures it writes
// PREFIX-levels.png (as the paper's Fig. 7) and PREFIX-filter.png (as its Fig. 13).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "subvec/core/error.h"
#include "subvec/core/metrics.h"
#include "subvec/io/image_io.h"
#include "subvec/vectorize/levels.h"
#include "subvec/pyramid/pyramid.h"
#include "subvec/render/renderer.h"
#include "subvec/vectorize/vectorize.h"
#include "support/image_measures.h"

namespace subvec {
namespace {

using test::away_from_features;
using test::contrast_across;
using test::fine_laplacian_energy;
using test::laplacian_energy;

double median_seconds(int runs, const std::function<void()>& f) {
  std::vector<double> t;
  for (int i = 0; i < runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

cv::Mat as_mat(const Image8& image) {
  cv::Mat m(image.height, image.width, CV_8UC3, const_cast<uint8_t*>(image.pixels.data()));
  return m.clone();
}

Image8 from_mat(const cv::Mat& m) {
  Image8 out(m.cols, m.rows, 3);
  for (int y = 0; y < m.rows; ++y) std::copy_n(m.ptr<uint8_t>(y), size_t(m.cols) * 3, out.row(y));
  return out;
}

Image8 render_level(const VectorImage& image, int level, Overlay overlay = Overlay::kNone) {
  RenderOptions o;
  o.level = level;
  o.overlay = overlay;
  return render(image, o);
}

const Feature& by_id(const ControlMesh& m, int32_t id) {
  for (const Feature& f : m.features)
    if (f.id == id) return f;
  throw Error(ErrorCode::kInvalidArgument, "feature " + std::to_string(id) + " missing");
}

cv::Mat tile(const cv::Mat& m, int width, const std::string& text) {
  cv::Mat out;
  const double s = double(width) / m.cols;
  cv::resize(m, out, cv::Size(width, std::max(1, int(m.rows * s + 0.5))), 0, 0, s < 1 ? cv::INTER_AREA : cv::INTER_NEAREST);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, font, 0.45, 1, &baseline);
  cv::rectangle(out, cv::Rect(0, 0, size.width + 8, size.height + baseline + 6), cv::Scalar(255, 255, 255), cv::FILLED);
  cv::putText(out, text, cv::Point(4, size.height + 3), font, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return out;
}

cv::Mat difference(const Image8& a, const Image8& b, double gain) {
  cv::Mat d(a.height, a.width, CV_8UC3);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width * 3; ++x)
      d.ptr<uint8_t>(y)[x] = cv::saturate_cast<uint8_t>(255 - gain * std::abs(int(a.row(y)[x]) - int(b.row(y)[x])));
  return d;
}

int run(int argc, char** argv) {
  std::string photo_path, figures;
  int runs = 3;
  bool dump = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) runs = std::max(1, std::stoi(argv[++i]));
    else if (a == "--features") dump = true;
    else if (a == "--figures" && i + 1 < argc) figures = argv[++i];
    else if (photo_path.empty()) photo_path = a;
    else throw Error(ErrorCode::kInvalidArgument, "unexpected argument '" + a + "'");
  }
  if (photo_path.empty()) throw Error(ErrorCode::kInvalidArgument, "usage: subvec_levels_eval PHOTO [--runs N] [--figures PREFIX] [--features]");
  const Image8 photo = read_image(photo_path);
  VectorImage single;
  VectorizeOptions one_level;  // vectorize() without levels 1 and up: they are timed below
  one_level.levels.levels = 1;
  const double vectorize_s = median_seconds(runs, [&] { single = vectorize(photo, one_level); });
  VectorImage image;
  const double levels_s = median_seconds(runs, [&] {
    image = single;
    build_levels(image, photo, {});
  });
  VectorImage smooth;
  FilterOptions f03;
  f03.color_eta = {0.3};  // colors, the command's default
  const double filter_s = median_seconds(runs, [&] { smooth = filter(image, f03); });

  std::string levels_json;
  for (size_t l = 0; l < image.levels.size(); ++l) {
    const double mae = compare(photo, render_level(image, int(l))).mae_mean;
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s{\"vertices\": %d, \"features\": %zu, \"mae\": %.3f}", l ? ", " : "",
                  image.levels[l].num_vertices(), image.levels[l].features.size(), mae);
    levels_json += buf;
  }

  // Contrast across the coarsest level's features: eta = 0.3 against a matched Gaussian blur.
  const Image8 before = render_level(image, 0), after = render_level(smooth, 0);
  const auto mask = away_from_features(image, 3.0);
  const double target = laplacian_energy(after, mask);
  double sigma = 0.3;
  cv::Mat blurred;
  for (;; sigma *= 1.05) {
    cv::GaussianBlur(as_mat(before), blurred, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    if (laplacian_energy(from_mat(blurred), mask) <= target || sigma > 10) break;
  }
  const Image8 blurred_image = from_mat(blurred);
  double eta_worst = 0, eta_mean = 0, blur_worst = 0, blur_mean = 0, min_contrast = 1e9, worst_levels = 0;
  int over = 0, over_floor = 0;  // features changed by > 5 %, and by > 5 % and > 1 level
  const auto& kept = image.levels.back().features;
  for (const Feature& k : kept) {
    const Feature& f = by_id(image.levels[0], k.id);
    const double c0 = contrast_across(before, image.levels[0], f, 1.5);
    const double c1 = contrast_across(after, smooth.levels[0], by_id(smooth.levels[0], k.id), 1.5);
    const double cb = contrast_across(blurred_image, image.levels[0], f, 1.5);
    eta_worst = std::max(eta_worst, std::abs(c1 / c0 - 1)), eta_mean += (c1 / c0 - 1) / static_cast<double>(kept.size());
    blur_worst = std::max(blur_worst, std::abs(cb / c0 - 1)), blur_mean += (cb / c0 - 1) / static_cast<double>(kept.size());
    min_contrast = std::min(min_contrast, c0);
    worst_levels = std::max(worst_levels, std::abs(c1 - c0));
    if (std::abs(c1 - c0) > 0.05 * c0) ++over;
    if (std::abs(c1 - c0) > std::max(0.05 * c0, 1.0)) ++over_floor;
    if (dump)
      std::fprintf(stderr, "feature %d: contrast %.2f -> %.2f (%+.1f %%), blur %.2f\n", k.id, c0, c1, 100 * (c1 / c0 - 1), cb);
  }
  // The high-frequency energy over eta (colors): should fall as eta decreases below 1, rise above.
  // Also measured to 1/16 of a color level (fine_laplacian_energy), without the 8-bit rounding.
  std::string sweep_json, fine_json;
  bool monotone = true, fine_monotone = true;
  double last = -1, fine_last = -1;
  for (const double eta : {0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.25, 1.5, 2.0}) {
    FilterOptions o;
    o.color_eta = {eta};
    const VectorImage filtered = filter(image, o);
    const double e = laplacian_energy(render_level(filtered, 0), mask);
    const double fine = fine_laplacian_energy(filtered, mask);
    if (e <= last) monotone = false;
    if (fine <= fine_last) fine_monotone = false;
    last = e, fine_last = fine;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%.2f", sweep_json.empty() ? "" : ", ", e);
    sweep_json += buf;
    std::snprintf(buf, sizeof buf, "%s%.3f", fine_json.empty() ? "" : ", ", fine);
    fine_json += buf;
  }
  std::printf(
      "{\"vectorize_s\": %.3f, \"levels_s\": %.3f, \"added\": %.3f, \"filter_s\": %.3f, \"levels\": [%s], "
      "\"contrast\": {\"features\": %zu, \"eta_mean\": %.4f, \"eta_worst\": %.4f, \"blur_sigma\": %.3f, "
      "\"blur_mean\": %.4f, \"blur_worst\": %.4f, \"laplacian_before\": %.2f, \"laplacian_after\": %.2f, "
      "\"min_contrast\": %.2f, \"worst_levels\": %.2f, \"over_5pct\": %d, \"over_5pct_and_1_level\": %d}, "
      "\"sweep\": {\"monotone\": %s, \"energy\": [%s], \"fine_monotone\": %s, "
      "\"fine_energy\": [%s]}}\n",
      vectorize_s, levels_s, levels_s / vectorize_s, filter_s, levels_json.c_str(), kept.size(), eta_mean, eta_worst,
      sigma, blur_mean, blur_worst, laplacian_energy(before, mask), target, min_contrast, worst_levels, over, over_floor,
      monotone ? "true" : "false", sweep_json.c_str(), fine_monotone ? "true" : "false",
      fine_json.c_str());

  if (!figures.empty()) {
    const int w = 256;
    // Fig. 7: the photo and three levels; below, the control meshes around the busiest spot.
    std::vector<cv::Mat> top = {tile(as_mat(photo), w, "original")}, bottom;
    const int side = std::min({96, image.width, image.height});
    const int cx = std::clamp(image.width / 2 - side / 2, 0, image.width - side);
    const int cy = std::clamp(image.height / 2 - side / 2, 0, image.height - side);
    const cv::Rect crop(cx, cy, side, side);
    bottom.push_back(tile(as_mat(photo)(crop), w, "crop"));
    for (size_t l = 0; l < image.levels.size() && l < 3; ++l) {
      top.push_back(tile(as_mat(render_level(image, int(l))), w, "level " + std::to_string(l)));
      RenderOptions o;
      o.level = int(l);
      o.overlay = Overlay::kMesh;
      o.window = Window{double(cx), double(cy), double(cx + side), double(cy + side)};
      o.width = w;
      bottom.push_back(tile(as_mat(render(image, o)), w, "mesh " + std::to_string(l)));
    }
    cv::Mat a, b, sheet;
    cv::hconcat(top, a);
    cv::hconcat(bottom, b);
    cv::vconcat(std::vector<cv::Mat>{a, b}, sheet);
    write_png(figures + "-levels.png", from_mat(sheet));
    // Fig. 13: raster, smoothed, difference; vector, enhanced, difference.
    FilterOptions f18;
    f18.color_eta = {1.8};
    const Image8 sharp = render_level(filter(image, f18), 0);
    cv::Mat r1, r2, fig;
    cv::hconcat(std::vector<cv::Mat>{tile(as_mat(photo), w, "raster"), tile(as_mat(after), w, "eta 0.3"),
                                     tile(difference(after, before, 4), w, "|eta 0.3 - vector| x4")},
                r1);
    cv::hconcat(std::vector<cv::Mat>{tile(as_mat(before), w, "vector"), tile(as_mat(sharp), w, "eta 1.8"),
                                     tile(difference(sharp, before, 4), w, "|eta 1.8 - vector| x4")},
                r2);
    cv::vconcat(std::vector<cv::Mat>{r1, r2}, fig);
    write_png(figures + "-filter.png", from_mat(fig));
    cv::Mat g;
    cv::hconcat(std::vector<cv::Mat>{tile(as_mat(before), w, "vector"), tile(as_mat(after), w, "pyramid eta 0.3"),
                                     tile(blurred, w, "Gaussian sigma " + std::to_string(sigma).substr(0, 4))},
                g);
    write_png(figures + "-blur.png", from_mat(g));
  }
  return 0;
}

}  // namespace
}  // namespace subvec

int main(int argc, char** argv) {
  try {
    return subvec::run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "subvec_levels_eval: %s\n", e.what());
    return 1;
  }
}
