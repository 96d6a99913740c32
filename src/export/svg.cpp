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
#include <span>
#include <string>
#include <unordered_map>

#include <Eigen/Dense>

#include "export/export_p.h"
#include "export/limit_mesh_p.h"
#include "subvec/core/error.h"
#include "subvec/export/export.h"
#include "subvec/io/file.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"

namespace subvec {
namespace {

// Consecutive tear bands whose colors are this close (levels) are drawn as one (export_p.h).
constexpr double kHintColorTolerance = 1.0;
// A triangle whose LinearColor varies by less than this (levels) is drawn flat.
constexpr double kFlatRange = 1.0;

std::string hex_color(double r, double g, double b) {
  auto byte = [](double v) { return static_cast<int>(std::lround(std::clamp(v, 0.0, 255.0))); };
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", byte(r), byte(g), byte(b));
  return buf;
}

// n in base 36 (least significant digit first): short ids.
std::string base36(int64_t n) {
  std::string id;
  do {
    id += "0123456789abcdefghijklmnopqrstuvwxyz"[n % 36];
    n /= 36;
  } while (n > 0);
  return id;
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

// The XML declaration, the <svg> element (its size in output units, the image in its viewBox, and
// `attributes`) and the image's title.
std::string header(const VectorImage& image, double scale, const std::string& attributes) {
  const double w = image.width, h = image.height;
  std::string svg = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  svg += "<svg xmlns=\"http://www.w3.org/2000/svg\"" + attributes + " width=\"" +
         detail::fixed(w * scale, 6) + "\" height=\"" + detail::fixed(h * scale, 6) +
         "\" viewBox=\"0 0 " + detail::fixed(w, 6) + " " + detail::fixed(h, 6) + "\">\n";
  for (const auto& [key, value] : image.metadata)
    if (key == "title") svg += "<title>" + xml_text(value) + "</title>\n";
  return svg;
}

// The strokes of `level` (the image's, or an object's) as filled outlines (export_p.h).
std::string stroke_paths(std::span<const Stroke> strokes, int level, int decimals, ExportReport& report) {
  std::string out;
  for (const Stroke& stroke : strokes) {
    if (stroke.level != level) continue;
    const std::vector<Vec2> outline = detail::stroke_outline(stroke);
    if (outline.empty()) continue;
    ++report.strokes;
    PathData d(decimals);
    for (size_t i = 0; i < outline.size(); ++i) {
      if (i < 2) d.command(i == 0 ? 'M' : 'L');
      d.number(outline[i].x);
      d.number(outline[i].y);
    }
    d.command('z');
    out += "<path fill=\"" + hex_color(stroke.color.r, stroke.color.g, stroke.color.b) +
           "\" d=\"" + d.text() + "\"/>\n";
  }
  return out;
}

// SvgTarget::kInkscape: the limit surface as SVG 2 mesh gradients, one bicubic Coons patch per
// control face (docs/export.md, "SVG for Inkscape"). A face's sides are cubic Béziers through the
// limit points of its corners with the limit curve's tangents there (on tears, the limit curve
// is itself a cubic B-spline); each control edge's curve is computed once, so neighbours share it
// exactly. A triangle is a Coons patch whose third side has collapsed to its third corner. The
// corners take the limit colors of the face's side of any tear. Each face is a path filled with
// its own one-patch gradient, so Inkscape's mesh tool edits each face's corners and colors.
// One control mesh's patches (a level's or an object's): a gradient per face into `defs`, named
// `prefix` and the face's number in base 36, and the path it fills into `paths`.
void mesh_patches(const ControlMesh& mesh, const MeshTopology& topology, int decimals,
                  const std::string& prefix, std::string& defs, std::string& paths) {
  const LimitEvaluator evaluator(mesh, topology);

  // Each control edge as a cubic Bézier from its lower-numbered vertex, from its first face.
  struct Curve {
    std::array<Vec2, 4> p;
  };
  std::vector<Curve> curves(topology.num_edges());
  // Face corner (u, v), and the derivative along the face's side k at its start and end.
  constexpr double kCorner[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  auto along = [](const LimitEvaluator::Sample& s, int k) {  // d/dt along side k (corner k to k+1)
    const Vec2 &du = s.position_du, &dv = s.position_dv;
    return k == 0 ? du : k == 1 ? Vec2{dv.x - du.x, dv.y - du.y} : Vec2{-dv.x, -dv.y};
  };
  for (int e = 0; e < topology.num_edges(); ++e) {
    const int f = topology.edge_faces[e][0];
    const Tri& v = mesh.triangles[f];
    int k = 0;
    while (topology.face_edges[f][k] != e) ++k;
    const LimitEvaluator::Sample a = evaluator.evaluate(f, kCorner[k][0], kCorner[k][1]);
    const LimitEvaluator::Sample b =
        evaluator.evaluate(f, kCorner[(k + 1) % 3][0], kCorner[(k + 1) % 3][1]);
    const Vec2 ta = along(a, k), tb = along(b, k);
    Curve c;
    c.p = {a.position, Vec2{a.position.x + ta.x / 3, a.position.y + ta.y / 3},
           Vec2{b.position.x - tb.x / 3, b.position.y - tb.y / 3}, b.position};
    if (v[k] > v[(k + 1) % 3]) std::reverse(c.p.begin(), c.p.end());
    curves[e] = c;
  }

  // Base-36 ids: the file repeats one per face twice.
  auto id_of = [&](int f) { return prefix + base36(f); };
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& v = mesh.triangles[f];
    std::array<std::array<Vec2, 4>, 3> side;
    for (int k = 0; k < 3; ++k) {
      side[k] = curves[topology.face_edges[f][k]].p;
      if (v[k] > v[(k + 1) % 3]) std::reverse(side[k].begin(), side[k].end());
    }
    // The patch's color is linear in the face's parameters, c0 (1 - u - v) + c1 u + c2 v: the
    // corners' colors are fitted by least squares to the limit colors at the parameters
    // (i, j) / 4 over the face, which draws the face's inside closer than its corner values.
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d rhs = Eigen::Matrix3d::Zero();  // column per channel
    constexpr int kSamples = 4;
    for (int j = 0; j <= kSamples; ++j) {
      for (int i = 0; i + j <= kSamples; ++i) {
        const double u = double(i) / kSamples, t = double(j) / kSamples;
        const LimitEvaluator::Sample sample = evaluator.evaluate(f, u, t);
        const Eigen::Vector3d b(1 - u - t, u, t);
        normal += b * b.transpose();
        for (int ch = 0; ch < 3; ++ch) rhs.col(ch) += b * sample.color[ch];
      }
    }
    const Eigen::Matrix3d corner = normal.ldlt().solve(rhs);  // row k: corner k's color
    std::array<std::string, 3> color;
    for (int k = 0; k < 3; ++k) color[k] = hex_color(corner(k, 0), corner(k, 1), corner(k, 2));
    auto relative = [&](const std::array<Vec2, 4>& c) {
      PathData d(decimals);
      d.command('c');
      for (int i = 1; i < 4; ++i) {
        d.number(c[i].x - c[0].x);
        d.number(c[i].y - c[0].y);
      }
      return d.text();
    };
    const std::string id = id_of(f);
    defs += "<meshgradient id=\"" + id + "\" xlink:href=\"#t\" x=\"" +
            detail::fixed(side[0][0].x, decimals) + "\" y=\"" + detail::fixed(side[0][0].y, decimals) +
            "\"><meshrow><meshpatch><stop path=\"" + relative(side[0]) + "\" stop-color=\"" +
            color[0] + "\"/><stop path=\"" + relative(side[1]) + "\" stop-color=\"" + color[1] +
            "\"/><stop path=\"l0 0\" stop-color=\"" + color[2] + "\"/><stop path=\"" +
            relative(side[2]) + "\" stop-color=\"" + color[2] +
            "\"/></meshpatch></meshrow></meshgradient>\n";
    // The mesh paints nothing outside its patch, so the shape it fills is the face's bounding box
    // (the curves' control points bound them), to the grid of the coordinates.
    double x0 = side[0][0].x, y0 = side[0][0].y, x1 = x0, y1 = y0;
    for (const auto& c : side) {
      for (const Vec2& p : c) {
        x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
        x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
      }
    }
    const double unit = std::pow(10.0, decimals);
    x0 = std::floor(x0 * unit) / unit, y0 = std::floor(y0 * unit) / unit;
    x1 = std::ceil(x1 * unit) / unit, y1 = std::ceil(y1 * unit) / unit;
    PathData d(decimals);
    d.command('M');
    d.number(x0);
    d.number(y0);
    d.command('h');
    d.number(x1 - x0);
    d.command('v');
    d.number(y1 - y0);
    d.command('h');
    d.number(x0 - x1);
    d.command('z');
    paths += "<path fill=\"url(#" + id + ")\" d=\"" + d.text() + "\"/>\n";
  }
}

std::string svg_mesh(const VectorImage& image, const ExportOptions& options, ExportReport& report) {
  const double scale = detail::check_export_options(image, options);
  const ControlMesh& mesh = image.levels[options.level];
  const MeshTopology topology = validate_level(mesh, image.width, image.height, options.level);
  // Coordinates in image pixels, to a tenth of an output pixel.
  const int decimals = std::clamp(static_cast<int>(std::ceil(std::log10(scale * 10) - 1e-9)), 1, 9);
  std::string defs, paths;
  mesh_patches(mesh, topology, decimals, "m", defs, paths);
  report.depth = report.min_depth = 0;
  report.triangles = 0;
  report.patches = mesh.num_triangles();
  paths = "<g>\n" + paths + "</g>\n";
  // Each object a group of its own patches over the level, bottom to top.
  for (const ObjectTopology& o : visible_objects(image, options.level)) {
    const Object& object = image.objects[o.object];
    std::string group;
    mesh_patches(object.mesh, o.topology, decimals, "o" + std::to_string(o.object) + "m", defs, group);
    paths += "<g id=\"object-" + std::to_string(o.object) + "\"><title>" + xml_text(object.name) + "</title>\n" +
             group + stroke_paths(object.strokes, options.level, decimals + 1, report) + "</g>\n";
    report.patches += object.mesh.num_triangles();
    ++report.objects;
  }

  std::string svg = header(image, scale, " xmlns:xlink=\"http://www.w3.org/1999/xlink\"");
  // The template holds what every face's gradient shares.
  svg += "<defs>\n<meshgradient id=\"t\" gradientUnits=\"userSpaceOnUse\" type=\"bicubic\"/>\n" +
         defs + "</defs>\n" + paths;
  svg += stroke_paths(image.strokes, options.level, decimals + 1, report);
  svg += "</svg>\n";
  report.bytes = static_cast<int64_t>(svg.size());
  return svg;
}

}  // namespace

std::string to_svg(const VectorImage& image, const ExportOptions& options, ExportReport* report) {
  ExportReport local;
  ExportReport& r = report ? *report : local;
  if (options.svg_target == SvgTarget::kInkscape) return svg_mesh(image, options, r);
  detail::LinearCells cells;
  const RefinedMesh mesh = detail::export_mesh(image, options, detail::Shading::kLinear, r, &cells);
  const std::vector<detail::ObjectMesh> objects =
      detail::export_object_meshes(image, options, detail::Shading::kLinear, r);
  const double s = export_scale(options, image.width);
  // Coordinates in image pixels, to a tenth of an output pixel (crisp edges sample pixel centres).
  const int decimals = std::clamp(static_cast<int>(std::ceil(std::log10(s * 10) - 1e-9)), 1, 9);
  // The grid is offset by half a step (the group below translates it back), so that no vertex
  // lands exactly on a pixel centre, where renderers may leave a pixel to none of its triangles.
  const double unit = std::pow(10.0, decimals), offset = 0.5 / unit;
  auto grid = [&](double v) { return double(std::llround((v - offset) * unit)) / unit; };

  // One refined mesh: each color cell (limit_mesh_p.h, LinearCells) filled with its LinearColor,
  // as a linear gradient (a `linearGradient` from the template "_", in user space, its two stops at
  // the cell's extreme points along the direction) over one path of its triangles or, where the
  // color varies by less than kFlatRange levels over the cell, flat in its color at the centre;
  // flat triangles of one color share a path, in order of first appearance. Then the hints along
  // its tears.
  auto draw = [&](const RefinedMesh& refined, const detail::LinearCells& fills) {
    const size_t num_cells = fills.colors.size();
    // Each cell's triangles, in order.
    std::vector<std::vector<int32_t>> members(num_cells);
    std::vector<int32_t> cell_order;
    for (int32_t t = 0; t < refined.num_triangles(); ++t) {
      std::vector<int32_t>& m = members[size_t(fills.cell_of[size_t(t)])];
      if (m.empty()) cell_order.push_back(fills.cell_of[size_t(t)]);
      m.push_back(t);
    }
    auto point = [&](PathData& d, int32_t v, double& px, double& py, bool first) {
      const double x = grid(refined.positions[2 * v]), y = grid(refined.positions[2 * v + 1]);
      if (first) {
        d.command('M');
        d.number(x);
        d.number(y);
        d.command('l');
      } else {
        d.number(x - px);
        d.number(y - py);
      }
      px = x, py = y;
    };
    // A cell's outline: its triangles tile a disk, so the edges not shared by two of them make one
    // loop, drawn as one polygon (else, as a fallback, its triangles one by one).
    std::vector<std::pair<int32_t, int32_t>> boundary;
    auto outline = [&](PathData& d, const std::vector<int32_t>& tris) {
      boundary.clear();
      for (const int32_t t : tris)
        for (int k = 0; k < 3; ++k) boundary.push_back({refined.triangles[t][k], refined.triangles[t][(k + 1) % 3]});
      std::sort(boundary.begin(), boundary.end());
      std::vector<std::pair<int32_t, int32_t>> loop;
      for (const auto& [a, b] : boundary)
        if (!std::binary_search(boundary.begin(), boundary.end(), std::pair{b, a})) loop.push_back({a, b});
      // Chain the loop from its smallest vertex; each vertex starts one edge.
      bool chained = !loop.empty();
      std::vector<int32_t> polygon;
      if (chained) {
        polygon.push_back(loop[0].first);
        for (size_t k = 0; k < loop.size() && chained; ++k) {
          const auto it = std::lower_bound(loop.begin(), loop.end(), std::pair{polygon.back(), INT32_MIN});
          if (it == loop.end() || it->first != polygon.back() || (it + 1 != loop.end() && (it + 1)->first == it->first)) {
            chained = false;
            break;
          }
          polygon.push_back(it->second);
        }
        chained = chained && polygon.size() == loop.size() + 1 && polygon.back() == polygon.front();
      }
      double px = 0, py = 0;
      if (chained) {
        polygon.pop_back();
        for (size_t k = 0; k < polygon.size(); ++k) point(d, polygon[k], px, py, k == 0);
        d.command('z');
        return;
      }
      for (const int32_t t : tris) {
        for (int k = 0; k < 3; ++k) point(d, refined.triangles[t][k], px, py, k == 0);
        d.command('z');
      }
    };
    std::vector<std::string> order;
    std::unordered_map<std::string, PathData> paths;
    std::string defs, shaded;
    for (const int32_t cell : cell_order) {
      const detail::LinearColor& fit = fills.colors[size_t(cell)];
      const std::vector<int32_t>& tris = members[size_t(cell)];
      // The cell's extent along its direction, and the centre of its box.
      double lo = INFINITY, hi = -INFINITY, x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
      for (const int32_t t : tris) {
        for (const int32_t v : refined.triangles[t]) {
          const double x = refined.positions[2 * v], y = refined.positions[2 * v + 1];
          const double along = (x - fit.centre[0]) * fit.direction[0] + (y - fit.centre[1]) * fit.direction[1];
          lo = std::min(lo, along), hi = std::max(hi, along);
          x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
      }
      double range = 0;
      for (int k = 0; k < 3; ++k) range = std::max(range, std::abs(fit.slope[k]) * (hi - lo));
      ++r.shapes;
      if (range < kFlatRange) {
        double c[3];
        fit.at(0.5 * (x0 + x1), 0.5 * (y0 + y1), c);
        const std::string color = hex_color(c[0], c[1], c[2]);
        auto [it, fresh] = paths.try_emplace(color, decimals);
        if (fresh) order.push_back(color);
        outline(it->second, tris);
        continue;
      }
      double a[3], b[3];
      const double ax = fit.centre[0] + lo * fit.direction[0], ay = fit.centre[1] + lo * fit.direction[1];
      const double bx = fit.centre[0] + hi * fit.direction[0], by = fit.centre[1] + hi * fit.direction[1];
      fit.at(ax, ay, a);
      fit.at(bx, by, b);
      const std::string id = base36(r.gradients++);
      defs += "<linearGradient id=\"" + id + "\" href=\"#_\" x1=\"" + detail::fixed(grid(ax), decimals) +
              "\" y1=\"" + detail::fixed(grid(ay), decimals) + "\" x2=\"" + detail::fixed(grid(bx), decimals) +
              "\" y2=\"" + detail::fixed(grid(by), decimals) + "\"><stop stop-color=\"" + hex_color(a[0], a[1], a[2]) +
              "\"/><stop offset=\"1\" stop-color=\"" + hex_color(b[0], b[1], b[2]) + "\"/></linearGradient>\n";
      PathData d(decimals);
      outline(d, tris);
      shaded += "<path fill=\"url(#" + id + ")\" d=\"" + d.text() + "\"/>\n";
    }
    std::string out = "<g shape-rendering=\"crispEdges\" transform=\"translate(" + detail::fixed(offset, 9) +
                      " " + detail::fixed(offset, 9) + ")\">\n";
    if (!defs.empty()) out += "<defs>\n" + defs + "</defs>\n";
    for (const std::string& color : order)
      out += "<path fill=\"" + color + "\" d=\"" + paths.at(color).text() + "\"/>\n";
    out += shaded;
    out += "</g>\n";
    if (options.tear_hints) {
      for (const detail::TearHint& hint : detail::tear_hints(refined, 1.0 / s, kHintColorTolerance)) {
        ++r.tear_hints;
        // Relative coordinates between points snapped to the grid of decimals + 1 (no drift).
        const double hint_unit = std::pow(10.0, decimals + 1);
        auto snap = [&](double v) { return double(std::llround(v * hint_unit)) / hint_unit; };
        PathData d(decimals + 1);
        double px = snap(hint.polygon[0].x), py = snap(hint.polygon[0].y);
        d.command('M');
        d.number(px);
        d.number(py);
        d.command('l');
        for (size_t k = 1; k < hint.polygon.size(); ++k) {
          const double x = snap(hint.polygon[k].x), y = snap(hint.polygon[k].y);
          d.number(x - px);
          d.number(y - py);
          px = x, py = y;
        }
        d.command('z');
        out += "<path fill=\"" + hex_color(hint.color[0], hint.color[1], hint.color[2]) +
               "\" d=\"" + d.text() + "\"/>\n";
      }
    }
    return out;
  };

  std::string svg = header(image, s, "");
  // The gradients' template: user-space coordinates (the triangles' own).
  svg += "<defs><linearGradient id=\"_\" gradientUnits=\"userSpaceOnUse\"/></defs>\n";
  svg += draw(mesh, cells);
  // Each object a group over the level, bottom to top, named by its title.
  for (const detail::ObjectMesh& object : objects) {
    svg += "<g id=\"object-" + std::to_string(object.object) + "\"><title>" +
           xml_text(image.objects[object.object].name) + "</title>\n" + draw(object.mesh, object.cells) +
           stroke_paths(image.objects[object.object].strokes, options.level, decimals + 1, r) + "</g>\n";
  }
  svg += stroke_paths(image.strokes, options.level, decimals + 1, r);
  svg += "</svg>\n";
  r.bytes = static_cast<int64_t>(svg.size());
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
