// View planning for the renderer (exposed for tests): output size, view transform, visible control
// faces and the subdivision depth.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "render/raster_p.h"
#include "subvec/mesh/topology.h"
#include "subvec/render/renderer.h"

namespace subvec::detail {

// The depth rule refines at most this many triangles on its own (an explicit depth may go to 2^26).
constexpr int64_t kMaxAutoTriangles = int64_t{1} << 24;
constexpr int kMaxAutoDepth = 8;

// Per control face, the bounding box (x0, y0, x1, y1) of the control vertices of every face that
// shares a vertex with it: its limit patch lies in their convex hull, so inside this box.
std::vector<std::array<double, 4>> ring_boxes(const ControlMesh& mesh,
                                              const MeshTopology& topology);

// The same bound after `levels` steps of refinement: per control face, the union over its
// children of the box of their refined one-rings. Tighter (a child's ring is a quarter of the
// size per level), at the cost of refining the whole level `levels` times; the tiles of a large
// render select their faces by these.
std::vector<std::array<double, 4>> refined_ring_boxes(const ControlMesh& mesh,
                                                      const MeshTopology& topology, int levels,
                                                      int threads);

// Whether a face's ring box meets the window: the renderer's visibility rule, for a view and for
// each tile of one.
inline bool box_meets(const std::array<double, 4>& b, const Window& w) {
  return !(b[2] < w.x0 || b[0] > w.x1 || b[3] < w.y0 || b[1] > w.y1);
}

struct ViewPlan {
  ViewTransform view;
  Window window;
  int channels = 3;             // 4 when the window leaves the image
  bool all_faces = false;       // every control face is visible (faces lists them all)
  std::vector<int32_t> faces;   // visible control faces, ascending
  double mean_edge_pixels = 0;  // mean control edge length of the visible faces, output pixels
  int depth = 0;
};

// Checks the options (Error(kInvalidArgument) / kLimit) and plans the view of one level.
ViewPlan plan_view(const VectorImage& image, const ControlMesh& mesh,
                   std::span<const std::array<double, 4>> boxes, const RenderOptions& options);

// Whether a refinement of `have` (all faces when have_all) holds every face of `want` at the same
// level and depth: the rule by which a refinement is reused (Renderer's cache, ViewMesh::covers).
bool covers_faces(std::span<const int32_t> have, bool have_all, std::span<const int32_t> want,
                  bool want_all);

// The depth rule (renderer.cpp): the smallest k in 0..8 with
// mean_edge_pixels / 2^k <= max_edge_pixels * sqrt(max(1, zoom)), zoom in output pixels per image
// pixel, lowered until num_faces * 4^k <= kMaxAutoTriangles.
int choose_depth(double mean_edge_pixels, double max_edge_pixels, double zoom, int64_t num_faces);

// render(): a CPU view of more than `one_piece_triangles` refined triangles (render() passes
// 2^20) is drawn in tiles by render_strips(), which `tiled` reports; any other in one piece.
Image8 render_one_off(const VectorImage& image, const RenderOptions& options, double one_piece_triangles,
                      bool* tiled = nullptr);

}  // namespace subvec::detail
