// GrabCut segmentation as a source of features (vectorize/segment.h).
//
// Design note. The boundary is taken from the cleaned binary mask, not from the image: it is the
// crack between inside and outside pixels, which marching squares at level 1/2 over the pixel
// centres gives exactly (crossings at pixel-edge midpoints, corner cells cut diagonally). A ring
// of outside nodes around the image closes every contour; crossings on that ring lie exactly on
// the image border and mark where the region touches it. The inside is 4-connected and the outside
// 8-connected (a saddle cell separates its two inside corners), so the one region gives one simple
// loop. Opening and closing the mask first keeps the loop's sides at least 3 px apart, so that the
// smoothing afterwards (each point moves well under a pixel) cannot make it cross itself.
#include "subvec/vectorize/segment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/geometry_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

std::string rect_text(const PixelRect& r) {
  return std::to_string(r.x) + "," + std::to_string(r.y) + "," + std::to_string(r.width) + "," +
         std::to_string(r.height);
}

// Restores the calling thread's cv::theRNG() on every way out.
class SeededRng {
 public:
  explicit SeededRng(uint64_t seed) : saved_(cv::theRNG()) { cv::theRNG() = cv::RNG(seed); }
  ~SeededRng() { cv::theRNG() = saved_; }
  SeededRng(const SeededRng&) = delete;
  SeededRng& operator=(const SeededRng&) = delete;

 private:
  cv::RNG saved_;
};

double polyline_length(const std::vector<Vec2>& p) {
  double len = 0;
  for (size_t i = 1; i < p.size(); ++i) len += std::hypot(p[i].x - p[i - 1].x, p[i].y - p[i - 1].y);
  return len;
}

// One pass of [1 2 1]/4; open polylines keep their ends, closed ones (front() == back()) wrap.
void smooth(std::vector<Vec2>& p, bool closed) {
  const size_t n = p.size();
  if (n < 3) return;
  std::vector<Vec2> q = p;
  const size_t first = closed ? 0 : 1, last = n - 1;  // last: the closing copy, or the fixed end
  for (size_t i = first; i < last; ++i) {
    const Vec2 a = p[i == 0 ? n - 2 : i - 1], b = p[i], c = p[i + 1];
    q[i] = {0.25 * a.x + 0.5 * b.x + 0.25 * c.x, 0.25 * a.y + 0.5 * b.y + 0.25 * c.y};
  }
  if (closed) q[n - 1] = q[0];
  p = std::move(q);
}

// Evenly spaced points along the polyline, about `spacing` apart; the ends stay where they are.
std::vector<Vec2> resample(const std::vector<Vec2>& p, double spacing) {
  const double length = polyline_length(p);
  const int segments = std::max(1, static_cast<int>(std::lround(length / spacing)));
  std::vector<Vec2> out{p.front()};
  const double step = length / segments;
  size_t i = 0;   // current segment p[i] .. p[i + 1]
  double at = 0;  // arc length at p[i]
  for (int k = 1; k < segments; ++k) {
    const double s = k * step;
    while (i + 2 < p.size()) {
      const double seg = std::hypot(p[i + 1].x - p[i].x, p[i + 1].y - p[i].y);
      if (at + seg >= s) break;
      at += seg;
      ++i;
    }
    const double seg = std::hypot(p[i + 1].x - p[i].x, p[i + 1].y - p[i].y);
    const double t = seg > 0 ? std::clamp((s - at) / seg, 0.0, 1.0) : 0.0;
    out.push_back({p[i].x + t * (p[i + 1].x - p[i].x), p[i].y + t * (p[i + 1].y - p[i].y)});
  }
  out.push_back(p.back());
  return out;
}

double orient(Vec2 a, Vec2 b, Vec2 c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

double segment_distance(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a),
               o4 = orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
    return 0;
  return std::min({detail::segment_distance(a, c, d), detail::segment_distance(b, c, d),
                   detail::segment_distance(c, a, b), detail::segment_distance(d, a, b)});
}

// The boundary's segments, bucketed on a coarse grid for distance queries.
class SegmentGrid {
 public:
  SegmentGrid(const std::vector<DetectedFeature>& lines, double cell) : cell_(cell) {
    for (const DetectedFeature& f : lines)
      for (size_t i = 0; i + 1 < f.points.size(); ++i)
        segments_.push_back({f.points[i], f.points[i + 1]});
    if (segments_.empty()) return;
    x0_ = y0_ = 1e300;
    double x1 = -1e300, y1 = -1e300;
    for (const auto& s : segments_) {
      for (const Vec2& p : s)
        x0_ = std::min(x0_, p.x), y0_ = std::min(y0_, p.y), x1 = std::max(x1, p.x),
        y1 = std::max(y1, p.y);
    }
    nx_ = static_cast<int>((x1 - x0_) / cell_) + 1;
    ny_ = static_cast<int>((y1 - y0_) / cell_) + 1;
    cells_.resize(size_t(nx_) * ny_);
    for (size_t k = 0; k < segments_.size(); ++k) {
      const auto& s = segments_[k];
      const int cx0 = cx(std::min(s[0].x, s[1].x)), cx1 = cx(std::max(s[0].x, s[1].x));
      const int cy0 = cy(std::min(s[0].y, s[1].y)), cy1 = cy(std::max(s[0].y, s[1].y));
      for (int j = cy0; j <= cy1; ++j)
        for (int i = cx0; i <= cx1; ++i) cells_[size_t(j) * nx_ + i].push_back(static_cast<int>(k));
    }
  }

  // Whether segment a-b comes closer than `r` to any boundary segment.
  bool near(Vec2 a, Vec2 b, double r) const {
    if (segments_.empty()) return false;
    const int cx0 = cx(std::min(a.x, b.x) - r), cx1 = cx(std::max(a.x, b.x) + r);
    const int cy0 = cy(std::min(a.y, b.y) - r), cy1 = cy(std::max(a.y, b.y) + r);
    for (int j = cy0; j <= cy1; ++j)
      for (int i = cx0; i <= cx1; ++i)
        for (int k : cells_[size_t(j) * nx_ + i])
          if (segment_distance(a, b, segments_[k][0], segments_[k][1]) < r) return true;
    return false;
  }

 private:
  int cx(double x) const {
    return std::clamp(static_cast<int>(std::floor((x - x0_) / cell_)), 0, nx_ - 1);
  }
  int cy(double y) const {
    return std::clamp(static_cast<int>(std::floor((y - y0_) / cell_)), 0, ny_ - 1);
  }

  double cell_;
  double x0_ = 0, y0_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<std::array<Vec2, 2>> segments_;
  std::vector<std::vector<int>> cells_;
};

}  // namespace

int64_t RegionMask::area() const {
  return std::count_if(inside.begin(), inside.end(), [](uint8_t v) { return v != 0; });
}

RegionMask segment_foreground(const Image8& image, const PixelRect& rect,
                              const SegmentOptions& options) {
  const int w = image.width, h = image.height;
  if (rect.width <= 0 || rect.height <= 0) {
    throw Error(ErrorCode::kInvalidArgument, "segment rectangle " + rect_text(rect) + " is empty");
  }
  if (rect.x < 0 || rect.y < 0 || rect.x > w - rect.width || rect.y > h - rect.height) {
    throw Error(ErrorCode::kInvalidArgument, "segment rectangle " + rect_text(rect) +
                                                 " is not inside the " + std::to_string(w) + "x" +
                                                 std::to_string(h) + " image");
  }
  // GrabCut fits two 5-component colour models, one to the pixels inside and one to those outside.
  const int64_t inside = int64_t(rect.width) * rect.height, outside = int64_t(w) * h - inside;
  if (outside < 5) {
    throw Error(ErrorCode::kInvalidArgument,
                "segment rectangle " + rect_text(rect) + " leaves fewer than 5 pixels of the " +
                    std::to_string(w) + "x" + std::to_string(h) +
                    " image outside it: GrabCut needs background pixels there");
  }
  if (inside < 5) {
    throw Error(ErrorCode::kInvalidArgument,
                "segment rectangle " + rect_text(rect) +
                    " is too small: GrabCut needs at least 5 pixels inside it");
  }
  if (!(options.iterations >= 1 && options.iterations <= 100)) {
    throw Error(ErrorCode::kInvalidArgument, "GrabCut iterations must be in 1..100");
  }

  cv::Mat3b bgr(h, w);
  for (int y = 0; y < h; ++y) {
    const uint8_t* src = image.row(y);
    for (int x = 0; x < w; ++x, src += image.channels)
      bgr(y, x) = cv::Vec3b(src[2], src[1], src[0]);
  }
  cv::Mat1b gc(h, w, static_cast<uint8_t>(cv::GC_BGD));
  cv::Mat background_model, foreground_model;
  try {
    const SeededRng rng(options.seed);
    cv::grabCut(bgr, gc, cv::Rect(rect.x, rect.y, rect.width, rect.height), background_model,
                foreground_model, options.iterations, cv::GC_INIT_WITH_RECT);
  } catch (const cv::Exception& e) {
    throw Error(ErrorCode::kInvalidArgument,
                "GrabCut failed for segment rectangle " + rect_text(rect) + ": " + e.err);
  }

  // Foreground: GC_FGD (1) and GC_PR_FGD (3).
  cv::Mat1b fg(h, w);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) fg(y, x) = (gc(y, x) & 1) ? 255 : 0;
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::morphologyEx(fg, fg, cv::MORPH_OPEN, square);
  cv::morphologyEx(fg, fg, cv::MORPH_CLOSE, square);

  cv::Mat1i labels;
  cv::Mat stats, centroids;
  const int count = cv::connectedComponentsWithStats(fg, labels, stats, centroids, 4, CV_32S);
  int best = 0;
  for (int k = 1; k < count; ++k)
    if (best == 0 || stats.at<int>(k, cv::CC_STAT_AREA) > stats.at<int>(best, cv::CC_STAT_AREA))
      best = k;
  if (best == 0) {
    throw Error(ErrorCode::kInvalidArgument,
                "GrabCut found no foreground in segment rectangle " + rect_text(rect));
  }

  // Holes: outside pixels not 8-connected to the image border.
  cv::Mat1b outside_mask(h, w);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) outside_mask(y, x) = labels(y, x) == best ? 0 : 255;
  cv::Mat1i holes;
  const int outside_count = cv::connectedComponents(outside_mask, holes, 8, CV_32S);
  std::vector<uint8_t> touches_border(outside_count, 0);
  for (int x = 0; x < w; ++x) touches_border[holes(0, x)] = touches_border[holes(h - 1, x)] = 1;
  for (int y = 0; y < h; ++y) touches_border[holes(y, 0)] = touches_border[holes(y, w - 1)] = 1;

  RegionMask mask;
  mask.width = w;
  mask.height = h;
  mask.inside.resize(size_t(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool in = labels(y, x) == best || !touches_border[holes(y, x)];
      mask.inside[size_t(y) * w + x] = in ? 1 : 0;
    }
  }
  return mask;
}

std::vector<DetectedFeature> region_boundary_features(const RegionMask& mask,
                                                      const SegmentOptions& options) {
  const int w = mask.width, h = mask.height;
  if (w <= 0 || h <= 0 || mask.inside.size() != size_t(w) * h) {
    throw Error(ErrorCode::kInvalidArgument, "region mask is empty or malformed");
  }
  // Nodes (i, j) for i in -1..w, j in -1..h at pixel centres (i + 1/2, j + 1/2); those outside the
  // image are outside the region. Crossings live on grid edges between an inside and an outside
  // node: horizontal edge (i, j)-(i+1, j), vertical edge (i, j)-(i, j+1), ids below.
  const int nw = w + 2, nh = h + 2;  // nodes, shifted by one
  const int num_horizontal = (nw - 1) * nh;
  auto in = [&](int i, int j) { return i >= 0 && j >= 0 && i < w && j < h && mask.at(i, j); };
  auto horizontal = [&](int i, int j) { return (j + 1) * (nw - 1) + (i + 1); };
  auto vertical = [&](int i, int j) { return num_horizontal + (j + 1) * nw + (i + 1); };
  const int num_edges = num_horizontal + nw * (nh - 1);
  auto position = [&](int id) -> Vec2 {
    if (id < num_horizontal) {
      const int i = id % (nw - 1) - 1, j = id / (nw - 1) - 1;
      return {i + 1.0, j + 0.5};
    }
    const int k = id - num_horizontal, i = k % nw - 1, j = k / nw - 1;
    return {i + 0.5, j + 1.0};
  };
  auto on_border = [&](Vec2 p) { return p.x == 0 || p.y == 0 || p.x == w || p.y == h; };

  // Directed segments with the region on their left (y down): next[crossing] = following crossing.
  std::vector<int> next(num_edges, -1);
  for (int j = -1; j < h; ++j) {
    for (int i = -1; i < w; ++i) {
      // Corners a (i, j), b (i+1, j), c (i+1, j+1), d (i, j+1); edges top, right, bottom, left.
      const bool a = in(i, j), b = in(i + 1, j), c = in(i + 1, j + 1), d = in(i, j + 1);
      const int top = horizontal(i, j), right = vertical(i + 1, j), bottom = horizontal(i, j + 1),
                left = vertical(i, j);
      const Vec2 corner[4] = {
          {i + 0.5, j + 0.5}, {i + 1.5, j + 0.5}, {i + 1.5, j + 1.5}, {i + 0.5, j + 1.5}};
      const bool inside[4] = {a, b, c, d};
      // The two edges beside each corner, and the edge pair across the cell for two adjacent
      // corners.
      const int beside[4][2] = {{left, top}, {top, right}, {right, bottom}, {bottom, left}};
      auto link = [&](int e0, int e1, int reference) {
        // Orient e0 -> e1 so the region lies to the left: the reference corner is inside or not.
        const Vec2 p = position(e0), q = position(e1);
        const double side = orient(p, q, corner[reference]);
        const bool left_of = side < 0;  // y down: a negative orientation is on the left as drawn
        if (left_of == inside[reference])
          next[e0] = e1;
        else
          next[e1] = e0;
      };
      const int count = a + b + c + d;
      if (count == 0 || count == 4) continue;
      if (count == 1 || count == 3) {
        for (int k = 0; k < 4; ++k)
          if (inside[k] == (count == 1)) link(beside[k][0], beside[k][1], k);
      } else if (a == c) {  // saddle: each inside corner cut off on its own
        for (int k = 0; k < 4; ++k)
          if (inside[k]) link(beside[k][0], beside[k][1], k);
      } else if (a == b) {
        link(left, right, 0);
      } else {
        link(top, bottom, 0);
      }
    }
  }

  // Loops; the region is one 4-connected component without holes, so there is one. Keep the one
  // enclosing the largest area should a caller pass anything else.
  std::vector<uint8_t> seen(num_edges, 0);
  std::vector<Vec2> loop;
  std::vector<uint8_t> loop_border;
  double best_area = 0;
  for (int start = 0; start < num_edges; ++start) {
    if (next[start] < 0 || seen[start]) continue;
    std::vector<Vec2> points;
    double area = 0;
    for (int e = start; !seen[e]; e = next[e]) {
      seen[e] = 1;
      points.push_back(position(e));
      if (next[e] < 0) break;  // cannot happen for a closed mask; stop rather than loop
    }
    for (size_t k = 0; k < points.size(); ++k) {
      const Vec2 p = points[k], q = points[(k + 1) % points.size()];
      area += p.x * q.y - q.x * p.y;
    }
    if (std::abs(area) > best_area) {
      best_area = std::abs(area);
      loop = std::move(points);
    }
  }
  if (loop.size() < 4) return {};
  loop_border.resize(loop.size());
  for (size_t k = 0; k < loop.size(); ++k) loop_border[k] = on_border(loop[k]);

  std::vector<std::vector<Vec2>> pieces;
  std::vector<uint8_t> closed;
  const auto first_border = std::find(loop_border.begin(), loop_border.end(), 1);
  if (first_border == loop_border.end()) {
    pieces.push_back(loop);
    pieces.back().push_back(loop.front());
    closed.push_back(1);
  } else {
    // Start at a border crossing; every run of inside crossings between two border crossings is
    // one open piece, including the border crossings that end it.
    const size_t n = loop.size(), s = static_cast<size_t>(first_border - loop_border.begin());
    std::vector<Vec2> run{loop[s]};
    for (size_t k = 1; k <= n; ++k) {
      const size_t at = (s + k) % n;
      run.push_back(loop[at]);
      if (loop_border[at]) {
        if (run.size() > 2) {
          pieces.push_back(std::move(run));
          closed.push_back(0);
        }
        run = {loop[at]};
      }
    }
  }

  std::vector<DetectedFeature> out;
  for (size_t k = 0; k < pieces.size(); ++k) {
    std::vector<Vec2>& p = pieces[k];
    for (int pass = 0; pass < options.smoothing_passes; ++pass) smooth(p, closed[k] != 0);
    DetectedFeature f;
    f.points = resample(p, 1.0);
    if (closed[k] && f.points.size() < 5) continue;  // fewer than 4 distinct points
    f.length = polyline_length(f.points);
    if (f.length < 3.0) continue;
    out.push_back(std::move(f));
  }
  return out;
}

void clear_features_near(std::vector<DetectedFeature>& features,
                         const std::vector<DetectedFeature>& boundary, double clearance,
                         double min_length) {
  if (boundary.empty() || !(clearance > 0)) return;
  const SegmentGrid grid(boundary, 4.0);
  std::vector<DetectedFeature> out;
  for (DetectedFeature& f : features) {
    const size_t n = f.points.size();
    if (n < 2) continue;
    // keep[i]: no segment at point i comes within the clearance.
    std::vector<uint8_t> keep(n, 1);
    bool any_cut = false;
    for (size_t i = 0; i + 1 < n; ++i) {
      if (grid.near(f.points[i], f.points[i + 1], clearance))
        keep[i] = keep[i + 1] = 0, any_cut = true;
    }
    if (!any_cut) {
      out.push_back(std::move(f));
      continue;
    }
    const bool closed = f.closed();
    if (closed) keep[0] = keep[n - 1] = keep[0] && keep[n - 1];
    // Runs of kept points; on a closed feature start right after a cut so no run wraps around.
    size_t start = 0;
    if (closed) {
      while (keep[start]) ++start;  // some point is cut: any_cut
    }
    const size_t m = closed ? n - 1 : n;  // distinct points
    std::vector<Vec2> run;
    size_t run_first = 0;
    auto flush = [&](size_t last) {
      if (run.size() >= 2) {
        DetectedFeature piece;
        piece.points = std::move(run);
        piece.length = polyline_length(piece.points);
        piece.contrast = f.contrast;
        piece.start_node = !closed && run_first == 0 ? f.start_node : -1;
        piece.end_node = !closed && last == n - 1 ? f.end_node : -1;
        if (piece.length >= min_length) out.push_back(std::move(piece));
      }
      run.clear();
    };
    size_t last = 0;
    for (size_t k = 0; k < m; ++k) {
      const size_t i = (start + k) % m;
      if (keep[i]) {
        if (run.empty()) run_first = i;
        run.push_back(f.points[i]);
        last = i;
      } else {
        flush(last);
      }
    }
    flush(last);
  }
  features = std::move(out);
}

}  // namespace subvec
