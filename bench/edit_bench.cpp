// Editing benchmarks (issue 5 targets):
//   ARAP drag update on a 10,000-vertex control mesh, after the first (factorization cached)  <= 10 ms
//   color edit (selection + BLEND) plus re-render of a 512x512 frame                           <= 30 ms
// Run: build/bin/subvec_bench --benchmark_filter=Edit --benchmark_repetitions=5
//        --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include "subvec/edit/color.h"
#include "subvec/edit/selection.h"
#include "subvec/edit/shape.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

// The synthetic image with about 10,000 control vertices (drag) or the usual ~3,000 (render).
const VectorImage& synthetic(int vertices) {
  static const VectorImage big = [] {
    test::SyntheticOptions o;
    o.vertices = 10000;
    return test::make_synthetic_image(o);
  }();
  static const VectorImage usual = test::make_synthetic_image();
  return vertices > 5000 ? big : usual;
}

// A mouse drag of part of a feature: every update moves the click point a little further, with
// the same handle vertices, so only the first call factors.
void BM_EditArapDrag10k(benchmark::State& state) {
  const VectorImage& image = synthetic(10000);
  const ControlMesh& mesh = image.levels[0];
  const Feature& feature = mesh.features[0];
  const Vec2 click = mesh.positions[feature.vertices[feature.vertices.size() / 3]];
  ShapeEditor editor(mesh, image.width, image.height);
  std::vector<Vec2> out;
  editor.deform(drag_feature(mesh, feature, click, {1, 1}, 30), out);  // factors
  int step = 0;
  for (auto _ : state) {
    const double d = 1 + (step++ % 8);
    editor.deform(drag_feature(mesh, feature, click, {d, 0.5 * d}, 30), out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["vertices"] = mesh.num_vertices();
  state.counters["triangles"] = mesh.num_triangles();
}
BENCHMARK(BM_EditArapDrag10k)->UseRealTime()->Unit(benchmark::kMillisecond);

// The first update of a new constraint set: the three factorizations.
void BM_EditArapFactor10k(benchmark::State& state) {
  const VectorImage& image = synthetic(10000);
  const ControlMesh& mesh = image.levels[0];
  const Feature& feature = mesh.features[0];
  const Vec2 click = mesh.positions[feature.vertices[feature.vertices.size() / 3]];
  std::vector<Vec2> out;
  for (auto _ : state) {
    ShapeEditor editor(mesh, image.width, image.height);
    editor.deform(drag_feature(mesh, feature, click, {3, 1}, 30), out);
    benchmark::DoNotOptimize(out.data());
  }
}
BENCHMARK(BM_EditArapFactor10k)->UseRealTime()->Unit(benchmark::kMillisecond);

// A BLEND over a 60-pixel region picked at a point, then the 512x512 frame drawn again (the
// renderer keeps its refinement and re-evaluates the colors). threads:1 makes the CPU time the
// whole cost, a figure that a loaded machine disturbs less than the wall-clock time.
void BM_EditColorRender512(benchmark::State& state) {
  const VectorImage& image = synthetic(3000);
  const ControlMesh& mesh = image.levels[0];
  const MeshTopology topology = validate_level(mesh, image.width, image.height);
  Renderer renderer(image);
  RenderOptions o;
  o.width = o.height = 512;
  o.threads = static_cast<int>(state.range(0));
  Image8 frame;
  renderer.render(o, frame);
  std::vector<Color> colors;
  int step = 0;
  for (auto _ : state) {
    const float amount = 0.2f + 0.1f * float(step++ % 4);
    const ColorSelection s = select_vertex_colors(mesh, topology, {256, 256}, 60);
    colors = mesh.colors;
    ControlMesh edited;
    edited.colors.swap(colors);
    blend_colors(edited, s.colors, {40, 160, 220}, amount);
    renderer.set_colors(0, edited.colors);
    renderer.render(o, frame);
    colors.swap(edited.colors);
    benchmark::DoNotOptimize(frame.pixels.data());
  }
}
BENCHMARK(BM_EditColorRender512)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace subvec
