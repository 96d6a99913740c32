// subvec_upscale: a bicubic upscale of a photograph, or a centred crop of it, the inputs of the
// large-image vectorization benchmarks (scripts/bench-vectorize).
//
//   subvec_upscale IN OUT.png FACTOR          FACTOR 1..16 times the size, bicubic
//   subvec_upscale IN OUT.png crop W H        the W x H pixels at the centre
#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>

#include <opencv2/imgproc.hpp>

#include "subvec/core/error.h"
#include "subvec/io/image_io.h"

int main(int argc, char** argv) {
  try {
    const char* usage = "usage: subvec_upscale IN OUT.png FACTOR | subvec_upscale IN OUT.png crop W H";
    if (argc == 6 && std::string(argv[3]) == "crop") {
      const subvec::Image8 in = subvec::read_image(argv[1]);
      const int w = std::stoi(argv[4]), h = std::stoi(argv[5]);
      if (w < 2 || h < 2 || w > in.width || h > in.height)
        throw subvec::Error(subvec::ErrorCode::kInvalidArgument, "crop W H must be 2.. the image's size");
      const int x0 = (in.width - w) / 2, y0 = (in.height - h) / 2;
      subvec::Image8 out(w, h, in.channels);
      for (int y = 0; y < h; ++y)
        std::copy_n(in.row(y0 + y) + size_t(x0) * in.channels, size_t(w) * in.channels, out.row(y));
      subvec::write_png(argv[2], out);
      return 0;
    }
    if (argc != 4) throw subvec::Error(subvec::ErrorCode::kInvalidArgument, usage);
    const int factor = std::stoi(argv[3]);
    if (factor < 1 || factor > 16) throw subvec::Error(subvec::ErrorCode::kInvalidArgument, "FACTOR must be 1..16");
    const subvec::Image8 in = subvec::read_image(argv[1]);
    const cv::Mat src(in.height, in.width, in.channels == 4 ? CV_8UC4 : CV_8UC3,
                      const_cast<uint8_t*>(in.pixels.data()));
    cv::Mat dst;
    cv::resize(src, dst, cv::Size(in.width * factor, in.height * factor), 0, 0, cv::INTER_CUBIC);
    subvec::Image8 out(dst.cols, dst.rows, in.channels);
    for (int y = 0; y < dst.rows; ++y) std::copy_n(dst.ptr<uint8_t>(y), out.row(y + 1) - out.row(y), out.row(y));
    subvec::write_png(argv[2], out);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "subvec_upscale: %s\n", e.what());
    return 1;
  }
}
