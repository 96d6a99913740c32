// The GPU renderer (OpenGL through headless EGL; Mesa's llvmpipe in CI) against the CPU renderer,
// the reference: the same frames within MAE <= 0.5 and a largest channel difference <= 8, on the
// examples, the synthetic test image, the vectorized butterfly of docs/figures and a photograph
// vectorized here. Skipped, with the reason, only when no EGL display can be created at all.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "render/gpu/gpu_p.h"
#include "subvec/edit/objects.h"
#include "subvec/core/error.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/topology.h"
#include "subvec/render/renderer.h"
#include "subvec/subdiv/subdivision.h"
#include "subvec/vectorize/vectorize.h"
#include "support/frame_difference.h"
#include "support/paths.h"
#include "support/shared_photos.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

// Skips when no EGL display exists; a display without a usable context is a failure.
#define REQUIRE_GPU()                                                                  \
  do {                                                                                 \
    bool no_display = false;                                                           \
    const std::string why = detail::gpu_probe(&no_display);                            \
    if (!why.empty() && no_display) GTEST_SKIP() << "no EGL display: " << why;         \
    ASSERT_TRUE(why.empty()) << "an EGL display exists but GPU rendering fails: " << why; \
  } while (0)

// The sizes must agree; frame_difference() makes frames that don't as far apart as can be.
test::FrameDifference difference(const Image8& a, const Image8& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.channels, b.channels);
  return test::frame_difference(a, b);
}

// Renders `options` on both backends and checks the acceptance bounds.
void expect_match(const VectorImage& image, RenderOptions options, const std::string& what) {
  options.backend = Backend::kCpu;
  const Image8 cpu = render(image, options);
  options.backend = Backend::kGpu;
  Renderer renderer(image);
  const Image8 gpu = renderer.render(options);
  EXPECT_EQ(renderer.last_backend(), Backend::kGpu) << what;
  const test::FrameDifference d = difference(cpu, gpu);
  EXPECT_LE(d.mae, 0.5) << what;
  EXPECT_LE(d.max, 8) << what;
  std::printf("  %-44s %4dx%-4d %dch  MAE %.4f  max %d\n", what.c_str(), cpu.width, cpu.height,
              cpu.channels, d.mae, d.max);
}

// The views every image is checked in: its own size, 3x, a 4x zoom, a window leaving the image
// (RGBA, anti-aliased border), and without anti-aliasing.
void expect_match_in_views(const VectorImage& image, const std::string& name) {
  const double w = image.width, h = image.height;
  RenderOptions o;
  expect_match(image, o, name + " 1x");
  o.width = int(3 * w);
  expect_match(image, o, name + " 3x");
  o.width = int(std::lround(2 * w));
  o.window = Window{0.3 * w, 0.35 * h, 0.55 * w, 0.6 * h};
  expect_match(image, o, name + " window, 8x");
  o.width = int(w);
  o.window = Window{-0.2 * w, -0.1 * h, 1.1 * w, 0.9 * h};
  expect_match(image, o, name + " past the border (RGBA)");
  o = RenderOptions{};
  o.width = int(2 * w);
  o.antialias = false;
  expect_match(image, o, name + " 2x, no anti-aliasing");
}

using test::source_dir;

// Names the OpenGL context the tests run on, once, before them (a bundle run on another machine,
// scripts/gpu-check, reports it).
class ContextReport : public ::testing::Environment {
 public:
  void SetUp() override {
    bool no_display = false;
    const std::string why = detail::gpu_probe(&no_display);
    if (why.empty()) {
      const GpuRendererInfo gl = gpu_renderer();
      std::printf("OpenGL renderer: %s (%s)\n", gl.name.c_str(),
                  gl.software ? "software" : "hardware");
    } else {
      std::printf("OpenGL: no context (%s)\n", why.c_str());
    }
  }
};
const ::testing::Environment* const context_report =
    ::testing::AddGlobalTestEnvironment(new ContextReport);

TEST(GpuRender, MatchesTheCpuOnTheExamples) {
  REQUIRE_GPU();
  for (const char* name : {"01-disk", "02-open-tear", "03-junction"}) {
    const VectorImage image = read_svec(source_dir() / "examples" / (std::string(name) + ".svec.json"));
    expect_match_in_views(image, name);
  }
}

// Over 4096 output pixels wide the 4x4 pass no longer fits one target: the frame is drawn in
// column tiles and copied row by row.
TEST(GpuRender, WideOutputsAreDrawnInTiles) {
  REQUIRE_GPU();
  const VectorImage image = read_svec(source_dir() / "examples" / "02-open-tear.svec.json");
  RenderOptions o;
  o.window = Window{0, 0, 128, 6};
  o.width = 4500;
  expect_match(image, o, "02-open-tear, 4500 wide");
}

// Objects (edit/objects.h) are composited over the GPU's frame by the CPU's rasterizer: the frame
// equals the CPU's as for a level.
TEST(GpuRender, ObjectsMatchTheCpu) {
  REQUIRE_GPU();
  VectorImage image = read_svec(source_dir() / "examples" / "01-disk.svec.json");
  make_object(image, 0, 0, "disk");
  transform_object(image, 0, {.translate = {20, -5}, .rotate_degrees = 15, .scale = 0.8});
  expect_match_in_views(image, "01-disk, the disk an object, moved");
}

TEST(GpuRender, MatchesTheCpuOnTheSyntheticImage) {
  REQUIRE_GPU();
  expect_match_in_views(test::make_synthetic_image(), "synthetic 3,000 vertices");
}

TEST(GpuRender, MatchesTheCpuOnTheVectorizedButterfly) {
  REQUIRE_GPU();
  // docs/figures/butterfly.svec: the shared photograph butterfly.png, vectorized (README.md).
  const VectorImage image = read_svec(source_dir() / "docs" / "figures" / "butterfly.svec");
  expect_match_in_views(image, "butterfly.svec");
}

TEST(GpuRender, MatchesTheCpuOnASharedPhotographVectorizedHere) {
  REQUIRE_GPU();
  const fs::path path = test::shared_photos() / "rocket.png";
  if (!fs::exists(path)) GTEST_SKIP() << "no " << path << ": shared photographs not present";
  // A 160 x 128 crop around the rocket keeps the vectorization to about a second.
  const Image8 photo = read_image(path);
  Image8 crop(160, 128, 3);
  for (int y = 0; y < crop.height; ++y) {
    const uint8_t* src = photo.row(y + 40) + size_t(120) * photo.channels;
    for (int x = 0; x < crop.width; ++x)
      for (int c = 0; c < 3; ++c) crop.row(y)[3 * x + c] = src[x * photo.channels + c];
  }
  VectorizeOptions vo;
  vo.ratio = 0.02;
  const VectorImage image = vectorize(crop, vo);
  expect_match_in_views(image, "rocket.png crop, vectorized");
}

TEST(GpuRender, OverlaysAndStrokesMatchTheCpu) {
  REQUIRE_GPU();
  const VectorImage image = read_svec(source_dir() / "docs" / "figures" / "butterfly.svec");
  for (Overlay overlay : {Overlay::kMesh, Overlay::kFeatures}) {
    RenderOptions o;
    o.overlay = overlay;
    o.width = 600;
    expect_match(image, o, overlay == Overlay::kMesh ? "butterfly, mesh overlay" : "butterfly, features");
  }
}

// Edits keep the refinement: only control values are uploaded and pushed through the stencils.
TEST(GpuRender, EditsMatchTheCpu) {
  REQUIRE_GPU();
  const VectorImage image = test::make_synthetic_image();
  Renderer cpu(image), gpu(image);
  RenderOptions o;
  o.backend = Backend::kGpu;
  RenderOptions c = o;
  c.backend = Backend::kCpu;
  Image8 a = cpu.render(c), b = gpu.render(o);
  EXPECT_LE(difference(a, b).max, 8);
  const Image8 before = b;

  std::vector<Color> colors = image.levels[0].colors;
  for (size_t i = 0; i < colors.size(); i += 3) colors[i] = {255.f - colors[i].r, colors[i].b, 30.f};
  cpu.set_colors(0, colors);
  gpu.set_colors(0, colors);
  a = cpu.render(c), b = gpu.render(o);
  test::FrameDifference d = difference(a, b);
  EXPECT_LE(d.mae, 0.5);
  EXPECT_LE(d.max, 8);

  std::vector<Vec2> positions = image.levels[0].positions;
  const MeshTopology topology = MeshTopology::build(image.levels[0], image.width, image.height);
  for (size_t i = 0; i < positions.size(); ++i) {
    if (topology.vertex_tags[i] == VertexTag::kSmooth) positions[i].x += 0.3 * std::sin(double(i));
  }
  cpu.set_positions(0, positions);
  gpu.set_positions(0, positions);
  a = cpu.render(c), b = gpu.render(o);
  d = difference(a, b);
  EXPECT_LE(d.mae, 0.5);
  EXPECT_LE(d.max, 8);
  EXPECT_EQ(gpu.last_backend(), Backend::kGpu);
  // The edits reached the GPU: the frame changed by far more than the tolerance.
  EXPECT_GT(difference(before, b).mae, 5.0);
}

// The stencils applied on the GPU give the CPU's limit values to float precision.
TEST(GpuRasterizer, LimitValuesMatchTheCpuStencils) {
  REQUIRE_GPU();
  const VectorImage image = test::make_synthetic_image();
  const ControlMesh& mesh = image.levels[0];
  const MeshTopology topology = MeshTopology::build(mesh, image.width, image.height);
  const Subdivision subdivision(mesh, topology, 3);
  RefinedMesh cpu;
  subdivision.evaluate(mesh.positions, mesh.colors, cpu);
  std::string error;
  const auto gpu = detail::GpuRasterizer::create(error);
  ASSERT_TRUE(gpu) << error;
  gpu->set_refinement(subdivision);
  gpu->set_positions(mesh.positions);
  gpu->set_colors(mesh.colors);
  std::vector<float> positions, colors;
  gpu->read_positions(positions);
  gpu->read_colors(colors);
  ASSERT_EQ(positions.size(), cpu.positions.size());
  ASSERT_EQ(colors.size(), cpu.colors.size());
  float worst_position = 0, worst_color = 0;
  for (size_t i = 0; i < positions.size(); ++i)
    worst_position = std::max(worst_position, std::abs(positions[i] - cpu.positions[i]));
  for (size_t i = 0; i < colors.size(); ++i)
    worst_color = std::max(worst_color, std::abs(colors[i] - cpu.colors[i]));
  EXPECT_LT(worst_position, 1e-3f);
  EXPECT_LT(worst_color, 1e-3f);
}

// Profiling (GL timer queries around each pass, detail::set_gpu_profiling) changes no pixel, times
// every pass of the last frame within its wall time (or gives NaN, a time the driver got wrong),
// counts the tiles, and stops with the switch.
TEST(GpuRasterizer, ProfiledFramesAreTheSameFramesAndAreTimed) {
  REQUIRE_GPU();
  const VectorImage image = read_svec(source_dir() / "examples" / "02-open-tear.svec.json");
  RenderOptions o;
  o.backend = Backend::kGpu;
  o.window = Window{0, 0, 128, 6};
  o.width = 4500;  // two column tiles
  Renderer renderer(image);
  const Image8 plain = renderer.render(o);
  std::vector<Color> colors = image.levels[0].colors;
  for (Color& c : colors) c = {c.b, c.r, c.g};
  renderer.set_colors(0, colors);
  const Image8 edited = renderer.render(o);
  renderer.set_colors(0, image.levels[0].colors);

  detail::set_gpu_profiling(true);
  EXPECT_EQ(renderer.render(o).pixels, plain.pixels);
  renderer.set_colors(0, colors);
  const Image8 profiled = renderer.render(o);
  const detail::GpuPassTimes t = detail::gpu_pass_times();
  detail::set_gpu_profiling(false);
  EXPECT_EQ(profiled.pixels, edited.pixels);
  EXPECT_EQ(renderer.last_backend(), Backend::kGpu);
  EXPECT_EQ(t.tiles, 2);
  EXPECT_GT(t.frame, 0.0);
  EXPECT_GE(t.read_back, 0.0);
  EXPECT_LE(t.read_back, t.frame);
  EXPECT_TRUE(std::isnan(t.stencils) || t.stencils >= 0.0);  // before the draw, outside `frame`
  for (double pass : {t.centres, t.samples, t.mark, t.resolve}) {
    if (!std::isnan(pass)) {
      EXPECT_GE(pass, 0.0);
      EXPECT_LE(pass, t.frame);
    }
  }
  // Off again: a frame leaves the last profiled frame's times as they were.
  renderer.render(o);
  EXPECT_EQ(detail::gpu_pass_times().frame, t.frame);
}

TEST(GpuRender, BadOptionsFailAsOnTheCpu) {
  REQUIRE_GPU();
  const VectorImage image = test::make_synthetic_image();
  RenderOptions o;
  o.backend = Backend::kGpu;
  o.window = Window{10, 10, 5, 20};
  EXPECT_THROW(render(image, o), Error);
  o.window.reset();
  o.level = 3;
  EXPECT_THROW(render(image, o), Error);
}

}  // namespace
}  // namespace subvec
