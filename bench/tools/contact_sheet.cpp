// subvec_contact_sheet: one evaluation picture per vectorized photograph, for docs/quality.md.
//
//   subvec_contact_sheet PHOTO IN.svec -o SHEET.png [--tile 256]
//
// Four tiles side by side, each `tile` pixels square: the original | the vector image at 1x | a x4
// zoom of the vector image around its busiest spot | the control mesh and features over the vector
// image. The zoom window is the (tile/4)-pixel square of the photo with the most gradient energy,
// found on a coarse grid, so the crop shows edges rather than sky. Deterministic.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>

#include <opencv2/imgproc.hpp>

#include "subvec/core/error.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/render/renderer.h"

namespace subvec {
namespace {

cv::Mat as_mat(const Image8& image) {
  cv::Mat m(image.height, image.width, image.channels == 4 ? CV_8UC4 : CV_8UC3,
            const_cast<uint8_t*>(image.pixels.data()));
  cv::Mat rgb;
  if (image.channels == 4) {
    cv::cvtColor(m, rgb, cv::COLOR_RGBA2RGB);
  } else {
    rgb = m.clone();
  }
  return rgb;
}

// Fits `m` into a tile x tile square (aspect kept, centred on white).
cv::Mat to_tile(const cv::Mat& m, int tile, int interpolation) {
  const double s = double(tile) / std::max(m.cols, m.rows);
  cv::Mat scaled;
  cv::resize(m, scaled, cv::Size(std::max(1, int(m.cols * s + 0.5)), std::max(1, int(m.rows * s + 0.5))), 0, 0,
             interpolation);
  cv::Mat out(tile, tile, CV_8UC3, cv::Scalar(255, 255, 255));
  scaled.copyTo(out(cv::Rect((tile - scaled.cols) / 2, (tile - scaled.rows) / 2, scaled.cols, scaled.rows)));
  return out;
}

// Top-left corner of the side x side window with the largest sum of gradient magnitudes.
cv::Point busiest_window(const cv::Mat& rgb, int side) {
  cv::Mat gray, gx, gy, mag;
  cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
  cv::Sobel(gray, gx, CV_32F, 1, 0);
  cv::Sobel(gray, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, mag);
  cv::Mat sum;
  cv::integral(mag, sum, CV_64F);
  cv::Point best(0, 0);
  double best_energy = -1;
  const int step = std::max(1, side / 4);
  for (int y = 0; y + side <= rgb.rows; y += step) {
    for (int x = 0; x + side <= rgb.cols; x += step) {
      const double e = sum.at<double>(y + side, x + side) - sum.at<double>(y, x + side) -
                       sum.at<double>(y + side, x) + sum.at<double>(y, x);
      if (e > best_energy) best_energy = e, best = {x, y};
    }
  }
  return best;
}

void label(cv::Mat& tile, const std::string& text) {
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double scale = 0.45;
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, font, scale, 1, &baseline);
  cv::rectangle(tile, cv::Rect(0, 0, size.width + 8, size.height + baseline + 6), cv::Scalar(255, 255, 255),
                cv::FILLED);
  cv::putText(tile, text, cv::Point(4, size.height + 3), font, scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
}

int run(int argc, char** argv) {
  std::string photo_path, svec_path, out_path;
  int tile = 256;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-o" && i + 1 < argc) {
      out_path = argv[++i];
    } else if (a == "--tile" && i + 1 < argc) {
      tile = std::stoi(argv[++i]);
    } else if (photo_path.empty()) {
      photo_path = a;
    } else if (svec_path.empty()) {
      svec_path = a;
    } else {
      throw Error(ErrorCode::kInvalidArgument, "unexpected argument '" + a + "'");
    }
  }
  if (photo_path.empty() || svec_path.empty() || out_path.empty() || tile < 64 || tile > 4096) {
    throw Error(ErrorCode::kInvalidArgument,
                "usage: subvec_contact_sheet PHOTO IN.svec -o SHEET.png [--tile 64..4096]");
  }
  const Image8 photo = read_image(photo_path);
  Renderer renderer(read_svec(svec_path));
  const VectorImage& image = renderer.image();
  if (image.width != photo.width || image.height != photo.height) {
    throw Error(ErrorCode::kInvalidArgument, "the photo and the vector image differ in size");
  }
  const cv::Mat original = as_mat(photo);

  RenderOptions one;
  const cv::Mat vector = as_mat(renderer.render(one));

  const int side = std::max(8, std::min({tile / 4, image.width, image.height}));
  const cv::Point at = busiest_window(original, side);
  RenderOptions zoom;
  zoom.window = Window{double(at.x), double(at.y), double(at.x + side), double(at.y + side)};
  zoom.width = tile;
  zoom.height = tile;
  const cv::Mat zoomed = as_mat(renderer.render(zoom));

  RenderOptions mesh;
  mesh.overlay = Overlay::kMesh;
  mesh.width = std::min(image.width, 2 * tile);
  const cv::Mat overlay = as_mat(renderer.render(mesh));

  cv::Mat tiles[4] = {to_tile(original, tile, cv::INTER_AREA), to_tile(vector, tile, cv::INTER_AREA), zoomed,
                      to_tile(overlay, tile, cv::INTER_AREA)};
  label(tiles[0], "original");
  label(tiles[1], "vector 1x");
  label(tiles[2], "vector x" + std::to_string(tile / side) + " (" + std::to_string(at.x) + "," +
                      std::to_string(at.y) + ")");
  label(tiles[3], "control mesh");
  cv::Mat sheet;
  cv::hconcat(tiles, 4, sheet);
  Image8 out(sheet.cols, sheet.rows, 3);
  for (int y = 0; y < sheet.rows; ++y) std::copy_n(sheet.ptr<uint8_t>(y), size_t(sheet.cols) * 3, out.row(y));
  write_png(out_path, out);
  return 0;
}

}  // namespace
}  // namespace subvec

int main(int argc, char** argv) {
  try {
    return subvec::run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "subvec_contact_sheet: %s\n", e.what());
    return 1;
  }
}
