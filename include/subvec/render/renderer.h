// Rasterization of a vector image (paper §7.1) on the CPU, or on the GPU through OpenGL (Backend).
//
// The renderer refines only the control faces whose limit surface touches the view window, to a
// depth chosen from the output scale, pushes the refined vertices to the limit and draws the
// triangles with Gouraud interpolation under a top-left fill rule. Tears and the image border are
// anti-aliased by supersampling the pixels they cross. Work is split over horizontal bands, one
// writer per pixel, so the output is byte-identical whatever the thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec {

// A view window in image coordinates (x0 < x1, y0 < y1); may extend past the image, where the
// output is transparent.
struct Window {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

enum class Overlay { kNone, kMesh, kFeatures };

// Where the color field is drawn. kGpu evaluates the limit stencils and rasterizes the refined
// triangles through OpenGL 4.3 in a headless EGL context (docs/gpu.md); overlays and strokes are
// then drawn over the read-back frame on the CPU. The frame equals the CPU's to rounding (the GPU
// reproduces its vertices, samples and fill rule). When no context can be created (no EGL, no
// driver, a build without SUBVEC_GPU), or a view's refinement does not fit the driver's buffers,
// the frame is drawn on the CPU: see gpu_unavailable_reason() and Renderer::last_backend().
enum class Backend { kCpu, kGpu };

// The largest output a render may be allowed (RenderOptions::max_pixels): 2^28 pixels, 1 GiB of
// RGBA.
inline constexpr int64_t kMaxRenderPixels = int64_t{1} << 28;

struct RenderOptions {
  int width = 0;                 // output width; 0: from the height, else the window's width x scale
  int height = 0;                // output height; 0: keep the window's aspect ratio
  double scale = 1;              // with width and height 0: output pixels per image pixel
  std::optional<Window> window;  // default: the whole image
  // Outputs over this many pixels are refused (Error(kLimit)): a file of a few hundred bytes may
  // declare a 65536 x 4096 image, whose render at 1x would take half a minute and gigabytes.
  // 2^26 (8192 x 8192) of a 3k-vertex photograph takes about 1 s and 150 MB through
  // render_strips on 2 cores (scripts/bench-render, docs/performance.md). At most kMaxRenderPixels.
  int64_t max_pixels = int64_t{1} << 26;
  int level = 0;                 // level of detail
  Overlay overlay = Overlay::kNone;
  bool antialias = true;         // supersample pixels crossed by tears and the border
  int threads = 0;               // <= 0: all cores
  int depth = -1;                // subdivision depth 0..10; -1: from the output scale
  double max_edge_pixels = 2.5;  // depth rule: refined edges average at most this * sqrt(zoom)
  Backend backend = Backend::kCpu;
};

// The output size and window of a render: the one place they are computed. Explicit width and/or
// height (a missing one keeps the window's aspect ratio), else the window's size times `scale`;
// each side rounded, at least 1.
struct RenderSize {
  int width = 0, height = 0;  // output pixels
  Window window;              // image coordinates (the whole image by default)
  double scale_x = 1, scale_y = 1;  // output pixels per image pixel
};

// Resolves and checks the size of a render of an image of image_width x image_height pixels:
// Error(kInvalidArgument) for a negative size, a scale that is not a positive number (or a scale
// beside a width or height), an empty or non-finite window or a bad max_pixels; Error(kLimit)
// ("output size WxH is too large: ...") for an output over Limits::kMaxDimension a side or
// options.max_pixels in all.
RenderSize render_size(const RenderOptions& options, int image_width, int image_height);

// Why Backend::kGpu would fall back to the CPU in this process: "" when an OpenGL 4.3 context can
// be created through EGL, else a one-line reason. The first call tries once; later calls return the
// same answer.
std::string gpu_unavailable_reason();

// The OpenGL renderer that Backend::kGpu would draw with (GL_RENDERER of the probed context; ""
// when gpu_unavailable_reason() is not ""), and whether it is a software rasterizer.
struct GpuRendererInfo {
  std::string name;
  bool software = false;
};
GpuRendererInfo gpu_renderer();
// Whether a GL_RENDERER string names a software rasterizer: Mesa's llvmpipe, softpipe or swrast,
// or another CPU implementation ("software" in the name). Those draw on the CPU, slower than
// subvec's own rasterizer.
bool is_software_renderer(std::string_view gl_renderer);

// The depth rule (docs/performance.md): with L the mean control edge length, in output pixels, of
// the faces whose limit surface may touch the window, and s the zoom (output pixels per image
// pixel), the depth is the smallest k in 0..8 with L / 2^k <= max_edge_pixels * sqrt(max(1, s)),
// lowered while the refined triangles would exceed 2^24. The deviation of the drawn triangles from
// the limit surface falls fourfold a level, so half a level per doubling of s holds it, in output
// pixels, at what the 1x render has. A window zoomed 2^z times refines about z / 2 more levels,
// over fewer faces.

// The control faces and the depth of a view of one level: the renderer's visible-face selection
// (a face is visible when the bounding box of its one-ring meets the window) and its depth rule,
// exactly as render() applies them for the same options.
struct ViewFaces {
  int level = 0;
  int depth = 0;
  RenderSize size;
  bool all_faces = false;      // every control face of the level is visible
  std::vector<int32_t> faces;  // the visible control faces, ascending (all of them when all_faces)
};

// Errors as render() (the level must pass validate_level()).
ViewFaces view_faces(const VectorImage& image, const RenderOptions& options);

// The refined limit mesh of a view, for a front end that draws it itself (apps/serve's page): the
// faces of view_faces() refined to its depth (only those faces and the ring they need, like the
// renderer's partial refinement), with limit positions and colors. The subdivision is kept so that
// an edit of positions or colors can be re-evaluated without refining again.
struct ViewMesh {
  ViewFaces faces;
  std::optional<Subdivision> subdivision;  // empty when no face is visible
  RefinedMesh refined;                     // topology and limit values; empty when no face is visible
  // Whether this refinement holds every face `other` needs at the same level and depth (the rule
  // by which the renderer reuses the refinement of its last view).
  bool covers(const ViewFaces& other) const;
};

// Errors as render(). `options.threads` evaluates; overlay, antialias and backend are not used.
ViewMesh view_mesh(const VectorImage& image, const RenderOptions& options);

// The visible objects of options.level (mesh/vector_image.h), bottom to top, each refined whole to
// the depth render() draws them at for `options` (view_faces' depth) and pushed to the limit: for
// a front end that draws them itself over the level's view.
struct ObjectView {
  int object = 0;  // index in VectorImage::objects
  RefinedMesh refined;
};
std::vector<ObjectView> object_views(const VectorImage& image, const RenderOptions& options);

// Draws the image as described by `options`; RGB, or RGBA when the window leaves the image. On
// the CPU a view of over 2^20 refined triangles is drawn in tiles (render_strips(), the same
// bytes), so that its memory is the output's and a bounded refinement, not the whole view's.
// Throws Error(kInvalidArgument) for a bad level, size, window or depth, Error(kLimit) for an
// output over the size limits, Error(kInvalidMesh) when the level fails validate_level().
Image8 render(const VectorImage& image, const RenderOptions& options);

// Tiles of render_strips(): square tiles of `tile` output pixels a side (a multiple of 64, 64 to
// 8192), drawn in horizontal strips of one tile row. 0: chosen from the refined triangles per
// output pixel and the width (256 to 2048: at most about 2^18 refined triangles a tile before the
// ring, and down to 1024, a strip of at most 32 MiB).
struct TileOptions {
  int tile = 0;
};

// Draws the render of `options` in tiles, strip by strip, top to bottom: sink(y0, strip) receives
// rows [y0, y0 + strip.height) of the output, at the output's full width, each row once and in
// order; `strip` is valid during the call only. The depth is the one render() chooses for the
// whole view (the depth rule over every visible face); each tile then refines only the control
// faces whose limit surface may come within a few output pixels of it (with the ring they need),
// and draws only its own pixels, so the rows are render()'s byte for byte (tears, border,
// overlays and strokes included), whatever the tile size or thread count. Peak memory depends on
// the tile size and the mesh, not on the output size. Always on the CPU (options.backend is not
// used). Errors as render(), before the first call of `sink`; what `sink` throws propagates.
void render_strips(const VectorImage& image, const RenderOptions& options,
                   const std::function<void(int y0, const Image8& strip)>& sink,
                   const TileOptions& tiles = {});

// A renderer that keeps the refinement of the last view, so that redrawing the same view, a view
// inside it at the same depth (pan, zoom within a level), or drawing after an edit of positions or
// colors (set_positions / set_colors: limit values re-evaluated) skips refinement. Not thread-safe;
// one render at a time per Renderer.
class Renderer {
 public:
  explicit Renderer(VectorImage image);
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;

  const VectorImage& image() const;
  Image8 render(const RenderOptions& options);
  // The same into `out`, reusing its memory when its size matches (an interactive redraw then
  // allocates nothing).
  void render(const RenderOptions& options, Image8& out);
  // Edits that keep topology: the cached refinement is kept and only re-evaluated.
  void set_positions(int level, std::span<const Vec2> positions);
  void set_colors(int level, std::span<const Color> colors);
  // The backend that drew the last frame (kCpu when kGpu was asked for and is unavailable).
  Backend last_backend() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace subvec
