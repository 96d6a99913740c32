// GPU renderer benchmarks (issue 10): frame time of Backend::kGpu, and of the CPU for reference, at
// 512x512, 1920x1080 and 3840x2160 for a ~3,000- and a ~20,000-control-vertex image, with the
// refinement and its stencils cached (a redraw) and after an edit (new positions and colors
// uploaded and pushed through the stencils on the GPU, then a frame). A frame includes the
// read-back into the caller's Image8. Results in docs/gpu.md.
// Run: build/bin/subvec_bench --benchmark_filter='Frame' --benchmark_repetitions=3
//        --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include <string>

#include "subvec/render/renderer.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

// The ~3,000-vertex synthetic image of the CPU benchmarks (512x512), and a ~20,000-vertex one
// (1024x1024, the same construction).
const VectorImage& image(int which) {
  static const VectorImage small = test::make_synthetic_image();
  static const VectorImage large = [] {
    test::SyntheticOptions o;
    o.width = 1024;
    o.height = 1024;
    o.vertices = 20000;
    return test::make_synthetic_image(o);
  }();
  return which == 0 ? small : large;
}

constexpr int kSizes[3][2] = {{512, 512}, {1920, 1080}, {3840, 2160}};

RenderOptions options(int size, Backend backend) {
  RenderOptions o;
  o.width = kSizes[size][0];
  o.height = kSizes[size][1];
  o.backend = backend;
  return o;
}

bool gpu_missing(benchmark::State& state, Backend backend) {
  if (backend != Backend::kGpu) return false;
  const std::string why = gpu_unavailable_reason();
  if (why.empty()) return false;
  state.SkipWithError(("no GPU context: " + why).c_str());
  return true;
}

// Redraws one view, refinement cached (the first frame, done before timing, refines).
void frame_cached(benchmark::State& state, int which, int size, Backend backend) {
  if (gpu_missing(state, backend)) return;
  Renderer renderer(image(which));
  const RenderOptions o = options(size, backend);
  Image8 frame;
  renderer.render(o, frame);
  for (auto _ : state) {
    renderer.render(o, frame);
    benchmark::DoNotOptimize(frame.pixels.data());
  }
  state.counters["control_vertices"] = image(which).levels[0].num_vertices();
}

// An edit of every position (a small drag field) and color, then a frame: on the GPU the control
// values are uploaded and pushed through the cached stencils.
void frame_after_edit(benchmark::State& state, int which, int size, Backend backend) {
  if (gpu_missing(state, backend)) return;
  const VectorImage& img = image(which);
  Renderer renderer(img);
  const RenderOptions o = options(size, backend);
  Image8 frame;
  renderer.render(o, frame);
  std::vector<Color> colors_a = img.levels[0].colors, colors_b = colors_a;
  for (Color& c : colors_b) c = {c.g, c.b, c.r};
  std::vector<Vec2> positions_a = img.levels[0].positions, positions_b = positions_a;
  positions_b[positions_b.size() / 2 + 7].x += 1.0;
  bool flip = false;
  for (auto _ : state) {
    flip = !flip;
    renderer.set_positions(0, flip ? positions_b : positions_a);
    renderer.set_colors(0, flip ? colors_b : colors_a);
    renderer.render(o, frame);
    benchmark::DoNotOptimize(frame.pixels.data());
  }
}

const int registered = [] {
  const char* images[] = {"3k", "20k"};
  const char* sizes[] = {"512x512", "1920x1080", "3840x2160"};
  for (Backend backend : {Backend::kGpu, Backend::kCpu}) {
    const std::string prefix = backend == Backend::kGpu ? "GpuFrame/" : "CpuFrame/";
    for (int which = 0; which < 2; ++which) {
      for (int size = 0; size < 3; ++size) {
        const std::string name = prefix + images[which] + "/" + sizes[size];
        benchmark::RegisterBenchmark((name + "/cached").c_str(), frame_cached, which, size, backend)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark((name + "/edit").c_str(), frame_after_edit, which, size,
                                     backend)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
      }
    }
  }
  return 0;
}();

}  // namespace
}  // namespace subvec
