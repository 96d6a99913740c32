// SVG export (export.h, docs/export.md). SVG has no Gouraud shading that renderers share (SVG 2
// mesh gradients are drawn by Inkscape only), so the limit mesh is drawn as flat triangles, each in
// the mean of its corner colors, at the depth of the linear tolerance: about a pixel each. They are
// drawn with crisp edges (shape-rendering="crispEdges": no anti-aliasing), which makes them tile
// the image without the seams that anti-aliasing leaves between adjacent shapes (a stroke in the
// fill color, the usual cure, smears the colors of neighbours into each other); the tears, the
// only sharp edges of the picture, are then anti-aliased by tear hints (export_p.h) drawn over
// them. Triangles of one color share a path.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <unordered_map>

#include "export/export_p.h"
#include "export/limit_mesh_p.h"
#include "subvec/core/error.h"
#include "subvec/export/export.h"
#include "subvec/io/file.h"

namespace subvec {
namespace {

// Consecutive tear bands whose colors are this close (levels) are drawn as one (export_p.h).
constexpr double kHintColorTolerance = 1.0;

std::string hex_color(double r, double g, double b) {
  auto byte = [](double v) { return static_cast<int>(std::lround(std::clamp(v, 0.0, 255.0))); };
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", byte(r), byte(g), byte(b));
  return buf;
}

std::string xml_text(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else out += c;
  }
  return out;
}

// SVG path data: numbers at a fixed number of decimals, without leading zeros ("-.5"), separated
// only where the grammar needs it.
class PathData {
 public:
  explicit PathData(int decimals) : decimals_(decimals) {}
  void command(char c) {
    text_ += c;
    number_ = false;
  }
  void number(double v) {
    std::string t = detail::fixed(v, decimals_);
    if (t.rfind("0.", 0) == 0) t.erase(0, 1);
    if (t.rfind("-0.", 0) == 0) t.erase(1, 1);
    const bool dot = t.find('.') != std::string::npos;
    // "1.5" then ".5" reads as two numbers; "15" then ".5" or any number then "5" does not.
    if (number_ && t[0] != '-' && (t[0] != '.' || !dot_)) text_ += ' ';
    text_ += t;
    number_ = true;
    dot_ = dot;
  }
  const std::string& text() const { return text_; }

 private:
  int decimals_;
  std::string text_;
  bool number_ = false, dot_ = false;
};

}  // namespace

std::string to_svg(const VectorImage& image, const ExportOptions& options, ExportReport* report) {
  ExportReport local;
  ExportReport& r = report ? *report : local;
  const RefinedMesh mesh =
      detail::export_mesh(image, options, detail::Shading::kFlat, r);
  const double w = image.width, h = image.height, s = export_scale(options, image.width);
  // Coordinates in image pixels, to a tenth of an output pixel (crisp edges sample pixel centres).
  const int decimals = std::clamp(static_cast<int>(std::ceil(std::log10(s * 10) - 1e-9)), 1, 9);
  // The grid is offset by half a step (the group below translates it back), so that no vertex
  // lands exactly on a pixel centre, where renderers may leave a pixel to none of its triangles.
  const double unit = std::pow(10.0, decimals), offset = 0.5 / unit;
  auto grid = [&](double v) { return double(std::llround((v - offset) * unit)) / unit; };

  // Triangles of one color share a path, in order of first appearance.
  std::vector<std::string> order;
  std::unordered_map<std::string, PathData> paths;
  for (int32_t t = 0; t < mesh.num_triangles(); ++t) {
    const Tri& v = mesh.triangles[t];
    const Tri& c = mesh.triangle_colors[t];
    double mean[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int ch = 0; ch < 3; ++ch) mean[ch] += mesh.colors[3 * c[k] + ch] / 3.0;
    const std::string color = hex_color(mean[0], mean[1], mean[2]);
    auto [it, fresh] = paths.try_emplace(color, decimals);
    if (fresh) order.push_back(color);
    PathData& d = it->second;
    double px = grid(mesh.positions[2 * v[0]]), py = grid(mesh.positions[2 * v[0] + 1]);
    d.command('M');
    d.number(px);
    d.number(py);
    d.command('l');
    for (int k = 1; k < 3; ++k) {
      const double x = grid(mesh.positions[2 * v[k]]), y = grid(mesh.positions[2 * v[k] + 1]);
      d.number(x - px);
      d.number(y - py);
      px = x;
      py = y;
    }
    d.command('z');
  }

  std::string svg = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  svg += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + detail::fixed(w * s, 6) +
         "\" height=\"" + detail::fixed(h * s, 6) + "\" viewBox=\"0 0 " + detail::fixed(w, 6) +
         " " + detail::fixed(h, 6) + "\">\n";
  for (const auto& [key, value] : image.metadata)
    if (key == "title") svg += "<title>" + xml_text(value) + "</title>\n";
  svg += "<g shape-rendering=\"crispEdges\" transform=\"translate(" + detail::fixed(offset, 9) +
         " " + detail::fixed(offset, 9) + ")\">\n";
  for (const std::string& color : order)
    svg += "<path fill=\"" + color + "\" d=\"" + paths.at(color).text() + "\"/>\n";
  svg += "</g>\n";
  if (options.tear_hints) {
    for (const detail::TearHint& hint : detail::tear_hints(mesh, 1.0 / s, kHintColorTolerance)) {
      PathData d(decimals + 1);
      d.command('M');
      d.number(hint.polygon[0].x);
      d.number(hint.polygon[0].y);
      d.command('L');
      for (size_t k = 1; k < hint.polygon.size(); ++k) {
        d.number(hint.polygon[k].x);
        d.number(hint.polygon[k].y);
      }
      d.command('z');
      svg += "<path fill=\"" + hex_color(hint.color[0], hint.color[1], hint.color[2]) +
             "\" d=\"" + d.text() + "\"/>\n";
    }
  }
  for (const Stroke& stroke : image.strokes) {
    if (stroke.level != options.level) continue;
    const std::vector<Vec2> outline = detail::stroke_outline(stroke);
    if (outline.empty()) continue;
    PathData d(decimals + 1);
    for (size_t i = 0; i < outline.size(); ++i) {
      if (i < 2) d.command(i == 0 ? 'M' : 'L');
      d.number(outline[i].x);
      d.number(outline[i].y);
    }
    d.command('z');
    svg += "<path fill=\"" + hex_color(stroke.color.r, stroke.color.g, stroke.color.b) +
           "\" d=\"" + d.text() + "\"/>\n";
  }
  svg += "</svg>\n";
  return svg;
}

double export_scale(const ExportOptions& options, int image_width) {
  return options.width > 0 ? double(options.width) / image_width : options.scale;
}

bool is_vector_export(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return ext == ".pdf" || ext == ".svg";
}

void write_vector_export(const std::filesystem::path& path, const VectorImage& image,
                         const ExportOptions& options, ExportReport* report) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  std::string bytes;
  if (ext == ".pdf") {
    bytes = to_pdf(image, options, report);
  } else if (ext == ".svg") {
    bytes = to_svg(image, options, report);
  } else {
    throw Error(ErrorCode::kInvalidArgument,
                path.string() + ": not a vector export (expected .pdf or .svg)");
  }
  write_file_atomic(path, std::span(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

}  // namespace subvec
