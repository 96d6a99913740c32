// Renderer benchmarks (issue 2 targets, on the synthetic ~3,000-vertex / ~5,800-triangle image):
//   (a) 512x512 full frame, topology cached           <= 8 ms
//   (b) 512x512 after a color or a position edit      <= 25 ms
//   (c) 3840x2160 full frame, topology cached         <= 120 ms
//   (d) 512x512 window of a 16x zoom, cached          <= 1.5 x (a)
// Run: build/bin/subvec_bench --benchmark_filter=Render --benchmark_repetitions=5
//        --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include "subvec/render/renderer.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

const VectorImage& synthetic() {
  static const VectorImage image = test::make_synthetic_image();
  return image;
}

RenderOptions options(int width, int height, int threads = 0) {
  RenderOptions o;
  o.width = width;
  o.height = height;
  o.threads = threads;
  return o;
}

// Redraws one view with the refinement cached (the first frame, done before timing, refines).
void cached(benchmark::State& state, const RenderOptions& o) {
  Renderer renderer(synthetic());
  Image8 frame;
  renderer.render(o, frame);
  for (auto _ : state) {
    renderer.render(o, frame);  // a redraw into the window's buffer, as an interactive view does
    benchmark::DoNotOptimize(frame.pixels.data());
  }
  state.counters["pixels"] = double(o.width) * o.height;
}

void BM_RenderFull512(benchmark::State& state) {
  cached(state, options(512, 512, static_cast<int>(state.range(0))));
}
BENCHMARK(BM_RenderFull512)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_RenderFull512NoAA(benchmark::State& state) {
  RenderOptions o = options(512, 512);
  o.antialias = false;
  cached(state, o);
}
BENCHMARK(BM_RenderFull512NoAA)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_RenderColorEdit512(benchmark::State& state) {
  Renderer renderer(synthetic());
  const RenderOptions o = options(512, 512);
  renderer.render(o);
  std::vector<Color> a = synthetic().levels[0].colors, b = a;
  for (Color& c : b) c = {c.g, c.b, c.r};
  bool flip = false;
  for (auto _ : state) {
    renderer.set_colors(0, (flip = !flip) ? b : a);
    benchmark::DoNotOptimize(renderer.render(o).pixels.data());
  }
}
BENCHMARK(BM_RenderColorEdit512)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_RenderPositionEdit512(benchmark::State& state) {
  Renderer renderer(synthetic());
  const RenderOptions o = options(512, 512);
  renderer.render(o);
  std::vector<Vec2> a = synthetic().levels[0].positions, b = a;
  // A small drag of one interior vertex (the face selection stays the same).
  b[b.size() / 2 + 7].x += 1.0;
  bool flip = false;
  for (auto _ : state) {
    renderer.set_positions(0, (flip = !flip) ? b : a);
    benchmark::DoNotOptimize(renderer.render(o).pixels.data());
  }
}
BENCHMARK(BM_RenderPositionEdit512)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_Render4K(benchmark::State& state) { cached(state, options(3840, 2160)); }
BENCHMARK(BM_Render4K)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_RenderZoom16(benchmark::State& state) {
  RenderOptions o = options(512, 512);
  o.window = Window{200, 200, 232, 232};  // crosses the tear of the upper-left circle
  cached(state, o);
}
BENCHMARK(BM_RenderZoom16)->UseRealTime()->Unit(benchmark::kMillisecond);

// For reference: a first frame, refinement included.
void BM_RenderFull512Uncached(benchmark::State& state) {
  const RenderOptions o = options(512, 512);
  for (auto _ : state) benchmark::DoNotOptimize(render(synthetic(), o).pixels.data());
}
BENCHMARK(BM_RenderFull512Uncached)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_RenderOverlayMesh512(benchmark::State& state) {
  RenderOptions o = options(512, 512);
  o.overlay = Overlay::kMesh;
  cached(state, o);
}
BENCHMARK(BM_RenderOverlayMesh512)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace subvec

BENCHMARK_MAIN();
