// subvec_svec_precision: the measurements behind the compact `.svec` defaults (docs/format.md).
// For each pair PHOTO VECTOR (a photograph and its vectorization, any .svec form) it writes the
// compact form at several position and color grids and prints, per grid, the bytes per control
// vertex and the change of the 1x render's MAE against the photograph, and the MAE between the
// renders before and after quantization; also the bytes of version 1 and of version 2 at the
// default grids. A last row gives the medians over the images.
//
//   subvec_svec_precision PHOTO VECTOR [PHOTO VECTOR ...]
#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/core/metrics.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/render/renderer.h"

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 3 || argc % 2 == 0) {
      throw subvec::Error(subvec::ErrorCode::kInvalidArgument,
                          "usage: subvec_svec_precision PHOTO VECTOR [PHOTO VECTOR ...]");
    }
    const std::vector<std::pair<int, int>> grids = {{1, -1}, {2, -1}, {3, -1}, {4, -1},
                                                    {2, 1},  {2, 0},  {2, -2}};
    std::vector<std::vector<double>> bpv(grids.size()), dmae(grids.size()), rmae(grids.size());
    std::vector<double> lossless_bpv, v2_bpv;
    std::printf("%-12s %5s %5s %10s %8s %10s %10s\n", "image", "pbits", "cbits", "bytes",
                "B/vertex", "dMAE", "MAE(render)");
    for (int i = 1; i + 1 < argc; i += 2) {
      const subvec::Image8 photo = subvec::read_image(argv[i]);
      const subvec::VectorImage image = subvec::read_svec(argv[i + 1]);
      int vertices = 0;
      for (const auto& level : image.levels) vertices += level.num_vertices();
      subvec::RenderOptions ro;
      ro.width = photo.width;
      ro.height = photo.height;
      const subvec::Image8 reference = subvec::render(image, ro);
      const double base = subvec::compare(photo, reference).mae_mean;
      std::string name = argv[i];
      name = name.substr(name.find_last_of('/') + 1);
      name = name.substr(0, name.find('.'));
      const size_t lossless =
          subvec::to_svec_binary(image, subvec::SvecWriteOptions{.lossless = true}).size();
      lossless_bpv.push_back(double(lossless) / vertices);
      std::printf("%-12s %5s %5s %10zu %8.3f %10s %10s\n", name.c_str(), "v1", "-", lossless,
                  double(lossless) / vertices, "0", "0");
      // Version 2 at the default grids: the same content as version 3 in varints and zstd.
      const size_t v2 =
          subvec::to_svec_binary(image, subvec::SvecWriteOptions{.compact_version = 2}).size();
      v2_bpv.push_back(double(v2) / vertices);
      std::printf("%-12s %5s %5s %10zu %8.3f %10s %10s\n", name.c_str(), "v2", "2/-1", v2,
                  double(v2) / vertices, "", "");
      for (size_t g = 0; g < grids.size(); ++g) {
        subvec::SvecWriteOptions options;
        options.position_bits = grids[g].first;
        options.color_bits = grids[g].second;
        const std::vector<uint8_t> bytes = subvec::to_svec_binary(image, options);
        const subvec::Image8 out = subvec::render(subvec::parse_svec_binary(bytes), ro);
        const double d = subvec::compare(photo, out).mae_mean - base;
        const double r = subvec::compare(reference, out).mae_mean;
        bpv[g].push_back(double(bytes.size()) / vertices);
        dmae[g].push_back(d);
        rmae[g].push_back(r);
        std::printf("%-12s %5d %5d %10zu %8.3f %+10.4f %10.4f\n", name.c_str(), grids[g].first,
                    grids[g].second, bytes.size(), double(bytes.size()) / vertices, d, r);
      }
      std::fflush(stdout);
    }
    std::printf("%-12s %5s %5s %10s %8.3f %10s %10s\n", "median", "v1", "-", "",
                median(lossless_bpv), "0", "0");
    std::printf("%-12s %5s %5s %10s %8.3f %10s %10s\n", "median", "v2", "2/-1", "",
                median(v2_bpv), "", "");
    for (size_t g = 0; g < grids.size(); ++g) {
      std::printf("%-12s %5d %5d %10s %8.3f %+10.4f %10.4f\n", "median", grids[g].first,
                  grids[g].second, "", median(bpv[g]), median(dmae[g]), median(rmae[g]));
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "subvec_svec_precision: %s\n", e.what());
    return 1;
  }
}
