// subvec: the command-line front end. It only translates: options -> parameter structs -> library
// calls -> files and text (docs/cli.md). Error policy: a subvec::Error or any other exception
// becomes one line "subvec: <message>" on stderr and exit status 1; a command-line mistake found by
// CLI11 becomes one line "subvec: <command>: <message>; <hint>" (usage_error: the closest option or
// command name, messages.h, or the help to read) and CLI11's exit status (100-114). Outputs are written atomically by the library, so a failed run never leaves a
// partial file and never clobbers an existing one.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <new>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/core/metrics.h"
#include "subvec/export/export.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"
#include "subvec/vectorize/vectorize.h"

#include "batch.h"
#include "cancel.h"
#include "edit_commands.h"
#include "memory.h"
#include "messages.h"
#include "progress.h"
#include "pyramid_commands.h"  // filter
#include "validators.h"
#include "vectorize_options.h"
// serve (issue 7): the browser editor, apps/serve/
#include "serve_command.h"

#ifndef SUBVEC_VERSION
#define SUBVEC_VERSION "unknown"
#endif

namespace {

namespace fs = std::filesystem;
using subvec::Error;
using subvec::ErrorCode;
using subvec_cli::one_line;

std::string in_quotes(const fs::path& p) { return "'" + p.string() + "'"; }

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// ---- --window X0,Y0,X1,Y1 --------------------------------------------------------------------

// Parses "X0,Y0,X1,Y1"; returns an error message, or "" and fills `w`.
std::string parse_window(const std::string& text, subvec::Window& w) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const char* begin = item.c_str();
    char* end = nullptr;
    const double x = std::strtod(begin, &end);
    while (end && std::isspace(static_cast<unsigned char>(*end))) ++end;
    if (item.empty() || end == begin || *end != '\0' || !std::isfinite(x)) {
      return "expected four numbers X0,Y0,X1,Y1, got '" + text + "'";
    }
    v.push_back(x);
  }
  if (v.size() != 4 || (!text.empty() && text.back() == ',')) {
    return "expected four numbers X0,Y0,X1,Y1, got '" + text + "'";
  }
  if (!(v[0] < v[2]) || !(v[1] < v[3])) {
    return "the window must have X0 < X1 and Y0 < Y1, got '" + text + "'";
  }
  w = {v[0], v[1], v[2], v[3]};
  return "";
}

// ---- render ----------------------------------------------------------------------------------

struct RenderArgs {
  std::string input, output;
  int width = 0;
  double scale = 1;
  std::string window;
  int level = 0;
  std::string overlay = "none";  // none, mesh or features (checked by CLI11)
  bool no_aa = false;
  int threads = 0;
  int depth = -1;
  double tolerance = 0.25;  // .pdf and .svg only
  std::string pdf_target = "any";  // .pdf only: any or poppler (checked by CLI11)
  std::string svg_target = "browser";  // .svg only: browser or inkscape (checked by CLI11)
  double svg_color_tolerance = subvec::ExportOptions{}.linear_color_tolerance;  // .svg, browser
  bool verbose = false;     // -v: what a vector export holds
  bool gpu = false;         // --gpu (issue 10, docs/gpu.md)
  int64_t max_pixels = subvec::RenderOptions{}.max_pixels;  // the library's default
};

// Output formats by extension: .png rasterizes; .pdf and .svg export the limit mesh
// (subvec/export/export.h).
void check_image_output(const fs::path& out) {
  const std::string ext = lower(out.extension().string());
  if (ext == ".png" || subvec::is_vector_export(out)) return;
  if (ext.empty()) {
    throw Error(ErrorCode::kInvalidArgument,
                "output " + in_quotes(out) + " has no extension (supported: .png, .pdf, .svg)");
  }
  throw Error(ErrorCode::kInvalidArgument, "unsupported output format '" + ext + "' for " +
                                               in_quotes(out) + " (supported: .png, .pdf, .svg)");
}

// .pdf / .svg: the whole image at --scale (or --width), refined to --tolerance.
void run_vector_export(const RenderArgs& a, const subvec::VectorImage& image, bool width_given,
                       bool scale_given) {
  if (!a.window.empty() || lower(a.overlay) != "none") {
    throw Error(ErrorCode::kInvalidArgument,
                "--window and --overlay apply to .png output only, not to " + in_quotes(a.output));
  }
  subvec::ExportOptions options;
  options.level = a.level;
  if (width_given) options.width = a.width;
  if (scale_given) options.scale = a.scale;
  options.tolerance = a.tolerance;
  options.depth = a.depth;
  options.pdf_target =
      lower(a.pdf_target) == "poppler" ? subvec::PdfTarget::kPoppler : subvec::PdfTarget::kAny;
  options.svg_target = lower(a.svg_target) == "inkscape" ? subvec::SvgTarget::kInkscape
                                                         : subvec::SvgTarget::kBrowser;
  options.linear_color_tolerance = a.svg_color_tolerance;
  subvec::ExportReport report;
  subvec::write_vector_export(a.output, image, options, &report);
  if (a.verbose) {
    std::string pieces =
        report.patches ? std::to_string(report.patches) + " mesh patches (one per control face)"
                       : std::to_string(report.triangles) + " triangles (control faces at depths " +
                             std::to_string(report.min_depth) + " to " +
                             std::to_string(report.depth) + ")";
    if (report.shapes > 0) {
      pieces += " in " + std::to_string(report.shapes) + " shapes, " + std::to_string(report.gradients) +
                " of them linear gradients";
    }
    std::fprintf(stderr, "subvec: %s: %s, %lld tear hints, %lld strokes, %lld bytes\n",
                 a.output.c_str(), pieces.c_str(), static_cast<long long>(report.tear_hints),
                 static_cast<long long>(report.strokes), static_cast<long long>(report.bytes));
  }
}

void run_render(const RenderArgs& a, bool width_given, bool scale_given) {
  check_image_output(a.output);
  const subvec::VectorImage image = subvec::read_svec(a.input);

  const int num_levels = static_cast<int>(image.levels.size());
  if (a.level >= num_levels) {
    throw Error(ErrorCode::kInvalidArgument, "--level " + std::to_string(a.level) +
                                                 " is out of range: " + in_quotes(a.input) +
                                                 " has " + std::to_string(num_levels) +
                                                 (num_levels == 1 ? " level" : " levels") +
                                                 " (0 to " + std::to_string(num_levels - 1) + ")");
  }

  if (subvec::is_vector_export(a.output)) {
    run_vector_export(a, image, width_given, scale_given);
    return;
  }

  // Output size (subvec::render_size): explicit width (height keeps the window's aspect), or the
  // window's size times the scale (1 by default).
  subvec::RenderOptions options;
  if (!a.window.empty()) {
    subvec::Window window;
    parse_window(a.window, window);  // already validated by CLI11
    options.window = window;
  }
  if (width_given) options.width = a.width;
  if (scale_given) options.scale = a.scale;
  options.max_pixels = a.max_pixels;
  subvec::RenderSize size;
  try {
    size = subvec::render_size(options, image.width, image.height);
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kLimit) throw;
    throw Error(e.code(), std::string(e.what()) + " (--max-pixels raises the limit)");
  }
  options.level = a.level;
  const std::string overlay = lower(a.overlay);
  options.overlay = overlay == "mesh"       ? subvec::Overlay::kMesh
                    : overlay == "features" ? subvec::Overlay::kFeatures
                                            : subvec::Overlay::kNone;
  options.antialias = !a.no_aa;
  options.threads = a.threads;
  options.depth = a.depth;
  // --gpu (docs/gpu.md): OpenGL through headless EGL; without a context, or when the context is a
  // software rasterizer (slower than the CPU renderer), one line and the CPU.
  if (a.gpu) {
    const std::string why = subvec::gpu_unavailable_reason();
    if (!why.empty()) {
      std::fprintf(stderr, "subvec: GPU rendering unavailable (%s); rendering on the CPU\n",
                   why.c_str());
    } else if (const subvec::GpuRendererInfo gl = subvec::gpu_renderer(); gl.software) {
      std::fprintf(stderr,
                   "subvec: --gpu: OpenGL is %s (software); rendering on the CPU, which is faster "
                   "here\n",
                   gl.name.c_str());
    } else {
      options.backend = subvec::Backend::kGpu;
    }
  }

  if (options.backend == subvec::Backend::kGpu) {
    subvec::write_png(a.output, subvec::render(image, options));
    return;
  }
  // In tiles, rows streamed to the PNG encoder: memory independent of the output size.
  std::optional<subvec::PngWriter> png;
  subvec::render_strips(image, options, [&](int, const subvec::Image8& strip) {
    if (!png) png.emplace(a.output, size.width, size.height, strip.channels, options.threads);
    png->write_rows(strip);
  });
  png->finish();
}

// ---- info ------------------------------------------------------------------------------------

struct LevelInfo {
  int vertices, triangles, colors, features, tear_edges, crease_edges, border_edges, edges, corners;
};

LevelInfo level_info(const subvec::ControlMesh& mesh, int width, int height) {
  const subvec::MeshTopology topo = subvec::MeshTopology::build(mesh, width, height);
  LevelInfo info{mesh.num_vertices(),
                 mesh.num_triangles(),
                 mesh.num_colors(),
                 static_cast<int>(mesh.features.size()),
                 0,
                 0,
                 0,
                 topo.num_edges(),
                 0};
  for (subvec::EdgeTag t : topo.edge_tags) {
    info.tear_edges += t == subvec::EdgeTag::kTear;
    info.crease_edges += t == subvec::EdgeTag::kCrease;
    info.border_edges += t == subvec::EdgeTag::kBorder;
  }
  for (subvec::VertexTag t : topo.vertex_tags) info.corners += t == subvec::VertexTag::kCorner;
  return info;
}

void run_info(const std::string& input, bool json) {
  const subvec::VectorImage image = subvec::read_svec(input);
  std::error_code ec;
  const auto bytes = fs::file_size(input, ec);
  std::vector<LevelInfo> levels;
  int64_t total_vertices = 0;
  for (const subvec::ControlMesh& mesh : image.levels) {
    levels.push_back(level_info(mesh, image.width, image.height));
    total_vertices += mesh.num_vertices();
  }

  if (json) {
    nlohmann::ordered_json j;
    j["width"] = image.width;
    j["height"] = image.height;
    j["bytes"] = ec ? 0 : bytes;
    j["bytes_per_vertex"] = ec || total_vertices == 0 ? 0.0 : double(bytes) / double(total_vertices);
    j["levels"] = nlohmann::ordered_json::array();
    for (size_t i = 0; i < levels.size(); ++i) {
      const LevelInfo& l = levels[i];
      j["levels"].push_back({{"vertices", l.vertices},
                             {"triangles", l.triangles},
                             {"features", l.features},
                             {"tear_edges", l.tear_edges},
                             {"colors", l.colors},
                             {"creases", l.crease_edges},
                             {"border_edges", l.border_edges},
                             {"edges", l.edges},
                             {"corners", l.corners}});
      // ---- levels: feature ids and saliencies (for vectorize --feature-level), pyramid record ----
      nlohmann::ordered_json ids = nlohmann::ordered_json::array(), saliency = ids;
      for (const subvec::Feature& f : image.levels[i].features) ids.push_back(f.id), saliency.push_back(f.saliency);
      j["levels"].back()["feature_ids"] = ids;
      j["levels"].back()["feature_saliency"] = saliency;
      j["levels"].back()["collapses"] = image.levels[i].collapses.size();
      // ---- end levels ----
    }
    j["objects"] = nlohmann::ordered_json::array();
    for (const subvec::Object& o : image.objects) {
      j["objects"].push_back({{"level", o.level},
                              {"name", o.name},
                              {"visible", o.visible},
                              {"vertices", o.mesh.num_vertices()},
                              {"triangles", o.mesh.num_triangles()},
                              {"features", o.mesh.features.size()},
                              {"strokes", o.strokes.size()}});
    }
    j["strokes"] = image.strokes.size();
    j["metadata"] = nlohmann::ordered_json::object();
    for (const auto& [key, value] : image.metadata) j["metadata"][key] = value;
    std::cout << j.dump(2) << "\n";
    return;
  }

  std::printf("%s\n", input.c_str());
  std::printf("  size       %d x %d pixels\n", image.width, image.height);
  std::printf("  file       %llu bytes", static_cast<unsigned long long>(ec ? 0 : bytes));
  if (!ec && total_vertices > 0) {
    std::printf(" (%.2f per control vertex)", double(bytes) / double(total_vertices));
  }
  std::printf("\n");
  std::printf("  levels     %zu (0 is the finest)\n", levels.size());
  std::printf("  strokes    %zu\n", image.strokes.size());
  const char* label = "metadata";
  for (const auto& [key, value] : image.metadata) {
    std::printf("  %-10s %s: %s\n", label, key.c_str(), one_line(value).c_str());
    label = "";
  }
  std::printf(
      "\n  level  vertices  triangles    colors  features  tear edges  crease edges  corners\n");
  for (size_t i = 0; i < levels.size(); ++i) {
    const LevelInfo& l = levels[i];
    std::printf("  %5zu  %8d  %9d  %8d  %8d  %10d  %12d  %7d\n", i, l.vertices, l.triangles,
                l.colors, l.features, l.tear_edges, l.crease_edges, l.corners);
  }
  if (image.objects.empty()) return;
  std::printf("\n  object  level  vertices  triangles  features  strokes  visible  name\n");
  for (size_t i = 0; i < image.objects.size(); ++i) {
    const subvec::Object& o = image.objects[i];
    std::printf("  %6zu  %5d  %8d  %9d  %8zu  %7zu  %7s  %s\n", i, o.level, o.mesh.num_vertices(),
                o.mesh.num_triangles(), o.mesh.features.size(), o.strokes.size(), o.visible ? "yes" : "no",
                one_line(o.name).c_str());
  }
}

// ---- convert ---------------------------------------------------------------------------------

void run_convert(const std::string& input, const std::string& output, const subvec::SvecWriteOptions& options) {
  subvec::svec_format_for(output);  // rejects an unknown extension before any work
  subvec::write_svec(output, subvec::read_svec(input), options);
}

// ---- compare ---------------------------------------------------------------------------------

void run_compare(const std::string& reference, const std::string& test, bool json) {
  const subvec::Image8 a = subvec::read_image(reference);
  const subvec::Image8 b = subvec::read_image(test);
  if (a.width != b.width || a.height != b.height) {
    throw Error(ErrorCode::kInvalidArgument, "images differ in size: " + in_quotes(reference) +
                                                 " is " + std::to_string(a.width) + "x" +
                                                 std::to_string(a.height) + ", " + in_quotes(test) +
                                                 " is " + std::to_string(b.width) + "x" +
                                                 std::to_string(b.height));
  }
  const subvec::ImageDifference d = subvec::compare(a, b);
  if (json) {
    nlohmann::ordered_json j;
    j["width"] = a.width;
    j["height"] = a.height;
    j["mae"] = {{"r", d.mae[0]}, {"g", d.mae[1]}, {"b", d.mae[2]}};
    j["mae_mean"] = d.mae_mean;
    j["psnr"] =
        std::isinf(d.psnr) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(d.psnr);
    j["ssim"] = d.ssim;
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("size  %d x %d pixels\n", a.width, a.height);
  std::printf("MAE   %.4f  (R %.4f  G %.4f  B %.4f; 0-255 scale)\n", d.mae_mean, d.mae[0], d.mae[1],
              d.mae[2]);
  if (std::isinf(d.psnr)) {
    std::printf("PSNR  inf dB (identical)\n");
  } else {
    std::printf("PSNR  %.3f dB\n", d.psnr);
  }
  std::printf("SSIM  %.6f\n", d.ssim);
}

// ---- vectorize -------------------------------------------------------------------------------

struct VectorizeArgs {
  std::string input, output;
  int64_t max_pixels = 0;  // --max-pixels (add_limit_options)
  bool json = false;
  subvec_cli::VectorizeParams params;  // shared with batch (vectorize_options.h)
};

void run_vectorize(const VectorizeArgs& a) {
  subvec::VectorizeOptions options = subvec_cli::vectorize_options(a.params);  // validated
  subvec::svec_format_for(a.output);  // rejects an unknown extension before any work
  // Ctrl+C stops the job at its next check (cancel.h); nothing is written.
  const subvec_cli::CancelOnInterrupt interrupt;
  options.cancel = interrupt.flag();
  const auto start = std::chrono::steady_clock::now();
  subvec_cli::ProgressLine progress("vectorizing " + fs::path(a.input).filename().string());
  subvec::Image8 image;
  try {
    image = subvec::read_image(a.input, a.max_pixels);
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kLimit) throw;
    throw Error(e.code(), std::string(e.what()) + " (--max-pixels raises the limit)");
  }
  options.progress = [&](const std::string& stage, double fraction) {
    progress.update(stage, fraction);
  };
  // The library's estimate (what --max-memory is checked against): the heap reserve and --json.
  const int64_t estimate = subvec::estimate_vectorize_bytes(image.width, image.height, options);
  subvec_cli::reserve_memory(estimate);
  subvec::VectorizeReport report;
  subvec::VectorImage v;
  try {
    v = subvec::vectorize(image, options, &report);
  } catch (const Error& e) {
    // A budget that cannot be met and the memory check are named after their options, as the
    // option checks are.
    if (e.code() != ErrorCode::kInvalidArgument && e.code() != ErrorCode::kLimit) throw;
    throw Error(e.code(), subvec_cli::with_flag_names(e.what()));
  }
  progress.update("measuring", 1.0);
  const auto render_start = std::chrono::steady_clock::now();
  subvec::RenderOptions render_options;
  render_options.threads = options.threads;
  const subvec::ImageDifference d = subvec::compare(image, subvec::render(v, render_options));
  const double compare_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - render_start).count();
  interrupt.check();
  progress.update("writing", 1.0);
  subvec::write_svec(a.output, v);
  progress.finish();
  const double total =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The segment's boundary: how many mesh features follow it and whether it is one closed curve.
  int segment_closed = 0;
  for (const subvec::Feature& f : v.levels[0].features) {
    if (std::find(report.segment_feature_ids.begin(), report.segment_feature_ids.end(), f.id) !=
        report.segment_feature_ids.end()) {
      segment_closed += f.closed();
    }
  }
  const int segment_features = static_cast<int>(report.segment_feature_ids.size());
  const bool segment_is_closed = segment_features == 1 && segment_closed == 1;

  if (a.json) {
    nlohmann::ordered_json j;
    j["input"] = a.input;
    j["output"] = a.output;
    j["width"] = image.width;
    j["height"] = image.height;
    j["vertices"] = report.vertices;
    j["triangles"] = report.triangles;
    j["features"] = report.features;
    j["tear_vertices"] = report.tear_vertices;
    j["dense_vertices"] = report.dense_vertices;
    j["memory"] = {{"estimate_bytes", estimate}, {"peak_bytes", subvec_cli::peak_resident_bytes()}};
    j["budget"] = {{"target", report.target_vertices},
                   {"feature_tolerance", report.feature_tolerance},
                   {"features_dropped", report.features_dropped}};
    j["refine"] = {{"flips", report.refine.flips}, {"moves", report.refine.moves}};
    if (options.segment) {
      const subvec::PixelRect& r = *options.segment;
      j["segment"] = {{"rect", {r.x, r.y, r.width, r.height}},
                      {"foreground_pixels", report.segment_mask.area()},
                      {"features", segment_features},
                      {"closed", segment_is_closed}};
    } else {
      j["segment"] = nullptr;
    }
    // ---- levels ----
    nlohmann::ordered_json levels = nlohmann::ordered_json::array();
    for (size_t l = 0; l < v.levels.size(); ++l) {
      levels.push_back({{"vertices", v.levels[l].num_vertices()},
                        {"triangles", v.levels[l].num_triangles()},
                        {"features", v.levels[l].features.size()},
                        {"seconds", l < report.levels.seconds.size() ? report.levels.seconds[l] : 0.0}});
    }
    j["levels"] = levels;
    // ---- end levels ----
    j["mae"] = d.mae_mean;
    j["psnr"] =
        std::isinf(d.psnr) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(d.psnr);
    j["ssim"] = d.ssim;
    nlohmann::ordered_json stages;
    for (const auto& s : report.stages) stages[s.stage] = s.seconds;
    stages["render_compare"] = compare_seconds;
    j["seconds"] = stages;
    j["total_seconds"] = total;
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("%s -> %s\n", a.input.c_str(), a.output.c_str());
  std::printf("size      %d x %d pixels\n", image.width, image.height);
  std::printf("mesh      %d vertices, %d triangles, %d features (%d tear vertices)\n",
              report.vertices, report.triangles, report.features, report.tear_vertices);
  if (report.feature_tolerance > options.max_feature_error || report.features_dropped > 0) {
    std::printf("budget    %d vertices held: features within %g px of their curves, %d least salient dropped\n",
                report.target_vertices, report.feature_tolerance, report.features_dropped);
  }
  if (options.refine.rounds > 0) {
    std::printf("refined   %d edge flips, %d vertex moves\n", report.refine.flips, report.refine.moves);
  }
  if (options.segment) {
    std::string boundary = "is 1 closed feature";
    if (!segment_is_closed) {
      boundary = segment_features == 0
                     ? "lies on the image border (no feature)"
                     : "is " + std::to_string(segment_features) +
                           (segment_features == 1 ? " open feature" : " open features") +
                           " ending on the image border";
    }
    std::printf("segment   %s: %lld foreground pixels, boundary %s\n", a.params.segment.c_str(),
                static_cast<long long>(report.segment_mask.area()), boundary.c_str());
  }
  // ---- levels ----
  if (v.levels.size() > 1) {
    std::printf("levels   ");
    for (size_t l = 0; l < v.levels.size(); ++l)
      std::printf(" %zu: %d vertices, %zu features%s", l, v.levels[l].num_vertices(),
                  v.levels[l].features.size(), l + 1 < v.levels.size() ? ";" : "\n");
  }
  // ---- end levels ----
  std::printf("error     MAE %.3f, PSNR %.2f dB, SSIM %.4f (rendered at 1x against the input)\n",
              d.mae_mean, d.psnr, d.ssim);
  std::printf("seconds  ");
  for (const auto& s : report.stages) std::printf(" %s %.3f,", s.stage.c_str(), s.seconds);
  std::printf(" render+compare %.3f, total %.3f\n", compare_seconds, total);
}

// ---- command line ----------------------------------------------------------------------------

// The deepest subcommand CLI11 got to (the app itself when none).
const CLI::App* deepest_command(const CLI::App& app) {
  const CLI::App* at = &app;
  while (!at->get_subcommands().empty()) at = at->get_subcommands().front();
  return at;
}

// "subvec render" for render, "subvec" for the app itself.
std::string command_path(const CLI::App& app) {
  std::string path = "subvec";
  for (const CLI::App* at = &app; !at->get_subcommands().empty();) {
    at = at->get_subcommands().front();
    path += " " + at->get_name();
  }
  return path;
}
// info, convert and compare: run from their callbacks.
void add_file_commands(CLI::App& app) {
  // info
  static std::string info_input;  // static: the callbacks run after this function returns
  static bool info_json = false;
  CLI::App* info =
      app.add_subcommand("info", "Print the size and per-level statistics of a vector image");
  info->add_option("input", info_input, "Vector image (.svec or .svec.json)")->required();
  info->add_flag("--json", info_json, "Print a JSON object instead of text");
  info->footer(
      "Examples:\n"
      "  subvec info in.svec\n"
      "  subvec info in.svec.json --json    # {\"width\":..., \"height\":..., \"bytes\":..., "
      "\"levels\":[...]}");

  // convert
  static std::string convert_input, convert_output;
  static subvec::SvecWriteOptions convert_options;
  CLI::App* convert =
      app.add_subcommand("convert", "Convert between .svec (binary) and .svec.json");
  convert->add_option("input", convert_input, "Vector image (.svec or .svec.json)")->required();
  convert->add_option("-o,--output", convert_output, "Output; the format follows the extension")
      ->required();
  convert->add_flag("--lossless", convert_options.lossless,
                    ".svec: keep every value and the order of vertices exactly (version 1) instead "
                    "of the compact form");
  convert->add_option("--compact-version", convert_options.compact_version,
                      ".svec: the compact form's version, 3 (range-coded, the default) or 2 (for "
                      "readers that predate version 3)");
  convert->footer(
      "Examples:\n"
      "  subvec convert in.svec.json -o in.svec     # compact binary\n"
      "  subvec convert in.svec.json -o in.svec --lossless   # exact binary\n"
      "  subvec convert in.svec -o old.svec --compact-version 2   # for readers before version 3\n"
      "  subvec convert in.svec -o in.svec.json     # readable JSON");

  // compare
  static std::string compare_ref, compare_test;
  static bool compare_json = false;
  CLI::App* compare = app.add_subcommand(
      "compare", "Compare two raster images: mean absolute error per channel, PSNR and SSIM");
  compare->add_option("reference", compare_ref, "Reference image (PNG, JPEG, WebP, TIFF, BMP)")
      ->required();
  compare->add_option("test", compare_test, "Image to compare, of the same size")->required();
  compare->add_flag("--json", compare_json, "Print a JSON object instead of text");
  compare->footer(
      "Examples:\n"
      "  subvec compare photo.png render.png\n"
      "  subvec compare photo.png render.png --json   # psnr is null for identical images");
  info->callback([] { run_info(info_input, info_json); });
  convert->callback([] { run_convert(convert_input, convert_output, convert_options); });
  compare->callback([] { run_compare(compare_ref, compare_test, compare_json); });
}

// vectorize (the job's options: vectorize_options.h).
void add_vectorize_command(CLI::App& app) {
  // vectorize
  static VectorizeArgs va;  // static: the callback runs after this function returns
  CLI::App* vectorize =
      app.add_subcommand("vectorize", "Vectorize a photograph (PNG, JPEG, WebP, TIFF, BMP)");
  vectorize->add_option("input", va.input, "Raster image")->required();
  vectorize->add_option("-o,--output", va.output, "Output vector image (.svec or .svec.json)")
      ->required();
  subvec_cli::add_vectorize_options(vectorize, va.params);
  subvec_cli::add_limit_options(vectorize, va.params, va.max_pixels);
  vectorize->add_flag("--json", va.json, "Print the summary as JSON");
  // In a callback, like every command that runs a job: a range the library refuses
  // (vectorize_options()) is then a usage error, reported as CLI11's are.
  vectorize->callback([] { run_vectorize(va); });
  vectorize->footer(
      "Examples:\n"
      "  subvec vectorize photo.png -o photo.svec                 # 1% of the pixel count as "
      "vertices\n"
      "  subvec vectorize photo.jpg -o photo.svec --ratio 0.03    # finer\n"
      "  subvec vectorize photo.png -o photo.svec.json --vertices 2000 --json\n"
      "  subvec vectorize apple.png -o apple.svec --segment 30,40,440,460   # outline the apple");
}

// A command-line mistake: one line "subvec: [command: ]problem; hint" and CLI11's exit status.
// The hint is the closest valid name for an unknown option or command (messages.h), else the help
// to read. CLI11's own messages are reworded into subvec's (lower case, no "The following ...").
int usage_error(CLI::App& app, const CLI::ParseError& e) {
  using subvec_cli::closest_name;
  const CLI::App* at = deepest_command(app);
  const std::string help = "see '" + command_path(app) + " --help'";
  std::string message = subvec_cli::lower_first(e.what());
  std::string hint = help;
  int status = e.get_exit_code();

  // A word that is no option here: the first of them, with the closest option name.
  auto unknown = [&](const std::vector<std::string>& extra) {
    for (const std::string& word : extra) {
      if (word.size() < 2 || word[0] != '-') continue;
      const std::string name = word.substr(0, word.find('='));
      message = "unknown option " + name;
      std::vector<std::string> names;
      for (const CLI::Option* o : at->get_options()) {
        for (const std::string& l : o->get_lnames()) names.push_back("--" + l);
        for (const std::string& n : o->get_snames()) names.push_back("-" + n);
      }
      if (const std::string near = closest_name(name, names); !near.empty())
        hint = "did you mean " + near + "?";
      return;
    }
    std::string words;
    for (const std::string& word : extra) words += (words.empty() ? "'" : " '") + word + "'";
    message = (extra.size() == 1 ? "unexpected argument " : "unexpected arguments ") + words;
  };

  std::vector<std::string> commands;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    commands.push_back(sub->get_name());
  std::string command_list;
  for (size_t i = 0; i < commands.size(); ++i)
    command_list += (i == 0 ? "" : i + 1 == commands.size() ? " or " : ", ") + commands[i];

  const std::vector<std::string> leftover = app.remaining(true);  // words no option took
  if (at == &app && e.get_exit_code() == int(CLI::ExitCodes::RequiredError)) {
    // No command: either none was given or the first word is not one.
    const std::vector<std::string> extra = app.remaining();
    if (extra.empty()) {
      message = "a command is required: " + command_list;
    } else if (extra.front().rfind('-', 0) == 0) {
      unknown(extra);
      status = int(CLI::ExitCodes::ExtrasError);
    } else {
      message = "unknown command '" + extra.front() + "'";
      const std::string near = closest_name(extra.front(), commands);
      hint = !near.empty() ? "did you mean " + near + "?"
             : extra.front() == "help" ? "run 'subvec --help'"
                                       : "expected " + command_list;
      status = int(CLI::ExitCodes::ExtrasError);
    }
  } else if (dynamic_cast<const CLI::RequiredError*>(&e) != nullptr &&
             std::any_of(leftover.begin(), leftover.end(),
                         [](const std::string& w) { return w.size() > 1 && w[0] == '-'; })) {
    // "info -x": CLI11 misses the input first, but the unknown option is the mistake.
    unknown(leftover);
    status = int(CLI::ExitCodes::ExtrasError);
  } else if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr) {
    std::vector<std::string> extra = at->remaining();
    if (extra.empty()) extra = app.remaining(true);
    unknown(extra);
  } else if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) != nullptr) {
    // "--width: 1 required INT:INT in [1 - 65536] missing": the option's name, then CLI11's text.
    const std::string name = message.substr(0, message.find(':'));
    message = name.rfind('-', 0) == 0 ? name + " needs a value" : message;
  } else if (dynamic_cast<const CLI::ConversionError*>(&e) != nullptr) {
    // "Could not convert: --seed = seven"
    const std::string prefix = "could not convert: ";
    if (message.rfind(prefix, 0) == 0) {
      const std::string rest = message.substr(prefix.size());
      const size_t eq = rest.find(" = ");
      message = eq == std::string::npos ? "cannot convert " + rest
                                        : rest.substr(0, eq) + ": cannot convert '" +
                                              rest.substr(eq + 3) + "'";
    }
  } else if (dynamic_cast<const CLI::RequiredError*>(&e) != nullptr) {
    // "input is required" (a positional argument) or "--output is required".
    const std::string name = message.substr(0, message.find(' '));
    if (!name.empty() && name[0] != '-' && message == name + " is required")
      message = "the " + name + " argument is required";
  } else if (dynamic_cast<const CLI::ValidationError*>(&e) != nullptr) {
    // "--width: Value 0 not in range 1 to 65536": lower case after the option's name too.
    const size_t colon = message.find(": ");
    if (colon != std::string::npos)
      message = message.substr(0, colon + 2) + subvec_cli::lower_first(message.substr(colon + 2));
  }
  const std::string where = at == &app ? "" : at->get_name() + ": ";
  std::cerr << "subvec: " << one_line(where + message + "; " + hint) << "\n";
  return status;
}

int run(int argc, char** argv) {
  CLI::App app(
      "subvec: vector images built on piecewise smooth Loop subdivision surfaces.\n"
      "Vectorizes photographs; renders, edits, stylizes, inspects and converts .svec / .svec.json files; compares raster images.",
      "subvec");
  app.footer(
      "Examples:\n"
      "  subvec vectorize photo.png -o photo.svec\n"
      "  subvec render examples/01-disk.svec.json -o disk.png --scale 4\n"
      "  subvec info examples/01-disk.svec.json --json\n"
      "  subvec convert examples/01-disk.svec.json -o disk.svec\n"
      "  subvec compare photo.png disk.png\n"
      "\n"
      "Run 'subvec <command> --help' for the options of one command; docs/cli.md has them all.");
  app.set_version_flag("--version", std::string("subvec ") + SUBVEC_VERSION);
  app.require_subcommand(1);

  // render
  RenderArgs ra;
  CLI::App* render =
      app.add_subcommand("render", "Rasterize a vector image to PNG, or export it to PDF or SVG");
  render->add_option("input", ra.input, "Vector image (.svec or .svec.json)")->required();
  render
      ->add_option("-o,--output", ra.output,
                   "Output image; the format follows the extension (.png, .pdf, .svg)")
      ->required();
  CLI::Option* width_opt =
      render
          ->add_option("--width", ra.width,
                       "Output width in pixels; the height keeps the window's aspect ratio")
          ->check(CLI::Range(1, subvec::Limits::kMaxDimension));
  CLI::Option* scale_opt =
      render
          ->add_option("--scale", ra.scale,
                       "Output size as a multiple of the window's size (default 1)")
          ->check(subvec_cli::positive_number());
  width_opt->excludes(scale_opt);
  render
      ->add_option("--window", ra.window,
                   "View window X0,Y0,X1,Y1 in image pixels (default: the whole image); may extend "
                   "past the image, where the output is transparent")
      ->check(CLI::Validator(
          [](std::string& text) {
            subvec::Window w;
            return parse_window(text, w);
          },
          "X0,Y0,X1,Y1", "window"));
  render->add_option("--level", ra.level, "Level of detail, 0 (the finest) by default")
      ->check(CLI::Range(0, subvec::Limits::kMaxLevels - 1));
  render
      ->add_option("--overlay", ra.overlay,
                   "Draw the control mesh or the feature curves over the image")
      ->check(CLI::IsMember({"none", "mesh", "features"}, CLI::ignore_case))
      ->default_str("none");
  render->add_flag("--no-aa", ra.no_aa, "Disable anti-aliasing of tears and the image border");
  render->add_flag("--gpu", ra.gpu,
                   "Render .png output with OpenGL through headless EGL (falls back to the CPU, with "
                   "a message, when no GPU context can be created)");
  render
      ->add_option("--max-pixels", ra.max_pixels,
                   ".png: refuse larger outputs (default 67108864 = 8192 x 8192; at most 2^28)")
      ->check(CLI::Range(int64_t{1}, subvec::kMaxRenderPixels));
  render->add_option("--threads", ra.threads, "Worker threads; 0 (default) uses all cores")
      ->check(CLI::Range(0, 1024));
  render
      ->add_option("--depth", ra.depth,
                   "Subdivision depth; by default chosen from the output scale")
      ->check(CLI::Range(0, 10));
  render
      ->add_option("--tolerance", ra.tolerance,
                   ".pdf, .svg: largest deviation of the drawn triangles from the limit surface, in "
                   "output pixels (default 0.25)")
      ->check(subvec_cli::positive_number());
  render
      ->add_option("--pdf-target", ra.pdf_target,
                   ".pdf: the viewers the shading is built for: any (default; one RGB Gouraud "
                   "mesh) or poppler (per-channel meshes in two layers that pdftoppm interpolates "
                   "smoothly, about four times larger, offset half a unit elsewhere)")
      ->check(CLI::IsMember({"any", "poppler"}, CLI::ignore_case))
      ->default_str("any");
  render
      ->add_option("--svg-target", ra.svg_target,
                   ".svg: the programs the file is built for: browser (default; linear gradients "
                   "and flat triangles, drawn alike by browsers and librsvg) or inkscape (SVG 2 mesh gradients, one "
                   "patch per control face, editable with Inkscape's mesh tool)")
      ->check(CLI::IsMember({"browser", "inkscape"}, CLI::ignore_case))
      ->default_str("browser");
  render
      ->add_option("--svg-color-tolerance", ra.svg_color_tolerance,
                   ".svg for browsers: how far, on average in levels (0-255), a linear gradient may "
                   "stray from the limit surface's colors over its cell (default 8); smaller gives "
                   "truer colors and larger files")
      ->check(subvec_cli::positive_number());
  render->add_flag("-v,--verbose", ra.verbose,
                   ".pdf, .svg: print what the file holds (triangles or patches, tear hints, "
                   "strokes) and its size");
  render->footer(
      "Examples:\n"
      "  subvec render in.svec.json -o out.png                  # the image's own size\n"
      "  subvec render in.svec.json -o out.png --scale 4        # 4x larger\n"
      "  subvec render in.svec -o out.png --width 1920          # 1920 wide, aspect kept\n"
      "  subvec render in.svec -o zoom.png --window 10,10,42,34 --scale 16\n"
      "  subvec render in.svec -o mesh.png --overlay mesh --scale 4\n"
      "  subvec render in.svec -o out.pdf                       # vector: PDF, 1 pt per pixel\n"
      "  subvec render in.svec -o out.svg --scale 2");

  add_file_commands(app);       // info, convert, compare
  add_vectorize_command(app);   // vectorize
  subvec_cli::add_edit_commands(app);  // edit, stylize
  subvec_cli::add_pyramid_commands(app);  // filter
  subvec_serve::add_serve_command(app);  // serve (issue 7, apps/serve/)
  subvec_cli::add_batch_command(app);  // batch

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return usage_error(app, e);
  }

  if (render->parsed()) {
    run_render(ra, width_opt->count() > 0, scale_opt->count() > 0);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  subvec_cli::tune_memory();
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::cerr << "subvec: out of memory\n";
  } catch (const Error& e) {
    std::cerr << "subvec: " << one_line(e.what()) << "\n";
    // Ctrl+C (cancel.h): the status a shell gives a command SIGINT ends.
    if (e.code() == ErrorCode::kCancelled) return 130;
  } catch (const std::exception& e) {  // subvec::Error and everything else
    std::cerr << "subvec: " << one_line(e.what()) << "\n";
  } catch (...) {
    std::cerr << "subvec: unknown error\n";
  }
  return 1;
}
