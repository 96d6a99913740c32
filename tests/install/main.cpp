// The downstream program of tests/install: uses every layer of an installed subvec the way a user
// would, through find_package(subvec) and subvec::subvec. Reads a .svec.json, renders it at 2x,
// writes the PNG, vectorizes the render, round-trips the result through the binary format and
// exports it as PDF. Exit status 0 and one line of facts on success; a line on stderr otherwise.
#include <cstdio>
#include <exception>
#include <string>

#include "subvec/export/export.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/render/renderer.h"
#include "subvec/vectorize/vectorize.h"

namespace {

int fail(const std::string& what) {
  std::fprintf(stderr, "downstream: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) return fail("usage: downstream IN.svec.json OUT.png");
  try {
    const subvec::VectorImage image = subvec::read_svec(argv[1]);
    subvec::RenderOptions options;
    options.scale = 2;
    options.threads = 1;
    const subvec::Image8 frame = subvec::render(image, options);
    if (frame.width != 2 * image.width || frame.height != 2 * image.height)
      return fail("render size " + std::to_string(frame.width) + "x" + std::to_string(frame.height));
    subvec::write_png(argv[2], frame);

    // RGB over white for the vectorizer.
    subvec::Image8 rgb(frame.width, frame.height, 3);
    for (int y = 0; y < frame.height; ++y) {
      const uint8_t* in = frame.row(y);
      uint8_t* out = rgb.row(y);
      for (int x = 0; x < frame.width; ++x) {
        const int a = frame.channels == 4 ? in[4 * x + 3] : 255;
        for (int c = 0; c < 3; ++c) {
          const int v = in[frame.channels * x + c];
          out[3 * x + c] = static_cast<uint8_t>((v * a + 255 * (255 - a) + 127) / 255);
        }
      }
    }
    subvec::VectorizeOptions vectorize_options;
    vectorize_options.vertices = 300;
    vectorize_options.threads = 1;
    const subvec::VectorImage vector = subvec::vectorize(rgb, vectorize_options);
    const subvec::VectorImage back = subvec::parse_svec_binary(subvec::to_svec_binary(vector));
    if (back.width != rgb.width || back.levels.empty() || back.levels[0].positions.empty())
      return fail("the vectorized image did not round-trip");
    const std::string pdf = subvec::to_pdf(back);
    if (pdf.rfind("%PDF", 0) != 0) return fail("the PDF export does not start with %PDF");
    std::printf("downstream: rendered %dx%d, vectorized to %zu control vertices, %zu bytes of PDF\n",
                frame.width, frame.height, back.levels[0].positions.size(), pdf.size());
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  return 0;
}
