// Rasterization of a vector image (paper §7.1) on the CPU, or on the GPU through OpenGL (Backend).
//
// The renderer refines only the control faces whose limit surface touches the view window, to a
// depth chosen from the output scale, pushes the refined vertices to the limit and draws the
// triangles with Gouraud interpolation under a top-left fill rule. Tears and the image border are
// anti-aliased by supersampling the pixels they cross. Work is split over horizontal bands, one
// writer per pixel, so the output is byte-identical whatever the thread count.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

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

struct RenderOptions {
  int width = 0;                 // output width; 0: the window's width in image pixels
  int height = 0;                // output height; 0: keep the window's aspect ratio
  std::optional<Window> window;  // default: the whole image
  int level = 0;                 // level of detail
  Overlay overlay = Overlay::kNone;
  bool antialias = true;         // supersample pixels crossed by tears and the border
  int threads = 0;               // <= 0: all cores
  int depth = -1;                // subdivision depth 0..10; -1: from the output scale
  double max_edge_pixels = 2.5;  // depth rule: refine until refined edges average at most this
  Backend backend = Backend::kCpu;
};

// Why Backend::kGpu would fall back to the CPU in this process: "" when an OpenGL 4.3 context can
// be created through EGL, else a one-line reason. The first call tries once; later calls return the
// same answer.
std::string gpu_unavailable_reason();

// The depth rule (docs/performance.md): with L the mean control edge length, in output pixels, of
// the faces whose limit surface may touch the window, the depth is the smallest k in 0..8 with
// L / 2^k <= max_edge_pixels, lowered while the refined triangles would exceed 2^24. A window
// zoomed 2^z times refines z more levels over fewer faces: it costs about what a full view of the
// same output size costs.

// Draws the image as described by `options`; RGB, or RGBA when the window leaves the image.
// Throws Error(kInvalidArgument) for a bad level, size, window or depth, Error(kLimit) for an
// output over the size limits, Error(kInvalidMesh) when the level fails validate_level().
Image8 render(const VectorImage& image, const RenderOptions& options);

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
