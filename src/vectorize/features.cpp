// Feature detection (paper §4, "Feature detection"): Canny -> thinning -> linking -> pruning,
// bridging -> subpixel location. Chains are traced on the pixel grid (8-connectivity) between
// nodes: free endpoints and junction clusters. Junctions split chains, so features meeting at a
// junction share its node and, later, one mesh vertex.
#include "subvec/vectorize/features.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "core/messages_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

constexpr std::array<int, 8> kDx = {1, 1, 0, -1, -1, -1, 0, 1};
constexpr std::array<int, 8> kDy = {0, 1, 1, 1, 0, -1, -1, -1};

struct Pixel {
  int x, y;
  friend bool operator==(const Pixel&, const Pixel&) = default;
};

struct Chain {
  std::vector<Pixel> pixels;
  int start = -1, end = -1;  // node ids; -1 = free end
  bool closed = false;
};

// One pass of Zhang-Suen thinning until stable: removes the redundant pixels of 8-connected
// staircases so that chain pixels have exactly two neighbours.
void thin(cv::Mat1b& m) {
  const int w = m.cols, h = m.rows;
  auto at = [&](int x, int y) -> int { return x >= 0 && y >= 0 && x < w && y < h && m(y, x) ? 1 : 0; };
  std::vector<Pixel> remove;
  for (bool changed = true; changed;) {
    changed = false;
    for (int pass = 0; pass < 2; ++pass) {
      remove.clear();
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          if (!m(y, x)) continue;
          // Neighbours P2..P9 clockwise from north.
          const int p[8] = {at(x, y - 1), at(x + 1, y - 1), at(x + 1, y), at(x + 1, y + 1),
                            at(x, y + 1), at(x - 1, y + 1), at(x - 1, y), at(x - 1, y - 1)};
          const int b = std::accumulate(p, p + 8, 0);
          if (b < 2 || b > 6) continue;
          int a = 0;
          for (int i = 0; i < 8; ++i) a += (p[i] == 0 && p[(i + 1) % 8] == 1);
          if (a != 1) continue;
          if (pass == 0 ? (p[0] * p[2] * p[4] == 0 && p[2] * p[4] * p[6] == 0)
                        : (p[0] * p[2] * p[6] == 0 && p[0] * p[4] * p[6] == 0)) {
            remove.push_back({x, y});
          }
        }
      }
      for (const Pixel& q : remove) m(q.y, q.x) = 0;
      changed = changed || !remove.empty();
    }
  }
  // Zhang-Suen works with 4-connected crossings and keeps the redundant pixels of diagonal
  // staircases, whose neighbours then have three neighbours and read as junctions. Remove every
  // pixel that is 8-simple (Yokoi's 8-connectivity number is 1: its neighbours stay connected
  // without it) and is not an endpoint, in raster order until nothing changes.
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (!m(y, x)) continue;
        // Counter-clockwise from east: E, NE, N, NW, W, SW, S, SE; complements.
        const int n[8] = {at(x + 1, y), at(x + 1, y - 1), at(x, y - 1), at(x - 1, y - 1),
                          at(x - 1, y), at(x - 1, y + 1), at(x, y + 1), at(x + 1, y + 1)};
        int count = 0, connectivity = 0;
        for (int k = 0; k < 8; ++k) count += n[k];
        for (int k = 0; k < 8; k += 2) {
          const int a = 1 - n[k], b = 1 - n[(k + 1) % 8], c = 1 - n[(k + 2) % 8];
          connectivity += a - a * b * c;
        }
        if (count >= 2 && connectivity == 1) {
          m(y, x) = 0;
          changed = true;
        }
      }
    }
  }
}

double bilinear(const cv::Mat1f& m, double x, double y) {
  // (x, y) in pixel-centre coordinates of the matrix (centre of (i, j) at (i, j)).
  x = std::clamp(x, 0.0, double(m.cols - 1));
  y = std::clamp(y, 0.0, double(m.rows - 1));
  const int x0 = std::min(int(x), m.cols - 2 < 0 ? 0 : m.cols - 2), y0 = std::min(int(y), m.rows - 2 < 0 ? 0 : m.rows - 2);
  const int x1 = std::min(x0 + 1, m.cols - 1), y1 = std::min(y0 + 1, m.rows - 1);
  const double fx = x - x0, fy = y - y0;
  return (1 - fy) * ((1 - fx) * m(y0, x0) + fx * m(y0, x1)) + fy * ((1 - fx) * m(y1, x0) + fx * m(y1, x1));
}

double polyline_length(const std::vector<Vec2>& p) {
  double len = 0;
  for (size_t i = 1; i < p.size(); ++i) len += std::hypot(p[i].x - p[i - 1].x, p[i].y - p[i - 1].y);
  return len;
}

class Linker {
 public:
  Linker(const cv::Mat1b& edges) : edges_(edges), w_(edges.cols), h_(edges.rows), node_(h_ * w_, -1), used_(h_ * w_, 0) {}

  std::vector<Chain> trace() {
    // Nodes: connected clusters of junction pixels (3+ neighbours), and endpoints (1 neighbour).
    for (int y = 0; y < h_; ++y) {
      for (int x = 0; x < w_; ++x) {
        if (!on(x, y) || node_[y * w_ + x] >= 0) continue;
        const int n = degree(x, y);
        if (n >= 3) {
          flood_junction(x, y, num_nodes_++);
        } else if (n <= 1) {
          node_[y * w_ + x] = num_nodes_;
          record_node(num_nodes_++, {{x, y}});
        }
      }
    }
    // Chains from every node pixel through each non-node neighbour.
    for (int y = 0; y < h_; ++y) {
      for (int x = 0; x < w_; ++x) {
        if (node_[y * w_ + x] < 0) continue;
        for (int k = 0; k < 8; ++k) {
          const int nx = x + kDx[k], ny = y + kDy[k];
          if (!on(nx, ny)) continue;
          const int nn = node_[ny * w_ + nx];
          if (nn == node_[y * w_ + x]) continue;            // inside the same junction cluster
          if (nn < 0 && used_[ny * w_ + nx]) continue;      // chain already traced
          if (nn >= 0 && (node_[y * w_ + x] > nn || (node_[y * w_ + x] == nn))) continue;  // node-node link once
          walk({x, y}, {nx, ny});
        }
      }
    }
    // What is left are closed loops of degree-2 pixels.
    for (int y = 0; y < h_; ++y) {
      for (int x = 0; x < w_; ++x) {
        if (!on(x, y) || node_[y * w_ + x] >= 0 || used_[y * w_ + x]) continue;
        Chain c;
        c.closed = true;
        Pixel p{x, y}, prev{-10, -10};
        while (true) {
          c.pixels.push_back(p);
          used_[p.y * w_ + p.x] = 1;
          Pixel next{-1, -1};
          for (int k = 0; k < 8; ++k) {
            const Pixel q{p.x + kDx[k], p.y + kDy[k]};
            if (on(q.x, q.y) && !(q == prev) && !used_[q.y * w_ + q.x]) {
              next = q;
              break;
            }
          }
          if (next.x < 0) break;
          prev = p;
          p = next;
        }
        if (c.pixels.size() >= 3) {
          c.pixels.push_back(c.pixels.front());
          chains_.push_back(std::move(c));
        }
      }
    }
    return std::move(chains_);
  }

  int num_nodes() const { return num_nodes_; }
  Pixel node_pixel(int node) const { return node_pixels_[node]; }

 private:
  bool on(int x, int y) const { return x >= 0 && y >= 0 && x < w_ && y < h_ && edges_(y, x); }
  int degree(int x, int y) const {
    int n = 0;
    for (int k = 0; k < 8; ++k) n += on(x + kDx[k], y + kDy[k]);
    return n;
  }
  void flood_junction(int x, int y, int id) {
    std::vector<Pixel> stack{{x, y}}, cluster;
    node_[y * w_ + x] = id;
    while (!stack.empty()) {
      Pixel p = stack.back();
      stack.pop_back();
      cluster.push_back(p);
      for (int k = 0; k < 8; ++k) {
        const int nx = p.x + kDx[k], ny = p.y + kDy[k];
        if (on(nx, ny) && node_[ny * w_ + nx] < 0 && degree(nx, ny) >= 3) {
          node_[ny * w_ + nx] = id;
          stack.push_back({nx, ny});
        }
      }
    }
    record_node(id, cluster);
  }
  void record_node(int id, const std::vector<Pixel>& cluster) {
    if (static_cast<int>(node_pixels_.size()) <= id) node_pixels_.resize(id + 1);
    // The representative pixel: the cluster pixel closest to its centroid (deterministic).
    double cx = 0, cy = 0;
    for (const Pixel& p : cluster) cx += p.x, cy += p.y;
    cx /= static_cast<double>(cluster.size()), cy /= static_cast<double>(cluster.size());
    Pixel best = cluster.front();
    double best_d = 1e30;
    for (const Pixel& p : cluster) {
      const double d = (p.x - cx) * (p.x - cx) + (p.y - cy) * (p.y - cy);
      if (d < best_d || (d == best_d && (p.y < best.y || (p.y == best.y && p.x < best.x)))) best = p, best_d = d;
    }
    node_pixels_[id] = best;
  }
  void walk(Pixel from, Pixel first) {
    Chain c;
    c.start = node_[from.y * w_ + from.x];
    c.pixels.push_back(from);
    Pixel prev = from, p = first;
    while (true) {
      const int n = node_[p.y * w_ + p.x];
      c.pixels.push_back(p);
      if (n >= 0) {
        c.end = n;
        break;
      }
      used_[p.y * w_ + p.x] = 1;
      Pixel next{-1, -1};
      // Prefer an unvisited non-node neighbour; else a node neighbour (the chain ends there).
      for (int pass = 0; pass < 2 && next.x < 0; ++pass) {
        for (int k = 0; k < 8; ++k) {
          const Pixel q{p.x + kDx[k], p.y + kDy[k]};
          if (!on(q.x, q.y) || q == prev) continue;
          const int qn = node_[q.y * w_ + q.x];
          if (pass == 0 && qn < 0 && !used_[q.y * w_ + q.x]) {
            next = q;
            break;
          }
          if (pass == 1 && qn >= 0 && !(q == from && c.pixels.size() <= 2)) {
            next = q;
            break;
          }
        }
      }
      if (next.x < 0) {  // dead end without an endpoint node (already traced from the other side)
        c.end = -1;
        break;
      }
      prev = p;
      p = next;
    }
    if (c.pixels.size() >= 2) chains_.push_back(std::move(c));
  }

  const cv::Mat1b& edges_;
  int w_, h_;
  std::vector<int> node_;
  std::vector<uint8_t> used_;
  int num_nodes_ = 0;
  std::vector<Pixel> node_pixels_;
  std::vector<Chain> chains_;
};

// A chain in image coordinates, between nodes (ids of junction clusters or endpoints).
struct Polyline {
  std::vector<Vec2> points;
  int start = -1, end = -1;  // -1 on both: a closed loop
  double contrast_sum = 0;
  bool dead = false;
  bool closed() const { return start < 0 && end < 0 && points.size() > 2 && points.front() == points.back(); }
  double length() const { return polyline_length(points); }
};

// The chain graph: nodes joined by polylines. Degrees count polyline ends at a node.
class FeatureGraph {
 public:
  FeatureGraph(std::vector<Polyline> lines, int num_nodes) : lines_(std::move(lines)), degree_(num_nodes, 0) {
    recount();
  }
  std::vector<Polyline>& lines() { return lines_; }
  int degree(int node) const { return degree_[node]; }

  // Short branches hanging off a junction are noise (Canny's corner artefacts).
  void prune_spurs(double max_length) {
    for (Polyline& l : lines_) {
      if (l.dead) continue;
      const bool free_start = l.start >= 0 && degree_[l.start] == 1;
      const bool free_end = l.end >= 0 && degree_[l.end] == 1;
      const bool at_junction = (l.start >= 0 && degree_[l.start] >= 3) || (l.end >= 0 && degree_[l.end] >= 3);
      if ((free_start || free_end) && at_junction && l.length() < max_length) l.dead = true;
    }
    recount();
  }

  // A node where exactly two polylines end is no junction: join them into one.
  void merge_through_degree_two() {
    for (size_t i = 0; i < lines_.size(); ++i) {
      Polyline& a = lines_[i];
      for (bool progress = true; progress && !a.dead;) {
        progress = false;
        for (int side = 0; side < 2 && !a.dead; ++side) {
          const int node = side == 0 ? a.end : a.start;
          if (node < 0 || degree_[node] != 2) continue;
          if (a.start == a.end) {  // both ends of one polyline: it closes into a loop
            a.points.push_back(a.points.front());
            a.start = a.end = -1;
            degree_[node] = 0;
            progress = true;
            break;
          }
          const int j = find_other(node, i);
          if (j < 0) continue;
          join(i, j, node);
          progress = true;
        }
      }
    }
    recount();
  }

  // Bridge free ends closer than `max_gap` whose directions agree, nearest pairs first.
  void bridge_gaps(double max_gap) {
    struct End {
      size_t line;
      int node;
      Vec2 point, direction;  // direction points out of the line
    };
    std::vector<End> ends;
    for (size_t i = 0; i < lines_.size(); ++i) {
      const Polyline& l = lines_[i];
      if (l.dead || l.points.size() < 2) continue;
      auto out_dir = [](const std::vector<Vec2>& p, bool at_end) {
        const size_t n = p.size(), k = std::min<size_t>(4, n - 1);
        const Vec2 a = at_end ? p[n - 1 - k] : p[k], b = at_end ? p[n - 1] : p[0];
        const double len = std::hypot(b.x - a.x, b.y - a.y);
        return len > 0 ? Vec2{(b.x - a.x) / len, (b.y - a.y) / len} : Vec2{0, 0};
      };
      if (l.start >= 0 && degree_[l.start] == 1) ends.push_back({i, l.start, l.points.front(), out_dir(l.points, false)});
      if (l.end >= 0 && degree_[l.end] == 1) ends.push_back({i, l.end, l.points.back(), out_dir(l.points, true)});
    }
    struct Pair {
      double distance;
      size_t a, b;
    };
    std::vector<Pair> pairs;
    for (size_t a = 0; a < ends.size(); ++a) {
      for (size_t b = a + 1; b < ends.size(); ++b) {
        const double dx = ends[b].point.x - ends[a].point.x, dy = ends[b].point.y - ends[a].point.y;
        const double d = std::hypot(dx, dy);
        if (d > max_gap || ends[a].line == ends[b].line) continue;
        // Both ends must point roughly at each other.
        if (d > 0 && (ends[a].direction.x * dx + ends[a].direction.y * dy < 0.3 * d ||
                      -(ends[b].direction.x * dx + ends[b].direction.y * dy) < 0.3 * d)) {
          continue;
        }
        pairs.push_back({d, a, b});
      }
    }
    std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) { return x.distance < y.distance; });
    for (const Pair& p : pairs) {
      const End &a = ends[p.a], &b = ends[p.b];
      if (degree_[a.node] != 1 || degree_[b.node] != 1) continue;
      // Re-label b's node as a's: the two lines now meet at a node of degree 2.
      Polyline& lb = lines_[b.line];
      if (lb.dead) continue;
      if (lb.start == b.node) lb.start = a.node; else lb.end = a.node;
      degree_[a.node] = 2;
      degree_[b.node] = 0;
      merge_through_degree_two_at(a.node);
    }
    recount();
  }

  void remove_shorter_than(double min_length) {
    for (Polyline& l : lines_)
      if (!l.dead && l.length() < min_length) l.dead = true;
    recount();
  }

 private:
  void recount() {
    std::fill(degree_.begin(), degree_.end(), 0);
    for (const Polyline& l : lines_) {
      if (l.dead) continue;
      if (l.start >= 0) ++degree_[l.start];
      if (l.end >= 0) ++degree_[l.end];
    }
  }
  int find_other(int node, size_t not_this) const {
    for (size_t j = 0; j < lines_.size(); ++j)
      if (j != not_this && !lines_[j].dead && (lines_[j].start == node || lines_[j].end == node)) return static_cast<int>(j);
    return -1;
  }
  void merge_through_degree_two_at(int node) {
    for (size_t i = 0; i < lines_.size(); ++i) {
      if (lines_[i].dead || (lines_[i].start != node && lines_[i].end != node)) continue;
      const int j = find_other(node, i);
      if (j >= 0) join(i, j, node);
      else if (lines_[i].start == node && lines_[i].end == node) {
        lines_[i].points.push_back(lines_[i].points.front());
        lines_[i].start = lines_[i].end = -1;
      }
      return;
    }
  }
  // Appends line j to line i through their shared node; j dies.
  void join(size_t i, size_t j, int node) {
    Polyline &a = lines_[i], &b = lines_[j];
    if (a.end != node) {
      std::reverse(a.points.begin(), a.points.end());
      std::swap(a.start, a.end);
    }
    if (b.start != node) {
      std::reverse(b.points.begin(), b.points.end());
      std::swap(b.start, b.end);
    }
    const bool same_point = a.points.back() == b.points.front();
    a.points.insert(a.points.end(), b.points.begin() + (same_point ? 1 : 0), b.points.end());
    a.contrast_sum += b.contrast_sum;
    a.end = b.end;
    b.dead = true;
    degree_[node] = 0;
    if (a.start >= 0 && a.start == a.end) {  // the join closed a loop
      a.points.push_back(a.points.front());
      degree_[a.start] = 0;
      a.start = a.end = -1;
    }
  }

  std::vector<Polyline> lines_;
  std::vector<int> degree_;
};

// One pass of [1 2 1]/4 smoothing, ends fixed (closed loops wrap around): removes the pixel
// staircase left by the one-pixel chains without moving a curve by more than a quarter pixel.
void smooth_polyline(std::vector<Vec2>& p, bool closed) {
  const size_t n = p.size();
  if (n < 3) return;
  std::vector<Vec2> q = p;
  for (size_t i = 0; i < n; ++i) {
    size_t prev, next;
    if (closed) {
      if (i == n - 1) continue;
      prev = i == 0 ? n - 2 : i - 1;
      next = i + 1;
    } else {
      if (i == 0 || i == n - 1) continue;
      prev = i - 1, next = i + 1;
    }
    q[i] = {0.25 * p[prev].x + 0.5 * p[i].x + 0.25 * p[next].x, 0.25 * p[prev].y + 0.5 * p[i].y + 0.25 * p[next].y};
  }
  if (closed) q[n - 1] = q[0];
  p = std::move(q);
}

}  // namespace

void validate(const FeatureOptions& f, const std::string& prefix) {
  using detail::check_in;
  check_in(prefix + "blur_sigma", f.blur_sigma, 0, 20);
  check_in(prefix + "high_quantile", f.high_quantile, 0.01, 0.999);
  check_in(prefix + "min_high_threshold", f.min_high_threshold, 0, 1e4);
  check_in(prefix + "low_ratio", f.low_ratio, 0.01, 1);
  check_in(prefix + "min_length", f.min_length, 0, 1e6);
  check_in(prefix + "spur_length", f.spur_length, 0, 1e3);
  check_in(prefix + "max_gap", f.max_gap, 0, 100);
}

std::vector<DetectedFeature> detect_features(const Image8& image, const FeatureOptions& options) {
  if (image.width < 2 || image.height < 2) return {};
  validate(options);
  const int w = image.width, h = image.height;

  // Color gradient (Di Zenzo): the largest eigenvalue of the RGB structure tensor gives the
  // magnitude, its eigenvector the direction, so an edge between two colors of equal luminance (a
  // red apple on a green cloth) is found too. Channels are scaled by 1/sqrt(3) so that a gray edge
  // measures what it would in luminance: gray levels per pixel.
  cv::Mat3f rgb(h, w);
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = image.row(y);
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = row + x * image.channels;
      rgb(y, x) = cv::Vec3f(p[0], p[1], p[2]);
    }
  }
  if (options.blur_sigma > 0) cv::GaussianBlur(rgb, rgb, cv::Size(0, 0), options.blur_sigma);
  cv::Mat3f cx, cy;
  cv::Sobel(rgb, cx, CV_32F, 1, 0, 3, 1.0 / (8.0 * std::sqrt(3.0)));
  cv::Sobel(rgb, cy, CV_32F, 0, 1, 3, 1.0 / (8.0 * std::sqrt(3.0)));
  cv::Mat1f gx(h, w), gy(h, w), mag(h, w);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const cv::Vec3f a = cx(y, x), b = cy(y, x);
      const double jxx = a.dot(a), jyy = b.dot(b), jxy = a.dot(b);
      const double half_trace = 0.5 * (jxx + jyy);
      const double lambda = half_trace + std::sqrt(0.25 * (jxx - jyy) * (jxx - jyy) + jxy * jxy);
      // Principal eigenvector; its sign is arbitrary, which Canny's sectors do not see.
      double ex = jxy, ey = lambda - jxx;
      if (jxx >= jyy) ex = lambda - jyy, ey = jxy;
      const double norm = std::hypot(ex, ey);
      const double m = std::sqrt(std::max(lambda, 0.0));
      mag(y, x) = static_cast<float>(m);
      gx(y, x) = norm > 1e-12 ? static_cast<float>(m * ex / norm) : 0.0f;
      gy(y, x) = norm > 1e-12 ? static_cast<float>(m * ey / norm) : 0.0f;
    }
  }

  // Thresholds from the image's own gradient distribution.
  std::vector<float> values(mag.begin(), mag.end());
  auto q = values.begin() + static_cast<std::ptrdiff_t>(options.high_quantile * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), q, values.end());
  const double high = std::max<double>(*q, options.min_high_threshold);
  const double low = options.low_ratio * high;

  // Canny on our own derivatives (16x fixed point fits int16 for 8-bit images).
  constexpr double kScale = 16.0;
  cv::Mat dx, dy;
  gx.convertTo(dx, CV_16S, kScale);
  gy.convertTo(dy, CV_16S, kScale);
  cv::Mat1b edges;
  cv::Canny(dx, dy, edges, low * kScale, high * kScale, true);
  // Keep a one-pixel margin free: pixels on the image's outer ring have one-sided gradients.
  edges.row(0).setTo(0), edges.row(h - 1).setTo(0), edges.col(0).setTo(0), edges.col(w - 1).setTo(0);
  thin(edges);

  Linker linker(edges);
  std::vector<Chain> chains = linker.trace();

  // Subpixel location: move each chain pixel along the gradient direction to the parabola vertex
  // of the gradient magnitude sampled at -1, 0, +1 pixel.
  auto locate = [&](Pixel p) {
    Vec2 pt{p.x + 0.5, p.y + 0.5};
    const double m = mag(p.y, p.x);
    if (m > 1e-6) {
      const double nx = gx(p.y, p.x) / m, ny = gy(p.y, p.x) / m;
      const double m0 = bilinear(mag, p.x - nx, p.y - ny), m1 = bilinear(mag, p.x + nx, p.y + ny);
      const double denom = m0 - 2 * m + m1;
      if (denom < 0) {
        const double t = std::clamp(0.5 * (m0 - m1) / denom, -0.5, 0.5);
        pt.x += t * nx, pt.y += t * ny;
      }
    }
    return pt;
  };
  std::vector<Polyline> lines;
  lines.reserve(chains.size());
  for (const Chain& c : chains) {
    Polyline l;
    l.start = c.start, l.end = c.end;
    for (const Pixel& p : c.pixels) {
      l.points.push_back(locate(p));
      l.contrast_sum += mag(p.y, p.x);
    }
    if (c.closed) l.start = l.end = -1, l.points.back() = l.points.front();
    lines.push_back(std::move(l));
  }
  std::vector<Vec2> node_position(linker.num_nodes());
  for (int n = 0; n < linker.num_nodes(); ++n) node_position[n] = locate(linker.node_pixel(n));

  FeatureGraph graph(std::move(lines), linker.num_nodes());
  graph.prune_spurs(options.spur_length);
  graph.merge_through_degree_two();
  graph.bridge_gaps(options.max_gap);
  graph.remove_shorter_than(options.min_length);
  graph.merge_through_degree_two();
  graph.remove_shorter_than(options.min_length);

  std::vector<DetectedFeature> out;
  for (Polyline& l : graph.lines()) {
    if (l.dead) continue;
    DetectedFeature f;
    // Features meeting at a junction end exactly at the junction's position.
    const bool junction_start = l.start >= 0 && graph.degree(l.start) >= 3;
    const bool junction_end = l.end >= 0 && graph.degree(l.end) >= 3;
    if (junction_start) l.points.front() = node_position[l.start];
    if (junction_end) l.points.back() = node_position[l.end];
    smooth_polyline(l.points, l.closed());
    f.points = std::move(l.points);
    f.length = polyline_length(f.points);
    f.contrast = l.contrast_sum / static_cast<double>(std::max<size_t>(1, f.points.size()));
    f.start_node = junction_start ? l.start : -1;
    f.end_node = junction_end ? l.end : -1;
    out.push_back(std::move(f));
  }
  // Renumber junction nodes densely, in order of first appearance.
  std::vector<int> renumber(linker.num_nodes(), -1);
  int next = 0;
  for (DetectedFeature& f : out) {
    for (int* n : {&f.start_node, &f.end_node}) {
      if (*n < 0) continue;
      if (renumber[*n] < 0) renumber[*n] = next++;
      *n = renumber[*n];
    }
  }
  return out;
}

}  // namespace subvec
