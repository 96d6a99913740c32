// GPU renderer benchmarks (issue 10): frame time of Backend::kGpu, and of the CPU for reference, at
// 512x512, 1920x1080 and 3840x2160 for a ~3,000- and a ~20,000-control-vertex image, with the
// refinement and its stencils cached (a redraw) and after an edit (new positions and colors
// uploaded and pushed through the stencils on the GPU, then a frame). A frame includes the
// read-back into the caller's Image8, and each GPU frame is compared with the CPU renderer's
// (counters mae, max_diff). GpuPasses/... are the GPU cases again with each pass timed by GL timer
// queries (counters in ms per frame). Results in docs/gpu.md; scripts/gpu-check runs
// them on a GPU machine and writes the report.
// Run: build/bin/subvec_bench --benchmark_filter='Frame|Passes' --benchmark_repetitions=3
//        --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "render/gpu/gpu_p.h"
#include "subvec/render/renderer.h"
#include "support/frame_difference.h"
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

void add(detail::GpuPassTimes& sum, const detail::GpuPassTimes& t) {
  sum.stencils += t.stencils;
  sum.centres += t.centres;
  sum.samples += t.samples;
  sum.mark += t.mark;
  sum.resolve += t.resolve;
  sum.read_back += t.read_back;
  sum.frame += t.frame;
}

enum class Frames { kCached, kAfterEdit };

// Frames of one view (the first one, before timing, refines): redraws with the refinement cached,
// or an edit of every position (a small drag field) and color before each frame, which on the GPU
// uploads the control values and pushes them through the cached stencils. With `profile`, the
// passes are timed with GL timer queries (counters in ms per frame; the queries make each frame
// wait for the GPU, so the frame times of these cases are not the GpuFrame ones). GPU frames are
// compared with the CPU renderer's frame of the same state afterwards (counters mae, max_diff).
void frames(benchmark::State& state, int which, int size, Backend backend, Frames kind,
            bool profile) {
  if (gpu_missing(state, backend)) return;
  const VectorImage& img = image(which);
  Renderer renderer(img);
  const RenderOptions o = options(size, backend);
  Image8 frame;
  renderer.render(o, frame);
  if (backend == Backend::kGpu && renderer.last_backend() != Backend::kGpu) {
    state.SkipWithError("the GPU context could not draw this view; it was drawn on the CPU");
    return;
  }
  std::vector<Color> colors_a = img.levels[0].colors, colors_b = colors_a;
  for (Color& c : colors_b) c = {c.g, c.b, c.r};
  std::vector<Vec2> positions_a = img.levels[0].positions, positions_b = positions_a;
  positions_b[positions_b.size() / 2 + 7].x += 1.0;
  bool flip = false;
  detail::GpuPassTimes passes;
  detail::set_gpu_profiling(profile);
  for (auto _ : state) {
    if (kind == Frames::kAfterEdit) {
      flip = !flip;
      renderer.set_positions(0, flip ? positions_b : positions_a);
      renderer.set_colors(0, flip ? colors_b : colors_a);
    }
    renderer.render(o, frame);
    benchmark::DoNotOptimize(frame.pixels.data());
    if (profile) add(passes, detail::gpu_pass_times());
  }
  detail::set_gpu_profiling(false);
  state.counters["control_vertices"] = img.levels[0].num_vertices();
  if (profile) {
    const auto per_frame = benchmark::Counter::kAvgIterations;
    state.counters["stencils_ms"] = benchmark::Counter(passes.stencils, per_frame);
    state.counters["centres_ms"] = benchmark::Counter(passes.centres, per_frame);
    state.counters["samples_ms"] = benchmark::Counter(passes.samples, per_frame);
    state.counters["mark_ms"] = benchmark::Counter(passes.mark, per_frame);
    state.counters["resolve_ms"] = benchmark::Counter(passes.resolve, per_frame);
    state.counters["read_back_ms"] = benchmark::Counter(passes.read_back, per_frame);
    state.counters["frame_ms"] = benchmark::Counter(passes.frame, per_frame);
  } else if (backend == Backend::kGpu) {
    Renderer cpu(img);
    if (flip) {
      cpu.set_positions(0, positions_b);
      cpu.set_colors(0, colors_b);
    }
    RenderOptions c = o;
    c.backend = Backend::kCpu;
    const test::FrameDifference d = test::frame_difference(cpu.render(c), frame);
    state.counters["mae"] = d.mae;
    state.counters["max_diff"] = d.max;
  }
}

const int registered = [] {
  const char* images[] = {"3k", "20k"};
  const char* sizes[] = {"512x512", "1920x1080", "3840x2160"};
  struct Group {
    const char* prefix;
    Backend backend;
    bool profile;
  };
  for (const Group& g :
       {Group{"GpuFrame/", Backend::kGpu, false}, Group{"CpuFrame/", Backend::kCpu, false},
        Group{"GpuPasses/", Backend::kGpu, true}}) {
    for (int which = 0; which < 2; ++which) {
      for (int size = 0; size < 3; ++size) {
        const std::string name = g.prefix + std::string(images[which]) + "/" + sizes[size];
        for (Frames kind : {Frames::kCached, Frames::kAfterEdit}) {
          const std::string full = name + (kind == Frames::kCached ? "/cached" : "/edit");
          benchmark::RegisterBenchmark(full.c_str(), frames, which, size, g.backend, kind,
                                       g.profile)
              ->UseRealTime()
              ->Unit(benchmark::kMillisecond);
        }
      }
    }
  }
  return 0;
}();

}  // namespace
}  // namespace subvec
