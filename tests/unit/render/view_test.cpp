// The view mesh (view_mesh, view_faces) against the renderer, the output size (render_size), and
// the partial refinement against a full one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "subvec/core/error.h"
#include "subvec/render/renderer.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

using test::make_synthetic_image;

const VectorImage& image512() {
  static const VectorImage image = make_synthetic_image();
  return image;
}

// Reference face selection, written out: a face is visible when the bounding box of the control
// vertices of every face sharing a vertex with it meets the window (closed intervals).
std::vector<int32_t> faces_by_brute_force(const ControlMesh& mesh, const Window& w) {
  std::vector<std::vector<int32_t>> faces_of(mesh.num_vertices());
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    for (int v : mesh.triangles[f]) faces_of[v].push_back(f);
  }
  std::vector<int32_t> out;
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (int v : mesh.triangles[f]) {
      for (int g : faces_of[v]) {
        for (int u : mesh.triangles[g]) {
          const Vec2 p = mesh.positions[u];
          x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
        }
      }
    }
    if (x1 >= w.x0 && x0 <= w.x1 && y1 >= w.y0 && y0 <= w.y1) out.push_back(f);
  }
  return out;
}

// Reference depth, written out (docs/performance.md): the smallest k with L / 2^k <= max_edge,
// L the mean control edge of the faces in output pixels.
int depth_by_brute_force(const ControlMesh& mesh, const std::vector<int32_t>& faces, double sx,
                         double sy, double max_edge) {
  double sum = 0;
  for (int32_t f : faces) {
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = mesh.positions[mesh.triangles[f][k]];
      const Vec2 b = mesh.positions[mesh.triangles[f][(k + 1) % 3]];
      sum += std::hypot((b.x - a.x) * sx, (b.y - a.y) * sy);
    }
  }
  const double mean = sum / double(3 * faces.size());
  int k = 0;
  const double target = max_edge * std::sqrt(std::max(1.0, std::min(sx, sy)));
  while (k < 8 && mean / std::pow(2.0, k) > target) ++k;
  return k;
}

struct Case {
  const char* name;
  std::optional<Window> window;
  int width;
  double scale;
  double max_edge;
};

TEST(ViewMesh, DepthAndFacesAreTheRenderers) {
  test::SyntheticOptions small;
  small.vertices = 1000;
  const VectorImage image = make_synthetic_image(small);
  const ControlMesh& mesh = image.levels[0];
  const Case cases[] = {
      {"whole image", std::nullopt, 256, 1, 2.5},
      {"whole image, small", std::nullopt, 100, 1, 2.5},
      {"zoom 8x", Window{200, 220, 232, 252}, 256, 1, 2.5},
      {"zoom 6x, coarse", Window{100, 300, 180, 360}, 0, 6, 8},
      {"past the corner", Window{-60, -40, 90, 70}, 0, 3, 3},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    RenderOptions o;
    o.window = c.window;
    o.width = c.width;
    o.scale = c.scale;
    o.max_edge_pixels = c.max_edge;
    const ViewMesh view = view_mesh(image, o);
    const RenderSize size = render_size(o, image.width, image.height);
    EXPECT_EQ(view.faces.size.width, size.width);
    EXPECT_EQ(view.faces.size.height, size.height);

    // The faces: the one-ring boxes that meet the window, and only their children are refined.
    const std::vector<int32_t> expected = faces_by_brute_force(mesh, size.window);
    ASSERT_FALSE(expected.empty());
    EXPECT_EQ(view.faces.faces, expected);
    EXPECT_EQ(view.faces.all_faces, static_cast<int>(expected.size()) == mesh.num_triangles());
    const std::set<int32_t> parents(view.refined.triangle_parent.begin(),
                                    view.refined.triangle_parent.end());
    EXPECT_EQ(std::vector<int32_t>(parents.begin(), parents.end()), expected);
    EXPECT_EQ(view.refined.num_triangles(),
              static_cast<int>(expected.size()) << (2 * view.faces.depth));

    // The depth: the rule over those faces at the view's scale...
    EXPECT_EQ(view.faces.depth,
              depth_by_brute_force(mesh, expected, size.scale_x, size.scale_y, c.max_edge));
    // ...and the one the renderer draws at: the same bytes as at that depth named, not as one
    // level coarser (finer where it is 0).
    const Image8 drawn = render(image, o);
    RenderOptions at = o;
    at.depth = view.faces.depth;
    EXPECT_EQ(render(image, at).pixels, drawn.pixels);
    at.depth = view.faces.depth > 0 ? view.faces.depth - 1 : 1;
    EXPECT_NE(render(image, at).pixels, drawn.pixels);
    // view_faces() plans without refining, the same.
    const ViewFaces planned = view_faces(image, o);
    EXPECT_EQ(planned.faces, view.faces.faces);
    EXPECT_EQ(planned.depth, view.faces.depth);
  }
}

TEST(ViewMesh, CoversAViewInsideItAtTheSameDepth) {
  const VectorImage& image = image512();
  RenderOptions o;
  o.window = Window{100, 100, 300, 300};
  o.depth = 3;
  const ViewMesh view = view_mesh(image, o);
  EXPECT_FALSE(view.faces.all_faces);
  EXPECT_TRUE(view.covers(view.faces));
  RenderOptions inside = o;
  inside.window = Window{150, 150, 200, 220};
  EXPECT_TRUE(view.covers(view_faces(image, inside)));
  RenderOptions deeper = inside;
  deeper.depth = 4;
  EXPECT_FALSE(view.covers(view_faces(image, deeper)));
  RenderOptions beside = o;
  beside.window = Window{250, 250, 400, 400};
  EXPECT_FALSE(view.covers(view_faces(image, beside)));
  RenderOptions whole = o;
  whole.window.reset();
  EXPECT_FALSE(view.covers(view_faces(image, whole)));
  EXPECT_TRUE(view_mesh(image, whole).covers(view.faces));
}

TEST(ViewMesh, NothingVisibleIsAnEmptyMesh) {
  RenderOptions o;
  o.window = Window{2000, 2000, 2100, 2100};
  const ViewMesh view = view_mesh(image512(), o);
  EXPECT_TRUE(view.faces.faces.empty());
  EXPECT_FALSE(view.subdivision.has_value());
  EXPECT_EQ(view.refined.num_triangles(), 0);
}

// Reference: the partial refinement (the faces that touch a window and the ring they need) gives
// the limit positions and colors that refining the whole level gives over the same faces.
TEST(ViewMesh, PartialRefinementEqualsTheFullOneOverItsFaces) {
  const VectorImage& image = image512();
  for (const Window w : {Window{150, 140, 300, 260}, Window{-20, 400, 120, 530}}) {
    SCOPED_TRACE(w.x0);
    RenderOptions o;
    o.depth = 3;
    const ViewMesh full = view_mesh(image, o);
    ASSERT_TRUE(full.faces.all_faces);
    o.window = w;
    const ViewMesh part = view_mesh(image, o);
    ASSERT_FALSE(part.faces.all_faces);
    ASSERT_GT(part.faces.faces.size(), 50u);
    // The children of each control face, in refinement order.
    std::map<int32_t, std::vector<int32_t>> full_children, part_children;
    for (int t = 0; t < full.refined.num_triangles(); ++t)
      full_children[full.refined.triangle_parent[t]].push_back(t);
    for (int t = 0; t < part.refined.num_triangles(); ++t)
      part_children[part.refined.triangle_parent[t]].push_back(t);
    double worst_position = 0, worst_color = 0;
    int compared = 0;
    for (const auto& [face, tris] : part_children) {
      const std::vector<int32_t>& reference = full_children[face];
      ASSERT_EQ(tris.size(), reference.size()) << face;
      for (size_t i = 0; i < tris.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
          const auto pv = size_t(part.refined.triangles[tris[i]][k]);
          const auto fv = size_t(full.refined.triangles[reference[i]][k]);
          for (int d = 0; d < 2; ++d) {
            worst_position = std::max(worst_position,
                                      double(std::abs(part.refined.positions[2 * pv + d] -
                                                      full.refined.positions[2 * fv + d])));
          }
          const auto pc = size_t(part.refined.triangle_colors[tris[i]][k]);
          const auto fc = size_t(full.refined.triangle_colors[reference[i]][k]);
          for (int d = 0; d < 3; ++d) {
            worst_color = std::max(worst_color, double(std::abs(part.refined.colors[3 * pc + d] -
                                                                full.refined.colors[3 * fc + d])));
          }
          ++compared;
        }
      }
    }
    EXPECT_GT(compared, 50 * 64 * 3);
    EXPECT_LT(worst_position, 1e-3);  // image pixels
    EXPECT_LT(worst_color, 1e-3);     // 0-255 scale
  }
}

TEST(RenderSize, ScaleWidthHeightAndOneLimit) {
  RenderOptions o;
  RenderSize s = render_size(o, 640, 480);
  EXPECT_EQ(s.width, 640);
  EXPECT_EQ(s.height, 480);
  EXPECT_EQ(s.scale_x, 1);
  o.scale = 2.5;
  o.window = Window{10, 20, 30.2, 40};
  s = render_size(o, 640, 480);
  EXPECT_EQ(s.width, 51);  // round(20.2 * 2.5 = 50.5)
  EXPECT_EQ(s.height, 50);
  EXPECT_DOUBLE_EQ(s.scale_x, 51 / 20.2);
  EXPECT_DOUBLE_EQ(s.window.x1, 30.2);
  o.scale = 1;
  o.width = 101;  // height keeps the aspect ratio
  s = render_size(o, 640, 480);
  EXPECT_EQ(s.width, 101);
  EXPECT_EQ(s.height, 100);
  o.width = 0;
  o.height = 7;
  EXPECT_EQ(render_size(o, 640, 480).width, 7);

  auto code = [](const RenderOptions& options) {
    try {
      render_size(options, 640, 480);
    } catch (const Error& e) {
      return e.code();
    }
    return ErrorCode::kIo;  // stands for "no error"
  };
  RenderOptions bad;
  bad.scale = 0;
  EXPECT_EQ(code(bad), ErrorCode::kInvalidArgument);
  bad.scale = NAN;
  EXPECT_EQ(code(bad), ErrorCode::kInvalidArgument);
  bad.scale = 2;
  bad.width = 10;  // a width and a scale
  EXPECT_EQ(code(bad), ErrorCode::kInvalidArgument);
  bad = {};
  bad.max_pixels = kMaxRenderPixels + 1;
  EXPECT_EQ(code(bad), ErrorCode::kInvalidArgument);
  bad = {};
  bad.window = Window{0, 0, 0, 5};
  EXPECT_EQ(code(bad), ErrorCode::kInvalidArgument);

  // One limit, one message: the pixels in all (max_pixels) and the side.
  RenderOptions big;
  big.max_pixels = 640 * 480 - 1;
  try {
    render_size(big, 640, 480);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kLimit);
    EXPECT_STREQ(e.what(),
                 "output size 640x480 is too large: at most 65536 pixels a side and 307199 pixels "
                 "in all");
  }
  big.max_pixels = 640 * 480;
  EXPECT_EQ(code(big), ErrorCode::kIo);
  big.max_pixels = kMaxRenderPixels;
  big.width = 70000;
  big.height = 1;
  EXPECT_EQ(code(big), ErrorCode::kLimit);
  RenderOptions deflt;
  deflt.scale = 13;  // 8320 x 6240 = 51.9 M: under the default 2^26
  EXPECT_EQ(code(deflt), ErrorCode::kIo);
  deflt.scale = 14;  // 8960 x 6720 = 60.2 M
  EXPECT_EQ(code(deflt), ErrorCode::kIo);
  deflt.scale = 15;  // 9600 x 7200 = 69.1 M: over
  EXPECT_EQ(code(deflt), ErrorCode::kLimit);
}

}  // namespace
}  // namespace subvec
