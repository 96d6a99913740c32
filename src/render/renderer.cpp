// The renderer (paper §7.1 on the CPU): plans a view, keeps the refinement of the last view, and
// hands the limit mesh to the rasterizer (raster.cpp).
//
// Depth rule. The paper refines uniformly until the refined triangles outnumber the pixels of the
// window. We state the same idea per edge, in output pixels: at the image's own size (zoom s = 1
// output pixel per image pixel), refine until the mean refined edge of the visible faces is at most
// `max_edge_pixels` (2.5 by default). Each level halves edges, so with L the mean control edge
// length of the visible faces in output pixels the depth is the smallest k with
// L / 2^k <= max_edge_pixels * sqrt(s) (s taken as 1 below 1x).
//
// Why sqrt(s). What the edge length stands for is the error of drawing the limit surface as flat
// triangles: a chord of length h deviates from a curve of bounded curvature by O(h^2), and colors
// are interpolated linearly over the same chords, so the deviation falls fourfold per level
// (measured against the exact limit on chelsea: the median, 90th and 99th percentile edge deviation
// fall 4.0-4.5 times a level from depth 3; docs/performance.md, "The depth rule"). Zooming by s multiplies a position deviation, in output
// pixels, by s and leaves a color deviation as it is; so half a level per doubling of s, which is
// what sqrt(s) gives, keeps both deviations at or below those of the render at 1x. Refining a whole
// level per doubling (edges of 2.5 output pixels at any zoom) drew 8192^2 renders of a 512-class
// photograph at depth 7, 44M triangles, four times finer than the surface needs. Since the rule is
// in output pixels, a window zoomed by 2^z refines about z / 2 more levels, over the faces it sees
// only.
//
// Visible faces. The limit patch of a control face lies in the convex hull of the control vertices
// of the faces sharing a vertex with it (Loop masks, crease and corner rules are all convex
// combinations over that ring), so a face is refined when the bounding box of that ring meets the
// window. Subdivision refines the selected faces plus the ring they need and returns only their
// children.
#include "subvec/render/renderer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "core/messages_p.h"
#include "core/parallel_p.h"
#include "render/gpu/gpu_p.h"
#include "render/objects_p.h"
#include "render/raster_p.h"
#include "render/renderer_p.h"
#include "render/strokes_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/validate.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec {
namespace detail {

std::vector<std::array<double, 4>> ring_boxes(const ControlMesh& mesh,
                                              const MeshTopology& topology) {
  // Bounding box of each vertex's star (the vertices of its incident faces), then per face the
  // union over its three corners.
  const int nv = mesh.num_vertices();
  std::vector<std::array<double, 4>> star(nv);
  for (int v = 0; v < nv; ++v) {
    std::array<double, 4> b{mesh.positions[v].x, mesh.positions[v].y, mesh.positions[v].x,
                            mesh.positions[v].y};
    auto [begin, end] = topology.faces_of(v);
    for (const int32_t* f = begin; f != end; ++f) {
      for (const int32_t u : mesh.triangles[*f]) {
        const Vec2& p = mesh.positions[u];
        b = {std::min(b[0], p.x), std::min(b[1], p.y), std::max(b[2], p.x), std::max(b[3], p.y)};
      }
    }
    star[v] = b;
  }
  std::vector<std::array<double, 4>> boxes(mesh.num_triangles());
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    const auto &a = star[t[0]], &b = star[t[1]], &c = star[t[2]];
    boxes[f] = {std::min({a[0], b[0], c[0]}), std::min({a[1], b[1], c[1]}),
                std::max({a[2], b[2], c[2]}), std::max({a[3], b[3], c[3]})};
  }
  return boxes;
}

std::vector<std::array<double, 4>> refined_ring_boxes(const ControlMesh& mesh,
                                                      const MeshTopology& topology, int levels,
                                                      int threads) {
  // The limit patch of a control face is the union of its children's patches after `levels`
  // steps, and each child's lies in the hull of its own one-ring of refined (not limit) points:
  // Loop's masks, at tears, creases and corners too, have no negative weights. Per refined
  // vertex the box of its star, per refined triangle the union over its corners, per control
  // face the union over its children.
  const Subdivision subdivision(mesh, topology, levels, {}, /*push_to_limit=*/false);
  RefinedMesh r;
  subdivision.evaluate_once(mesh.positions, mesh.colors, r, threads);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<std::array<double, 4>> star(r.num_vertices(), {kInf, kInf, -kInf, -kInf});
  const auto grow = [](std::array<double, 4>& b, const std::array<double, 4>& o) {
    b = {std::min(b[0], o[0]), std::min(b[1], o[1]), std::max(b[2], o[2]), std::max(b[3], o[3])};
  };
  for (const Tri& t : r.triangles) {
    std::array<double, 4> b{kInf, kInf, -kInf, -kInf};
    for (const int32_t v : t) {
      const double x = r.positions[2 * v], y = r.positions[2 * v + 1];
      grow(b, {x, y, x, y});
    }
    for (const int32_t v : t) grow(star[v], b);
  }
  std::vector<std::array<double, 4>> boxes(mesh.num_triangles(), {kInf, kInf, -kInf, -kInf});
  for (int t = 0; t < r.num_triangles(); ++t) {
    std::array<double, 4>& b = boxes[r.triangle_parent[t]];
    for (const int32_t v : r.triangles[t]) grow(b, star[v]);
  }
  // The refined points are floats: widen each box by a few of their ulps.
  for (std::array<double, 4>& b : boxes) {
    const double pad = 1e-6 * (1 + std::max({std::abs(b[0]), std::abs(b[1]), std::abs(b[2]),
                                             std::abs(b[3])}));
    b = {b[0] - pad, b[1] - pad, b[2] + pad, b[3] + pad};
  }
  return boxes;
}

int choose_depth(double mean_edge_pixels, double max_edge_pixels, double zoom, int64_t num_faces) {
  const double target = max_edge_pixels * std::sqrt(std::max(1.0, zoom));
  int k = 0;
  while (k < kMaxAutoDepth && mean_edge_pixels / std::ldexp(1.0, k) > target) ++k;
  while (k > 0 && num_faces * (int64_t{1} << (2 * k)) > kMaxAutoTriangles) --k;
  return k;
}

namespace {

using detail::invalid;
using detail::num;

// A pixel count as an integer while it is one.
std::string pixels(double v) {
  if (v >= 1e15) return num(v);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f", v);
  return buf;
}

}  // namespace

bool covers_faces(std::span<const int32_t> have, bool have_all, std::span<const int32_t> want,
                  bool want_all) {
  return have_all || (!want_all && std::includes(have.begin(), have.end(), want.begin(), want.end()));
}

ViewPlan plan_view(const VectorImage& image, const ControlMesh& mesh,
                   std::span<const std::array<double, 4>> boxes, const RenderOptions& options) {
  ViewPlan p;
  const RenderSize size = render_size(options, image.width, image.height);
  if (!(options.max_edge_pixels > 0) || !std::isfinite(options.max_edge_pixels)) {
    invalid("max_edge_pixels " + num(options.max_edge_pixels) + " is not a positive number");
  }
  if (options.depth < -1 || options.depth > 10) {
    invalid("depth " + std::to_string(options.depth) + " is out of range (-1 to 10)");
  }
  const Window w = size.window;
  const double ww = w.x1 - w.x0, wh = w.y1 - w.y0;
  const int width = size.width, height = size.height;
  p.window = w;
  p.view = {w.x0, w.y0, size.scale_x, size.scale_y, width, height};
  constexpr double kMaxZoom = 65536;
  if (p.view.sx > kMaxZoom || p.view.sy > kMaxZoom) {
    invalid("window " + num(ww) + " x " + num(wh) + " is too small for a " + std::to_string(width) +
            " x " + std::to_string(height) + " output (zoom over 65536x)");
  }
  p.channels = (w.x0 < 0 || w.y0 < 0 || w.x1 > image.width || w.y1 > image.height) ? 4 : 3;

  // Visible faces and their mean edge length in output pixels.
  double edge_sum = 0;
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    if (!box_meets(boxes[f], w)) continue;
    p.faces.push_back(f);
    const Tri& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const Vec2& a = mesh.positions[t[k]];
      const Vec2& c = mesh.positions[t[(k + 1) % 3]];
      edge_sum += std::hypot((c.x - a.x) * p.view.sx, (c.y - a.y) * p.view.sy);
    }
  }
  p.all_faces = static_cast<int>(p.faces.size()) == mesh.num_triangles();
  const auto count = static_cast<int64_t>(p.faces.size());
  p.mean_edge_pixels = count ? edge_sum / double(3 * count) : 0;
  if (options.depth >= 0) {
    p.depth = options.depth;
    if (count * (int64_t{1} << (2 * p.depth)) > int64_t{1} << 26) {
      throw Error(ErrorCode::kLimit, "depth " + std::to_string(p.depth) + " over " +
                                         std::to_string(count) +
                                         " faces would refine more than 2^26 triangles");
    }
  } else {
    p.depth = choose_depth(p.mean_edge_pixels, options.max_edge_pixels,
                           std::min(p.view.sx, p.view.sy), count);
  }
  return p;
}

namespace {

// Overlay of the control mesh: the control polygon as ~1 px white lines, tears and creases in
// their own colors, control vertices as dots, all over a dark halo.
std::vector<OverlayLayer> mesh_overlay(const ControlMesh& mesh, const MeshTopology& topology,
                                       const ViewTransform& view) {
  OverlayLayer halo{{0, 0, 0}, 0.55f, 1.5f, {}, {}};
  OverlayLayer lines{{255, 255, 255}, 0.9f, 0.5f, {}, {}};
  OverlayLayer tears{{255, 64, 32}, 1.f, 0.65f, {}, {}};
  OverlayLayer creases{{255, 210, 0}, 1.f, 0.65f, {}, {}};
  OverlayLayer dots{{255, 255, 255}, 1.f, 0.f, {}, {}};
  auto out = [&](int v) {
    const auto o = view.to_output(mesh.positions[v].x, mesh.positions[v].y);
    return std::array<float, 2>{float(o[0]), float(o[1])};
  };
  auto visible = [&](float x0, float y0, float x1, float y1, float margin) {
    return std::max(x0, x1) >= -margin && std::min(x0, x1) <= float(view.width) + margin &&
           std::max(y0, y1) >= -margin && std::min(y0, y1) <= float(view.height) + margin;
  };
  for (int e = 0; e < topology.num_edges(); ++e) {
    const auto a = out(topology.edges[e][0]), b = out(topology.edges[e][1]);
    if (!visible(a[0], a[1], b[0], b[1], 4)) continue;
    const std::array<float, 4> s{a[0], a[1], b[0], b[1]};
    halo.segments.push_back(s);
    const EdgeTag tag = topology.edge_tags[e];
    (tag == EdgeTag::kTear     ? tears
     : tag == EdgeTag::kCrease ? creases
                               : lines)
        .segments.push_back(s);
  }
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const auto a = out(v);
    if (!visible(a[0], a[1], a[0], a[1], 4)) continue;
    halo.dots.push_back({a[0], a[1], 2.2f});
    dots.dots.push_back({a[0], a[1], 1.2f});
  }
  return {halo, lines, tears, creases, dots};
}

// Overlay of the refined limit feature curves: ~1.5 px vivid magenta over a dark halo.
std::vector<OverlayLayer> feature_overlay(const RefinedMesh& refined, const ViewTransform& view) {
  OverlayLayer halo{{0, 0, 0}, 0.5f, 1.75f, {}, {}};
  OverlayLayer curves{{255, 0, 255}, 1.f, 0.75f, {}, {}};
  for (const EdgeVerts& e : refined.tear_edges) {
    const auto a = view.to_output(refined.positions[2 * size_t(e[0])],
                                  refined.positions[2 * size_t(e[0]) + 1]);
    const auto b = view.to_output(refined.positions[2 * size_t(e[1])],
                                  refined.positions[2 * size_t(e[1]) + 1]);
    const std::array<float, 4> s{float(a[0]), float(a[1]), float(b[0]), float(b[1])};
    halo.segments.push_back(s);
    curves.segments.push_back(s);
  }
  return {halo, curves};
}

}  // namespace
}  // namespace detail

RenderSize render_size(const RenderOptions& options, int image_width, int image_height) {
  using detail::invalid;
  using detail::num;
  if (options.width < 0 || options.height < 0) {
    invalid("output size " + std::to_string(options.width) + " x " +
            std::to_string(options.height) + " is negative");
  }
  if (!(options.scale > 0) || !std::isfinite(options.scale)) {
    invalid("scale " + num(options.scale) + " is not a positive number");
  }
  if (options.scale != 1 && (options.width > 0 || options.height > 0)) {
    invalid("give width or scale, not both (width " + std::to_string(options.width) +
            ", height " + std::to_string(options.height) + ", scale " + num(options.scale) + ")");
  }
  if (options.max_pixels < 1 || options.max_pixels > kMaxRenderPixels) {
    invalid("max_pixels " + std::to_string(options.max_pixels) + " is out of range (1 to " +
            std::to_string(kMaxRenderPixels) + ")");
  }
  RenderSize r;
  r.window = options.window.value_or(Window{0, 0, double(image_width), double(image_height)});
  const Window& w = r.window;
  if (!std::isfinite(w.x0) || !std::isfinite(w.y0) || !std::isfinite(w.x1) ||
      !std::isfinite(w.y1) || !(w.x0 < w.x1) || !(w.y0 < w.y1)) {
    invalid("window " + num(w.x0) + "," + num(w.y0) + "," + num(w.x1) + "," + num(w.y1) +
            " is empty or not finite (want x0 < x1, y0 < y1)");
  }
  const double ww = w.x1 - w.x0, wh = w.y1 - w.y0;
  double width = options.width, height = options.height;
  if (width == 0 && height == 0) {
    width = ww * options.scale;
    height = wh * options.scale;
  } else if (height == 0) {
    height = width * wh / ww;
  } else if (width == 0) {
    width = height * ww / wh;
  }
  width = std::max(1.0, std::round(width));
  height = std::max(1.0, std::round(height));
  if (!(width <= Limits::kMaxDimension && height <= Limits::kMaxDimension &&
        width * height <= double(options.max_pixels))) {
    throw Error(ErrorCode::kLimit, "output size " + detail::pixels(width) + "x" +
                                       detail::pixels(height) + " is too large: at most " +
                                       std::to_string(Limits::kMaxDimension) +
                                       " pixels a side and " + std::to_string(options.max_pixels) +
                                       " pixels in all");
  }
  r.width = static_cast<int>(width);
  r.height = static_cast<int>(height);
  r.scale_x = width / ww;
  r.scale_y = height / wh;
  return r;
}

namespace {

// Everything derived from one level that survives between frames.
struct LevelState {
  std::optional<MeshTopology> topology;      // from validate_level: the level is valid
  std::vector<std::array<double, 4>> boxes;  // ring boxes; empty when positions changed
  std::vector<std::array<double, 4>> tile_boxes;  // refined ring boxes, the same; made by tiles
};

// The refinement of the last view and its limit values. A later view reuses it when it needs the
// same level and depth and a subset of its faces (a pan or zoom within the refined region); the
// rasterizer skips the blocks of refined triangles that the view does not meet.
struct RefineCache {
  int level = -1, depth = -1;
  std::vector<int32_t> faces;  // ascending; empty: all faces
  std::optional<Subdivision> subdivision;
  RefinedMesh refined;
  std::vector<detail::TriangleBlock> blocks;  // up to 64 triangles of one control face each
  bool positions_stale = false, colors_stale = false;
  bool on_gpu = false;  // limit values live on the GPU (refined holds no values then)
};

// Whether any visible object is drawn over `level`.
bool has_objects(const VectorImage& image, int level) {
  return std::any_of(image.objects.begin(), image.objects.end(),
                     [&](const Object& o) { return o.level == level && o.visible; });
}

// Cuts the refined triangles into blocks (runs of one control face, at most 64 triangles) and
// bounds each block's vertices.
void update_blocks(const RefinedMesh& r, std::vector<detail::TriangleBlock>& blocks, int threads) {
  constexpr int32_t kBlock = 64;
  if (blocks.empty()) {
    for (int32_t t = 0; t < r.num_triangles();) {
      int32_t end = t + 1;
      while (end < r.num_triangles() && end - t < kBlock &&
             r.triangle_parent[end] == r.triangle_parent[t])
        ++end;
      blocks.push_back({t, end, 0, 0, 0, 0});
      t = end;
    }
  }
  constexpr int kBlocksPerJob = 1024;
  const int jobs = (static_cast<int>(blocks.size()) + kBlocksPerJob - 1) / kBlocksPerJob;
  detail::parallel_for(jobs, threads, [&](int job) {
    const size_t end = std::min(blocks.size(), size_t(job + 1) * kBlocksPerJob);
    for (size_t i = size_t(job) * kBlocksPerJob; i < end; ++i) {
      detail::TriangleBlock& block = blocks[i];
      float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
      for (int32_t t = block.begin; t < block.end; ++t) {
        for (const int32_t v : r.triangles[t]) {
          const float x = r.positions[2 * size_t(v)], y = r.positions[2 * size_t(v) + 1];
          x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
      }
      block.x0 = x0, block.y0 = y0, block.x1 = x1, block.y1 = y1;
    }
  });
}

// The rasterizer's options for a view of `plan`: anti-aliasing as asked, the border's too when the
// window leaves the image.
detail::RasterOptions raster_options(const detail::ViewPlan& plan, const RenderOptions& options,
                                     int threads, std::span<const detail::TriangleBlock> blocks) {
  detail::RasterOptions raster;
  raster.channels = plan.channels;
  raster.antialias = options.antialias;
  raster.antialias_border = plan.channels == 4;
  raster.threads = threads;
  raster.blocks = blocks;
  return raster;
}

struct State {
  std::vector<LevelState> levels;
  RefineCache cache;
  detail::RasterScratch scratch;
  // The GPU path: created on the first kGpu frame; when that fails (or a refinement does not fit
  // the driver's buffers), kGpu frames of this state are drawn on the CPU.
  std::unique_ptr<detail::GpuRasterizer> gpu;
  bool gpu_tried = false;
  Backend last_backend = Backend::kCpu;
  // A single frame (render()): the refinement is evaluated once, level by level, without the
  // stencils that make a Renderer's later frames (edits) fast.
  bool one_frame = false;
};

LevelState& level_state(const VectorImage& image, State& state, int level) {
  if (level < 0 || level >= static_cast<int>(image.levels.size())) {
    throw Error(ErrorCode::kInvalidArgument, "level " + std::to_string(level) +
                                                 " is out of range (" +
                                                 std::to_string(image.levels.size()) + " levels)");
  }
  if (state.levels.size() != image.levels.size()) state.levels.resize(image.levels.size());
  LevelState& s = state.levels[level];
  const ControlMesh& mesh = image.levels[level];
  if (!s.topology) s.topology = validate_level(mesh, image.width, image.height, level);
  if (s.boxes.empty()) s.boxes = detail::ring_boxes(mesh, *s.topology);
  return s;
}

void render_with(const VectorImage& image, State& state, const RenderOptions& options, Image8& out) {
  if (image.width < 1 || image.height < 1) {
    throw Error(ErrorCode::kInvalidArgument, "the image has no pixels");
  }
  LevelState& ls = level_state(image, state, options.level);
  const ControlMesh& mesh = image.levels[options.level];
  detail::ViewPlan plan = detail::plan_view(image, mesh, ls.boxes, options);
  const int threads = detail::resolve_threads(options.threads);
  if (plan.faces.empty()) {
    out = Image8(plan.view.width, plan.view.height, plan.channels);
    detail::draw_objects(image, options.level, plan.view, plan.depth, options.antialias, threads,
                         nullptr, out);
    return;
  }
  if (plan.all_faces) plan.faces.clear();

  RefineCache& c = state.cache;
  bool use_gpu = false;
  if (options.backend == Backend::kGpu) {
    if (!state.gpu_tried) {
      state.gpu_tried = true;
      std::string error;
      state.gpu = detail::GpuRasterizer::create(error);
    }
    use_gpu = state.gpu != nullptr;
  }
  const bool reuse = c.subdivision && c.on_gpu == use_gpu && c.level == options.level &&
                     c.depth == plan.depth &&
                     detail::covers_faces(c.faces, c.faces.empty(), plan.faces, plan.all_faces);
  if (use_gpu) {
    try {
      if (!reuse) {
        c.subdivision.reset();
        c.refined = RefinedMesh{};
        c.blocks.clear();
        c.subdivision.emplace(mesh, *ls.topology, plan.depth, plan.faces);
        c.level = options.level;
        c.depth = plan.depth;
        c.faces = plan.faces;  // plan.faces is still needed if this view falls back to the CPU
        c.on_gpu = true;
        state.gpu->set_refinement(*c.subdivision);
        c.positions_stale = c.colors_stale = true;
      }
      if (c.positions_stale) state.gpu->set_positions(mesh.positions);
      if (c.colors_stale) state.gpu->set_colors(mesh.colors);
      c.positions_stale = c.colors_stale = false;
      state.gpu->draw(plan.view, plan.channels, options.antialias, out);
      detail::draw_objects(image, options.level, plan.view, plan.depth, options.antialias, threads,
                           nullptr, out);
    } catch (const Error& e) {
      if (e.code() != ErrorCode::kLimit) throw;
      // Over the driver's buffers or memory: this view is drawn on the CPU.
      c.subdivision.reset();
      use_gpu = false;
    }
  }
  state.last_backend = use_gpu ? Backend::kGpu : Backend::kCpu;
  if (use_gpu) {
    std::vector<detail::OverlayLayer> overlay;
    if (options.overlay == Overlay::kMesh)
      overlay = detail::mesh_overlay(mesh, *ls.topology, plan.view);
    if (options.overlay == Overlay::kFeatures) {
      RefinedMesh curves;
      curves.tear_edges = c.subdivision->topology().tear_edges;
      state.gpu->read_positions(curves.positions);
      overlay = detail::feature_overlay(curves, plan.view);
    }
    detail::draw_overlay(out, overlay, threads);
    detail::draw_strokes(image.strokes, options.level, plan.view, out);
    return;
  }
  if (c.on_gpu || !reuse) {
    c.subdivision.reset();
    c.refined = RefinedMesh{};
    c.blocks.clear();
    c.subdivision.emplace(mesh, *ls.topology, plan.depth, plan.faces);
    if (state.one_frame) {
      c.subdivision->evaluate_once(mesh.positions, mesh.colors, c.refined, threads);
    } else {
      c.subdivision->evaluate(mesh.positions, mesh.colors, c.refined, threads);
    }
    c.level = options.level;
    c.depth = plan.depth;
    c.faces = std::move(plan.faces);
    c.on_gpu = false;
    update_blocks(c.refined, c.blocks, threads);
  } else if (c.positions_stale && c.colors_stale) {
    c.subdivision->evaluate(mesh.positions, mesh.colors, c.refined, threads);
    update_blocks(c.refined, c.blocks, threads);
  } else if (c.positions_stale) {
    c.subdivision->evaluate_positions(mesh.positions, c.refined.positions, threads);
    update_blocks(c.refined, c.blocks, threads);
  } else if (c.colors_stale) {
    c.subdivision->evaluate_colors(mesh.colors, c.refined.colors, threads);
  }
  c.positions_stale = c.colors_stale = false;

  const detail::RasterOptions raster = raster_options(plan, options, threads, c.blocks);
  std::vector<detail::OverlayLayer> overlay;
  if (options.overlay == Overlay::kMesh)
    overlay = detail::mesh_overlay(mesh, *ls.topology, plan.view);
  if (options.overlay == Overlay::kFeatures)
    overlay = detail::feature_overlay(c.refined, plan.view);
  // Objects draw over the level and under its overlay.
  const bool objects = has_objects(image, options.level);
  detail::rasterize_into(c.refined, plan.view, raster,
                         objects ? std::span<const detail::OverlayLayer>{} : overlay, &state.scratch, out);
  if (objects) {
    detail::draw_objects(image, options.level, plan.view, plan.depth, options.antialias, threads,
                         nullptr, out);
    detail::draw_overlay(out, overlay, threads);
  }
  detail::draw_strokes(image.strokes, options.level, plan.view, out);
}

// The plan of one view with the level's validated topology: what render() plans for `options`.
struct LevelPlan {
  MeshTopology topology;
  detail::ViewPlan plan;
};

LevelPlan plan_level(const VectorImage& image, const RenderOptions& options) {
  if (image.width < 1 || image.height < 1) {
    throw Error(ErrorCode::kInvalidArgument, "the image has no pixels");
  }
  State state;
  LevelState& ls = level_state(image, state, options.level);
  detail::ViewPlan plan = detail::plan_view(image, image.levels[options.level], ls.boxes, options);
  return {std::move(*ls.topology), std::move(plan)};
}

ViewFaces view_faces_of(const detail::ViewPlan& plan, int level) {
  ViewFaces v;
  v.level = level;
  v.depth = plan.depth;
  v.size = {plan.view.width, plan.view.height, plan.window, plan.view.sx, plan.view.sy};
  v.all_faces = plan.all_faces;
  v.faces = plan.faces;
  return v;
}

}  // namespace

ViewFaces view_faces(const VectorImage& image, const RenderOptions& options) {
  return view_faces_of(plan_level(image, options).plan, options.level);
}

bool ViewMesh::covers(const ViewFaces& other) const {
  return faces.level == other.level && faces.depth == other.depth &&
         detail::covers_faces(faces.faces, faces.all_faces, other.faces, other.all_faces);
}

ViewMesh view_mesh(const VectorImage& image, const RenderOptions& options) {
  const LevelPlan p = plan_level(image, options);
  ViewMesh v;
  v.faces = view_faces_of(p.plan, options.level);
  if (p.plan.faces.empty()) return v;
  const ControlMesh& mesh = image.levels[options.level];
  // The renderer's partial refinement: the visible faces only, or the whole level (no face list)
  // when every face is visible.
  const std::span<const int32_t> faces =
      p.plan.all_faces ? std::span<const int32_t>{} : std::span<const int32_t>(p.plan.faces);
  v.subdivision.emplace(mesh, p.topology, p.plan.depth, faces);
  v.subdivision->evaluate(mesh.positions, mesh.colors, v.refined,
                          detail::resolve_threads(options.threads));
  return v;
}

namespace {

void render_strips_with(const VectorImage& image, State& state, const RenderOptions& options,
                        const std::function<void(int y0, const Image8& strip)>& sink,
                        const TileOptions& tiles);

// A one-off CPU render of more refined triangles than this is drawn in tiles (render_strips(),
// the same bytes): one piece of a 4 MP photograph at 1x (5.2 M triangles) took 4.5 s and 750 MB
// more than its 12 MB of pixels, the tiles 1.2 s and about 150 MB.
constexpr double kOnePieceTriangles = double(1 << 20);

}  // namespace

Image8 render(const VectorImage& image, const RenderOptions& options) {
  return detail::render_one_off(image, options, kOnePieceTriangles);
}

Image8 detail::render_one_off(const VectorImage& image, const RenderOptions& options,
                              double one_piece_triangles, bool* tiled) {
  State state;
  state.one_frame = true;
  Image8 out;
  if (tiled) *tiled = false;
  if (options.backend == Backend::kCpu && image.width >= 1 && image.height >= 1) {
    LevelState& ls = level_state(image, state, options.level);
    const detail::ViewPlan plan =
        detail::plan_view(image, image.levels[options.level], ls.boxes, options);
    if (double(plan.faces.size()) * std::ldexp(1.0, 2 * plan.depth) > one_piece_triangles) {
      if (tiled) *tiled = true;
      out = Image8(plan.view.width, plan.view.height, plan.channels);
      render_strips_with(image, state, options, [&](int y0, const Image8& strip) {
        std::copy(strip.pixels.begin(), strip.pixels.end(), out.row(y0));
      }, {});
      return out;
    }
  }
  render_with(image, state, options, out);
  return out;
}

namespace {

// What a worker keeps from tile to tile, so that later tiles reuse its pages.
struct TileWork {
  RefinedMesh refined;
  std::vector<detail::TriangleBlock> blocks;
  detail::RasterScratch scratch;
  std::vector<int32_t> faces;
};

// Output pixels around a tile within which its faces are selected: the overlays reach 2.75 pixels
// past their primitives, and snapping and the marks of tear pixels less than one.
constexpr double kTileMargin = 4;

// Draws the pixels `clip` of the view of `plan` into `strip` (the view's rows from clip.y0).
void draw_tile(const VectorImage& image, const RenderOptions& options, const MeshTopology& topology,
               std::span<const std::array<double, 4>> boxes, const detail::ViewPlan& plan,
               std::span<const detail::OverlayLayer> mesh_overlay, const detail::PixelRect& clip,
               int threads, TileWork& work, Image8& strip) {
  const ControlMesh& mesh = image.levels[options.level];
  const detail::ViewTransform& v = plan.view;
  const Window tile{v.x0 + (clip.x0 - kTileMargin) / v.sx, v.y0 + (clip.y0 - kTileMargin) / v.sy,
                    v.x0 + (clip.x1 + kTileMargin) / v.sx, v.y0 + (clip.y1 + kTileMargin) / v.sy};
  work.faces.clear();
  for (const int32_t f : plan.faces) {
    if (detail::box_meets(boxes[f], tile)) work.faces.push_back(f);
  }
  if (work.faces.empty()) {
    detail::draw_objects(image, options.level, v, plan.depth, options.antialias, threads, &clip, strip);
    if (options.overlay == Overlay::kMesh) detail::draw_overlay_clipped(strip, clip, mesh_overlay);
    detail::draw_strokes(image.strokes, options.level, v, clip, strip);
    return;
  }
  const bool all = work.faces.size() == size_t(mesh.num_triangles());
  {
    const Subdivision subdivision(mesh, topology, plan.depth,
                                  all ? std::span<const int32_t>{} : std::span<const int32_t>(work.faces));
    // evaluate_once() copies the topology only when the triangle count differs: another tile's
    // refinement may have the same count. Emptied (capacity kept), it is always copied.
    work.refined.triangles.clear();
    subdivision.evaluate_once(mesh.positions, mesh.colors, work.refined, threads);
  }
  work.blocks.clear();
  update_blocks(work.refined, work.blocks, threads);
  detail::RasterOptions raster = raster_options(plan, options, threads, work.blocks);
  raster.clip = clip;
  std::vector<detail::OverlayLayer> features;
  if (options.overlay == Overlay::kFeatures) features = detail::feature_overlay(work.refined, v);
  const std::span<const detail::OverlayLayer> overlay =
      options.overlay == Overlay::kFeatures ? features
      : options.overlay == Overlay::kMesh   ? mesh_overlay
                                            : std::span<const detail::OverlayLayer>{};
  // Objects draw over the level and under its overlay.
  const bool objects = has_objects(image, options.level);
  detail::rasterize_into(work.refined, v, raster, objects ? std::span<const detail::OverlayLayer>{} : overlay,
                         &work.scratch, strip);
  if (objects) {
    detail::draw_objects(image, options.level, v, plan.depth, options.antialias, threads, &clip, strip);
    detail::draw_overlay_clipped(strip, clip, overlay);
  }
  detail::draw_strokes(image.strokes, options.level, v, clip, strip);
}

}  // namespace

void render_strips(const VectorImage& image, const RenderOptions& options,
                   const std::function<void(int y0, const Image8& strip)>& sink,
                   const TileOptions& tiles) {
  State state;
  render_strips_with(image, state, options, sink, tiles);
}

namespace {

void render_strips_with(const VectorImage& image, State& state, const RenderOptions& options,
                        const std::function<void(int y0, const Image8& strip)>& sink,
                        const TileOptions& tiles) {
  if (image.width < 1 || image.height < 1) {
    throw Error(ErrorCode::kInvalidArgument, "the image has no pixels");
  }
  if (tiles.tile != 0 && (tiles.tile < 64 || tiles.tile > 8192 || tiles.tile % 64 != 0)) {
    detail::invalid("tile size " + std::to_string(tiles.tile) +
                    " is not 0 (automatic) or a multiple of 64 in 64..8192");
  }
  LevelState& ls = level_state(image, state, options.level);
  const ControlMesh& mesh = image.levels[options.level];
  const detail::ViewPlan plan = detail::plan_view(image, mesh, ls.boxes, options);
  const int threads = detail::resolve_threads(options.threads);
  const int width = plan.view.width, height = plan.view.height;
  // Automatic size: the largest of 2048, 1024, 512, 256 whose tile holds at most 2^18 refined
  // triangles at the view's mean density (ring included, a tile refines up to a few times that)
  // and, down to 1024, whose strip of rows (held twice: drawn, then filtered by the PNG encoder)
  // is at most 32 MiB. Smaller tiles refine the faces near their edges more often: 8192^2 of a
  // 512-class photograph takes ~1.7 s and 520 MB with 2048, ~2.1 s and 315 MB with 1024, 3.5 s
  // and 190 MB with 512; 16384^2 takes 7 s with 1024, 10.8 s with 512 (2 cores).
  int tile = tiles.tile;
  if (tile == 0) {
    const double density = double(plan.faces.size()) * std::ldexp(1.0, 2 * plan.depth) /
                           (double(width) * double(height));
    const double row_bytes = double(width) * plan.channels;
    tile = 2048;
    while (tile > 256 && (density * double(tile) * double(tile) > double(1 << 18) ||
                          (tile > 1024 && row_bytes * tile > double(32 << 20))))
      tile /= 2;
  }
  std::vector<detail::OverlayLayer> mesh_overlay;
  if (options.overlay == Overlay::kMesh)
    mesh_overlay = detail::mesh_overlay(mesh, *ls.topology, plan.view);
  const int columns = (width + tile - 1) / tile;
  // Tiles of a whole view select their faces by boxes two levels down: the ring boxes are about
  // three control faces wide, and every tile a face's box meets refines the face. On a 4x render
  // of a 512-class photograph (tiles of 512) the tiles then refine 6,477 faces instead of 8,129
  // (5,131 in the view), for a refinement of the whole level at depth 2 (one level for meshes of
  // over 2^16 faces; none over 2^18, nor for windows, where most of the level is out of view).
  const bool tiled = columns > 1 || height > tile;
  const int nf = mesh.num_triangles();
  const int box_levels = nf <= (1 << 16) ? 2 : nf <= (1 << 18) ? 1 : 0;
  const bool refined_boxes = tiled && plan.all_faces && box_levels > 0;
  if (refined_boxes && ls.tile_boxes.empty())
    ls.tile_boxes = detail::refined_ring_boxes(mesh, *ls.topology, box_levels, threads);
  const std::span<const std::array<double, 4>> tile_boxes =
      refined_boxes ? ls.tile_boxes : ls.boxes;
  // Several tiles a strip: one per worker, each drawn on one thread; else one tile at a time on
  // all of them. Tiles own disjoint pixels, so the order does not change the output.
  const bool across = columns >= 2 && threads >= 2;
  const int workers = across ? std::min(threads, columns) : 1;
  std::vector<TileWork> work(workers);
  Image8 strip;
  for (int y = 0; y < height; y += tile) {
    const int rows = std::min(tile, height - y);
    if (strip.height != rows) {
      strip = Image8(width, rows, plan.channels);
    } else {
      std::fill(strip.pixels.begin(), strip.pixels.end(), uint8_t{0});
    }
    auto draw = [&](int column, TileWork& w, int inner) {
      const detail::PixelRect clip{column * tile, y, std::min(width, (column + 1) * tile), y + rows};
      draw_tile(image, options, *ls.topology, tile_boxes, plan, mesh_overlay, clip, inner, w, strip);
    };
    if (across) {
      // Worker k draws columns k, k + workers, ...
      detail::parallel_for(workers, workers, [&](int k) {
        for (int column = k; column < columns; column += workers) draw(column, work[k], 1);
      });
    } else {
      for (int column = 0; column < columns; ++column) draw(column, work[0], threads);
    }
    sink(y, strip);
  }
}

}  // namespace

struct Renderer::Impl {
  VectorImage image;
  State state;
};

Renderer::Renderer(VectorImage image) : impl_(std::make_unique<Impl>()) {
  impl_->image = std::move(image);
}
Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;

const VectorImage& Renderer::image() const { return impl_->image; }

Image8 Renderer::render(const RenderOptions& options) {
  Image8 out;
  render_with(impl_->image, impl_->state, options, out);
  return out;
}

void Renderer::render(const RenderOptions& options, Image8& out) {
  render_with(impl_->image, impl_->state, options, out);
}

Backend Renderer::last_backend() const { return impl_->state.last_backend; }

std::string gpu_unavailable_reason() { return detail::gpu_probe(); }

bool is_software_renderer(std::string_view gl_renderer) {
  std::string lower(gl_renderer);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* word : {"llvmpipe", "softpipe", "swrast", "software", "swiftshader", "lavapipe"}) {
    if (lower.find(word) != std::string::npos) return true;
  }
  return false;
}

GpuRendererInfo gpu_renderer() {
  GpuRendererInfo info;
  if (!detail::gpu_probe().empty()) return info;
  info.name = detail::gpu_probe_renderer();
  info.software = is_software_renderer(info.name);
  return info;
}

void Renderer::set_positions(int level, std::span<const Vec2> positions) {
  VectorImage& image = impl_->image;
  if (level < 0 || level >= static_cast<int>(image.levels.size())) {
    throw Error(ErrorCode::kInvalidArgument,
                "set_positions: level " + std::to_string(level) + " is out of range");
  }
  ControlMesh& mesh = image.levels[level];
  if (static_cast<int>(positions.size()) != mesh.num_vertices()) {
    throw Error(ErrorCode::kInvalidArgument, "set_positions: " + std::to_string(positions.size()) +
                                                 " positions for " +
                                                 std::to_string(mesh.num_vertices()) + " vertices");
  }
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!std::isfinite(positions[i].x) || !std::isfinite(positions[i].y)) {
      throw Error(ErrorCode::kInvalidArgument,
                  "set_positions: position " + std::to_string(i) + " is not finite");
    }
  }
  mesh.positions.assign(positions.begin(), positions.end());
  State& s = impl_->state;
  if (level < static_cast<int>(s.levels.size())) {
    s.levels[level].boxes.clear();
    s.levels[level].tile_boxes.clear();
  }
  if (s.cache.level == level) s.cache.positions_stale = true;
}

void Renderer::set_colors(int level, std::span<const Color> colors) {
  VectorImage& image = impl_->image;
  if (level < 0 || level >= static_cast<int>(image.levels.size())) {
    throw Error(ErrorCode::kInvalidArgument,
                "set_colors: level " + std::to_string(level) + " is out of range");
  }
  ControlMesh& mesh = image.levels[level];
  if (static_cast<int>(colors.size()) != mesh.num_colors()) {
    throw Error(ErrorCode::kInvalidArgument,
                "set_colors: " + std::to_string(colors.size()) + " colors for " +
                    std::to_string(mesh.num_colors()) + " color values");
  }
  for (size_t i = 0; i < colors.size(); ++i) {
    if (!std::isfinite(colors[i].r) || !std::isfinite(colors[i].g) || !std::isfinite(colors[i].b)) {
      throw Error(ErrorCode::kInvalidArgument,
                  "set_colors: color " + std::to_string(i) + " is not finite");
    }
  }
  mesh.colors.assign(colors.begin(), colors.end());
  if (impl_->state.cache.level == level) impl_->state.cache.colors_stale = true;
}

}  // namespace subvec
