// The GPU path in a build without SUBVEC_GPU (no OpenGL / EGL development files): no context can
// be created, so Backend::kGpu always falls back to the CPU.
#include "render/gpu/gpu_p.h"

namespace subvec::detail {

std::unique_ptr<GpuRasterizer> GpuRasterizer::create(std::string& error) {
  error = "this subvec was built without GPU support (SUBVEC_GPU=OFF)";
  return nullptr;
}

std::string gpu_probe(bool* no_display) {
  if (no_display) *no_display = true;
  return "this subvec was built without GPU support (SUBVEC_GPU=OFF)";
}

std::string gpu_probe_renderer() { return {}; }

void set_gpu_profiling(bool) {}
GpuPassTimes gpu_pass_times() { return {}; }

}  // namespace subvec::detail
