// render_strips (tiles, rows streamed) against the one-piece render (Renderer, which never tiles):
// the same bytes at the same depth, whatever the tile size or thread count, across tears, the
// border, overlays and strokes; and render(), which tiles large views, against the same.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>

#include "render/renderer_p.h"
#include "subvec/core/error.h"
#include "subvec/io/image_io.h"
#include "subvec/render/renderer.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

using test::make_synthetic_image;

const VectorImage& image512() {
  static const VectorImage image = [] {
    VectorImage im = make_synthetic_image();
    // A stroke across the middle, crossing tile seams at every tile size below.
    Stroke s;
    s.level = 0;
    s.width = 3;
    s.taper = 0.2f;
    s.color = {250, 20, 40};
    s.points = {{40, 60}, {170, 250}, {260, 130}, {470, 400}};
    im.strokes.push_back(s);
    return im;
  }();
  return image;
}

// The strips of render_strips() stacked into one image; checks that they come in order.
Image8 stacked(const VectorImage& image, const RenderOptions& options, int tile) {
  Image8 out;
  int next = 0;
  render_strips(
      image, options,
      [&](int y0, const Image8& strip) {
        EXPECT_EQ(y0, next);
        if (out.width == 0) {
          const RenderSize size = render_size(options, image.width, image.height);
          out = Image8(size.width, size.height, strip.channels);
        }
        ASSERT_EQ(strip.width, out.width);
        ASSERT_EQ(strip.channels, out.channels);
        ASSERT_LE(y0 + strip.height, out.height);
        std::memcpy(out.row(y0), strip.pixels.data(), strip.pixels.size());
        next = y0 + strip.height;
      },
      TileOptions{tile});
  EXPECT_EQ(next, out.height);
  return out;
}

// The first pixel where two images differ, for the failure message.
std::string first_difference(const Image8& a, const Image8& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels) {
    return "sizes " + std::to_string(a.width) + "x" + std::to_string(a.height) + "x" +
           std::to_string(a.channels) + " and " + std::to_string(b.width) + "x" +
           std::to_string(b.height) + "x" + std::to_string(b.channels);
  }
  int count = 0;
  std::string first;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    if (a.pixels[i] == b.pixels[i]) continue;
    if (count++ == 0) {
      const size_t pixel = i / size_t(a.channels);
      first = "pixel (" + std::to_string(pixel % size_t(a.width)) + ", " +
              std::to_string(pixel / size_t(a.width)) + ") " + std::to_string(a.pixels[i]) +
              " vs " + std::to_string(b.pixels[i]);
    }
  }
  return count == 0 ? "" : std::to_string(count) + " bytes differ, first at " + first;
}

struct Case {
  const char* name;
  RenderOptions options;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  RenderOptions o;
  o.width = 600;  // with the depth rule's depth
  out.push_back({"depth rule", o});
  o.overlay = Overlay::kMesh;
  out.push_back({"mesh overlay", o});
  o.overlay = Overlay::kFeatures;
  out.push_back({"feature overlay", o});
  o = {};
  o.width = 700;  // not a multiple of any tile: partial tiles on the right and bottom
  o.depth = 1;    // large refined triangles, crossing several tiles
  out.push_back({"depth 2", o});
  o = {};
  o.window = Window{-30, 200, 260, 560};  // leaves the image: RGBA, the border anti-aliased
  o.width = 410;
  out.push_back({"window leaving the image", o});
  o.antialias = false;
  out.push_back({"no anti-aliasing", o});
  return out;
}

TEST(RenderStrips, EqualsTheOnePieceRenderForEveryTileSizeAndThreadCount) {
  const VectorImage& image = image512();
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const Image8 reference = Renderer(image).render(c.options);
    ASSERT_GT(reference.width, 0);
    for (const int tile : {64, 192, 1024}) {
      for (const int threads : {1, 3}) {
        if (threads == 3 && tile != 192) continue;  // one tile size is enough for threads
        SCOPED_TRACE("tile " + std::to_string(tile) + ", threads " + std::to_string(threads));
        RenderOptions o = c.options;
        o.threads = threads;
        const Image8 tiled = stacked(image, o, tile);
        EXPECT_EQ(first_difference(reference, tiled), "");
      }
    }
  }
}

TEST(RenderStrips, ALargeOneOffRenderIsDrawnInTilesWithTheOnePieceBytes) {
  // render() tiles views of over 2^20 refined triangles; the same rule with a bound of 2^16, so
  // that views of a few hundred pixels cross it (2^20 took 2,600 px: 20 s, minutes under ASan).
  const VectorImage& image = image512();
  constexpr double kBound = double(1 << 16);
  for (const bool window : {false, true}) {
    SCOPED_TRACE(window ? "window" : "whole image");
    RenderOptions o;
    o.width = window ? 300 : 700;
    if (window) o.window = Window{-20, 40, 400, 300}, o.depth = 4;
    const ViewFaces view = view_faces(image, o);
    ASSERT_GT(double(view.faces.size()) * std::ldexp(1.0, 2 * view.depth), kBound);
    bool tiled = false;
    const Image8 out = detail::render_one_off(image, o, kBound, &tiled);
    EXPECT_TRUE(tiled);
    EXPECT_EQ(first_difference(Renderer(image).render(o), out), "");
    // Under the bound: one piece.
    detail::render_one_off(image, o, double(view.faces.size()) * std::ldexp(1.0, 2 * view.depth), &tiled);
    EXPECT_FALSE(tiled);
  }
  // render() itself is that rule at 2^20: the 512-class image at 1x stays in one piece.
  bool tiled = true;
  EXPECT_EQ(first_difference(detail::render_one_off(image, {}, double(1 << 20), &tiled), render(image, {})), "");
  EXPECT_FALSE(tiled);
}

TEST(RenderStrips, ARefusedRenderCallsNoSink) {
  RenderOptions o;
  o.width = 1 << 15;
  o.height = 1 << 15;
  int calls = 0;
  EXPECT_THROW(render_strips(image512(), o, [&](int, const Image8&) { ++calls; }), Error);
  o = {};
  EXPECT_THROW(render_strips(image512(), o, [&](int, const Image8&) { ++calls; }, TileOptions{100}),
               Error);
  EXPECT_EQ(calls, 0);
}

TEST(PngWriter, StreamedRowsAreWritePngsBytes) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("subvec_png_writer_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  RenderOptions o;
  o.window = Window{-10, -10, 300, 200};  // RGBA
  const Image8 whole = render(image512(), o);
  write_png(dir / "whole.png", whole);
  {
    PngWriter w(dir / "rows.png", whole.width, whole.height, whole.channels);
    for (int y = 0; y < whole.height; y += 37) {
      Image8 strip(whole.width, std::min(37, whole.height - y), whole.channels);
      std::memcpy(strip.pixels.data(), whole.row(y), strip.pixels.size());
      w.write_rows(strip);
    }
    w.finish();
  }
  const auto bytes = [](const std::filesystem::path& p) {
    return std::filesystem::file_size(p);
  };
  EXPECT_EQ(bytes(dir / "whole.png"), bytes(dir / "rows.png"));
  const Image8 back = read_image(dir / "rows.png");
  EXPECT_EQ(back.width, whole.width);
  // An unfinished writer leaves no file behind.
  {
    PngWriter w(dir / "partial.png", 10, 10, 3);
    w.write_rows(Image8(10, 4, 3));
    EXPECT_THROW(w.finish(), Error);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "partial.png"));
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  }
  std::filesystem::remove_all(dir);
}

TEST(GpuRenderer, SoftwareRasterizersAreNamed) {
  EXPECT_TRUE(is_software_renderer("llvmpipe (LLVM 15.0.6, 256 bits)"));
  EXPECT_TRUE(is_software_renderer("Mesa softpipe"));
  EXPECT_TRUE(is_software_renderer("Software Rasterizer"));
  EXPECT_FALSE(is_software_renderer("NVIDIA H200/PCIe/SSE2"));
  EXPECT_FALSE(is_software_renderer("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 15.0.7)"));
  EXPECT_FALSE(is_software_renderer("Mesa Intel(R) UHD Graphics 620 (KBL GT2)"));
  // The library's answer is consistent with the probe.
  const GpuRendererInfo info = gpu_renderer();
  EXPECT_EQ(info.name.empty(), !gpu_unavailable_reason().empty());
  EXPECT_EQ(info.software, !info.name.empty() && is_software_renderer(info.name));
}

}  // namespace
}  // namespace subvec

