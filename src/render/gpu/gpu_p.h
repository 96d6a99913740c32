// The GPU path of the renderer (docs/gpu.md): OpenGL 4.3 core in a headless EGL context. This
// header has no GL or EGL types, so the rest of the library never includes GL headers; the GL code
// is in gpu_rasterizer.cpp (or gpu_stub.cpp in a build without SUBVEC_GPU).
//
// Design note. The CPU renderer is the reference (STYLE.md habit 8), so the GPU path reproduces
// its sampling rather than the hardware's own anti-aliasing:
//  - limit values: the same CSR limit stencils (Subdivision::position_stencils() /
//    color_stencils(), rows of about 11 weights) are uploaded once per refinement and applied by a
//    compute shader, one row per invocation; an edit uploads only the control values;
//  - geometry: refined triangles are pulled in the vertex shader by (vertex, color) index pairs,
//    so face-varying colors (tears) need no duplicated vertices; vertices are snapped to the CPU's
//    24.8 fixed point in double precision, and the projection uses power-of-two scales only, so the
//    GPU sees exactly the CPU's vertex positions;
//  - anti-aliasing, as the CPU does it: every pixel is its centre sample (a pass at the output
//    size), except the pixels crossed by refined tear edges (and border edges when the window
//    leaves the image), marked by a compute shader with the CPU's marking rule, which are the mean
//    of their covered samples in a second pass at 4x4 the output size: the CPU's subsample grid at
//    offsets (k + 0.5) / 4, each subsample rounded as the CPU rounds. Hardware MSAA would not do:
//    sample positions are the driver's (llvmpipe offers 4), one sample in 16 on a tear with a jump
//    of 200 levels is 12 levels, and multisampling every pixel also smooths the places where the
//    limit surface folds over itself, which the CPU leaves sharp.
//    Large frames are drawn in tiles of at most 2^22 output pixels (2^26 subsamples).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "render/raster_p.h"
#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec::detail {

// "" when a GPU context can be created in this process, else why not (tried once, then cached).
// `no_display` (when given) tells whether the failure is that no EGL display exists at all (no
// driver, no device), as opposed to a display without a usable OpenGL 4.3 context.
std::string gpu_probe(bool* no_display = nullptr);
// The GL_RENDERER string of the context gpu_probe() created ("" when none could be).
std::string gpu_probe_renderer();

// Where the GPU time of the last frame went, in milliseconds, for profiling (bench/gpu_bench.cpp's
// GpuPasses, scripts/gpu-check's report). The passes are timed by GL timestamp queries, summed over
// the frame's tiles; `read_back` and `frame` are wall-clock times on the calling thread.
struct GpuPassTimes {
  double stencils = 0;   // the stencil products of the edits since the previous frame (compute)
  double centres = 0;    // the refined triangles drawn at the pixel centres
  double samples = 0;    // ... and at the 4x4 subsamples (frames with tears to anti-alias)
  double mark = 0;       // marking the pixels that tears cross (compute)
  double resolve = 0;    // resolving the samples into packed bytes (compute)
  double read_back = 0;  // copying the packed bytes into the output rows, after the GPU finished
  double frame = 0;      // the whole draw call
  int tiles = 0;
};

// Profiling is off by default: the queries make every frame wait for the GPU at its end. Turned on
// for the process; the times are those of the last frame any rasterizer drew while it was on.
void set_gpu_profiling(bool on);
GpuPassTimes gpu_pass_times();

// One EGL context with its programs and buffers. Not thread-safe; each call makes the context
// current on the calling thread.
class GpuRasterizer {
 public:
  // nullptr and a one-line `error` when no context can be created.
  static std::unique_ptr<GpuRasterizer> create(std::string& error);
  virtual ~GpuRasterizer() = default;
  // The context's GL_RENDERER string (e.g. "NVIDIA H200/PCIe/SSE2", "llvmpipe (LLVM 15.0.6, 256 bits)").
  virtual std::string renderer() const = 0;

  // A new refinement: uploads its limit stencils (built here when not built yet) and its
  // triangles. The control values must be set afterwards.
  virtual void set_refinement(const Subdivision& subdivision) = 0;
  // New control values (the full arrays of the mesh): uploaded and pushed through the stencils on
  // the GPU.
  virtual void set_positions(std::span<const Vec2> positions) = 0;
  virtual void set_colors(std::span<const Color> colors) = 0;
  // Draws the refined triangles of the view into `out` (view.width x view.height, `channels` 3 or
  // 4), reusing its memory when the size matches. With `antialias`, 4x4 subsamples in the pixels
  // that tears (and, for RGBA, the border) cross.
  virtual void draw(const ViewTransform& view, int channels, bool antialias, Image8& out) = 0;
  // The limit positions (#N by 2) as evaluated on the GPU (feature overlays, tests).
  virtual void read_positions(std::vector<float>& out) = 0;
  virtual void read_colors(std::vector<float>& out) = 0;
};

}  // namespace subvec::detail
