// Objects drawn over their level: see objects_p.h.
#include "render/objects_p.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/parallel_p.h"
#include "render/strokes_p.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec::detail {
namespace {

// Whether the control points' bounding box (which holds the limit surface) meets the pixels of
// `rect` of the view, with a pixel to spare for the anti-aliased boundary.
bool meets(const ControlMesh& mesh, const ViewTransform& view, const PixelRect& rect) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (const Vec2& p : mesh.positions) {
    const auto [x, y] = view.to_output(p.x, p.y);
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  }
  return x1 >= rect.x0 - 1 && x0 <= rect.x1 + 1 && y1 >= rect.y0 - 1 && y0 <= rect.y1 + 1;
}

// Straight-alpha source-over of `layer` (RGBA) onto `out`, pixels of `rect`; both hold the rows
// from `row0`.
void composite(const Image8& layer, const PixelRect& rect, int row0, Image8& out) {
  for (int y = rect.y0; y < rect.y1; ++y) {
    const uint8_t* s = layer.row(y - row0);
    uint8_t* d = out.row(y - row0);
    for (int x = rect.x0; x < rect.x1; ++x) {
      const uint8_t* p = s + size_t(x) * 4;
      uint8_t* q = d + size_t(x) * out.channels;
      const uint32_t a = p[3];
      if (a == 0) continue;
      if (out.channels == 4) {
        // Over a partly transparent frame (past the image), in premultiplied terms.
        const uint32_t da = q[3] * (255 - a);  // scaled by 255
        const uint32_t oa = a * 255 + da;      // scaled by 255
        for (int c = 0; c < 3; ++c) q[c] = static_cast<uint8_t>((p[c] * a * 255 + q[c] * da + oa / 2) / oa);
        q[3] = static_cast<uint8_t>((oa + 127) / 255);
      } else {
        for (int c = 0; c < 3; ++c) q[c] = static_cast<uint8_t>((p[c] * a + q[c] * (255 - a) + 127) / 255);
      }
    }
  }
}

}  // namespace

void draw_objects(const VectorImage& image, int level, const ViewTransform& view, int depth,
                  bool antialias, int threads, const PixelRect* clip, Image8& out) {
  const PixelRect rect = clip ? *clip : PixelRect{0, 0, view.width, view.height};
  const int row0 = clip ? clip->y0 : 0;
  Image8 layer;
  RefinedMesh refined;
  for (size_t o = 0; o < image.objects.size(); ++o) {
    const Object& object = image.objects[o];
    if (object.level != level || !object.visible) continue;
    // Its strokes, over it and under the objects above.
    auto draw_its_strokes = [&] {
      if (clip) {
        draw_strokes(object.strokes, level, view, *clip, out);
      } else {
        draw_strokes(object.strokes, level, view, out);
      }
    };
    if (!meets(object.mesh, view, rect)) {
      draw_its_strokes();  // a wide stroke may reach past the mesh's box
      continue;
    }
    const MeshTopology topology =
        validate_object(object, image.width, image.height, static_cast<int>(image.levels.size()),
                        static_cast<int>(o));
    {
      const Subdivision subdivision(object.mesh, topology, depth);
      subdivision.evaluate_once(object.mesh.positions, object.mesh.colors, refined, threads);
    }
    RasterOptions raster;
    raster.channels = 4;
    raster.antialias = antialias;
    raster.antialias_border = antialias;
    raster.threads = threads;
    if (clip) {
      // The raster writes only the clip's pixels of a frame the caller cleared.
      layer = Image8(view.width, clip->y1 - clip->y0, 4);
      raster.clip = *clip;
    }
    rasterize_into(refined, view, raster, {}, nullptr, layer);
    composite(layer, rect, row0, out);
    draw_its_strokes();
  }
}

}  // namespace subvec::detail

namespace subvec {

std::vector<ObjectView> object_views(const VectorImage& image, const RenderOptions& options) {
  const ViewFaces view = view_faces(image, options);
  std::vector<ObjectView> out;
  for (const ObjectTopology& o : visible_objects(image, options.level)) {
    const Object& object = image.objects[o.object];
    ObjectView v;
    v.object = o.object;
    const Subdivision subdivision(object.mesh, o.topology, view.depth);
    subdivision.evaluate_once(object.mesh.positions, object.mesh.colors, v.refined,
                              detail::resolve_threads(options.threads));
    out.push_back(std::move(v));
  }
  return out;
}

}  // namespace subvec
