// `subvec render --gpu`: the GPU frame matches the CPU's, and without any EGL driver the command
// says so in one line and renders on the CPU.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "render/gpu/gpu_p.h"
#include "subvec/io/image_io.h"
#include "subvec/render/renderer.h"
#include "support/paths.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int status = -1;
  std::string err;
};

class GpuCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("subvec_gpu_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `[env] subvec <args>` (arguments without quotes needed) and keeps stderr.
  CliRun run_subvec(const std::string& env, const std::string& args) {
    const fs::path err = dir_ / ".stderr";
    const std::string command = env + " '" + test::cli_path() + "' " + args + " 2>'" +
                                err.string() + "'";
    const int raw = std::system(command.c_str());
    CliRun r;
    r.status = (raw != -1 && WIFEXITED(raw)) ? WEXITSTATUS(raw) : -1;
    std::ifstream in(err);
    r.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return r;
  }

  std::string example() const {
    return (test::source_dir() / "examples" / "03-junction.svec.json").string();
  }

  fs::path dir_;
};

TEST_F(GpuCli, RenderGpuMatchesTheCpu) {
  bool no_display = false;
  const std::string why = detail::gpu_probe(&no_display);
  if (!why.empty() && no_display) GTEST_SKIP() << "no EGL display: " << why;
  const fs::path cpu = dir_ / "cpu.png", gpu = dir_ / "gpu.png";
  ASSERT_EQ(run_subvec("", "render " + example() + " -o " + cpu.string() + " --scale 3").status, 0);
  const CliRun r = run_subvec("", "render " + example() + " -o " + gpu.string() + " --scale 3 --gpu");
  ASSERT_EQ(r.status, 0) << r.err;
  // No fallback message when a hardware context exists; on a software rasterizer (Mesa
  // llvmpipe), one line, and the CPU draws.
  const GpuRendererInfo gl = gpu_renderer();
  EXPECT_EQ(r.err, gl.software ? "subvec: --gpu: OpenGL is " + gl.name +
                                     " (software); rendering on the CPU, which is faster here\n"
                               : "");
  const Image8 a = read_image(cpu), b = read_image(gpu);
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  int64_t sum = 0;
  int worst = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const int d = std::abs(int(a.pixels[i]) - int(b.pixels[i]));
    sum += d;
    worst = std::max(worst, d);
  }
  EXPECT_LE(double(sum) / double(a.pixels.size()), 0.5);
  EXPECT_LE(worst, 8);
}

// GLVND with no vendor library: no EGL display at all. One line, exit 0, the CPU's exact frame.
TEST_F(GpuCli, WithoutAnEglDriverFallsBackToTheCpuWithOneLine) {
  const fs::path cpu = dir_ / "cpu.png", gpu = dir_ / "gpu.png";
  ASSERT_EQ(run_subvec("", "render " + example() + " -o " + cpu.string()).status, 0);
  const CliRun r = run_subvec("__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent/vendor.json",
                       "render " + example() + " -o " + gpu.string() + " --gpu");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err.rfind("subvec: GPU rendering unavailable (", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("rendering on the CPU"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(read_image(cpu).pixels, read_image(gpu).pixels);
}

}  // namespace
}  // namespace subvec
