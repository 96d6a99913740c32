// Global least-squares color fit through the limit stencils (paper §4, "Color optimization").
//
// With S the color limit stencils (refined color values = S * control colors) and B the sparse
// matrix that interpolates refined values at the fitted points (barycentric weights of the refined
// triangle containing each pixel centre), the fit solves
//     min_c |B S c - t|^2 + lambda |c - c0|^2
// through the normal equations S' (B'B) S c = S' B' t + lambda c0. B'B is assembled directly on the
// refined values (a 3x3 Gram block of barycentric weights per refined triangle), so the large
// pixel matrix is never formed, and the products run row by row through a dense accumulator.
// Then `l1_iterations` reweighted solves (each pixel row weighted by 1 / its absolute residual,
// floored) move the fit toward least absolute deviations, the error we report. Before those,
// `relocate_iterations` damped Gauss-Newton steps may move the smooth control vertices against the
// same pixel residual (relocate.cpp; docs/vectorize.md, "Vertex relocation").
//
// The stages of fit_colors(), in order: the targets (set_pixel_targets: locate the pixels, mark the
// band along the tears, fill its targets from their own side; or set_refined_vertex_targets), the
// least-squares solve (solve_colors), the optional relocation, the L1 reweighting (reweighted_fit)
// and the residual (measure_residual).
#include "subvec/vectorize/fit.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include <Eigen/SparseCholesky>

#include "core/cancel_p.h"
#include "core/geometry_p.h"
#include "core/messages_p.h"
#include "core/parallel_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/topology.h"
#include "subvec/subdiv/subdivision.h"
#include "vectorize/fit_p.h"
#include "vectorize/relocate_p.h"

namespace subvec {
namespace fit_detail {
namespace {

using detail::cross;

struct Segment {
  float ax, ay, bx, by;
};

// Whether segments pq and ab intersect (touching counts).
bool segments_cross(double px, double py, double qx, double qy, const Segment& s) {
  const double d1 = cross(qx - px, qy - py, s.ax - px, s.ay - py);
  const double d2 = cross(qx - px, qy - py, s.bx - px, s.by - py);
  const double d3 = cross(s.bx - s.ax, s.by - s.ay, px - s.ax, py - s.ay);
  const double d4 = cross(s.bx - s.ax, s.by - s.ay, qx - s.ax, qy - s.ay);
  return ((d1 <= 0 && d2 >= 0) || (d1 >= 0 && d2 <= 0)) && ((d3 <= 0 && d4 >= 0) || (d3 >= 0 && d4 <= 0));
}

// Tear segments bucketed on a coarse grid for neighbourhood queries.
class SegmentGrid {
 public:
  SegmentGrid(std::vector<Segment> segments, int width, int height, int cell)
      : segments_(std::move(segments)), cell_(cell), cols_(width / cell + 1), rows_(height / cell + 1),
        buckets_(size_t(cols_) * rows_) {
    for (size_t i = 0; i < segments_.size(); ++i) {
      const Segment& s = segments_[i];
      const int x0 = clamp_col(std::min(s.ax, s.bx)), x1 = clamp_col(std::max(s.ax, s.bx));
      const int y0 = clamp_row(std::min(s.ay, s.by)), y1 = clamp_row(std::max(s.ay, s.by));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) buckets_[size_t(y) * cols_ + x].push_back(static_cast<int32_t>(i));
    }
  }
  // Segment indices whose cells overlap the box (may repeat).
  void query(double x0, double y0, double x1, double y1, std::vector<int32_t>& out) const {
    out.clear();
    for (int y = clamp_row(y0); y <= clamp_row(y1); ++y)
      for (int x = clamp_col(x0); x <= clamp_col(x1); ++x)
        for (int32_t i : buckets_[size_t(y) * cols_ + x]) out.push_back(i);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  const Segment& operator[](int32_t i) const { return segments_[i]; }
  size_t size() const { return segments_.size(); }

 private:
  int clamp_col(double x) const { return std::clamp(static_cast<int>(x / cell_), 0, cols_ - 1); }
  int clamp_row(double y) const { return std::clamp(static_cast<int>(y / cell_), 0, rows_ - 1); }
  std::vector<Segment> segments_;
  int cell_, cols_, rows_;
  std::vector<std::vector<int32_t>> buckets_;
};

// Accumulates sparse rows through a dense array over the columns.
class RowAccumulator {
 public:
  explicit RowAccumulator(int columns) : acc_(columns, 0.0), seen_(columns, 0), touched_(size_t(columns) + 1) {}
  void add(int32_t column, double value) {
    touched_[count_] = column;  // kept only the first time the column is seen
    count_ += seen_[column] ^ 1;
    seen_[column] = 1;
    acc_[column] += value;
  }
  // Appends the row (columns from `first_column` on, sorted; exact zeros dropped, except the
  // diagonal `keep` when given) and starts a new one.
  void flush(Rows& out, int32_t first_column = 0, int32_t keep = -1) {
    if (keep >= 0 && !seen_[keep]) touched_[count_++] = keep, seen_[keep] = 1;
    std::sort(touched_.begin(), touched_.begin() + count_);
    for (size_t i = 0; i < count_; ++i) {
      const int32_t column = touched_[i];
      if (column >= first_column && (acc_[column] != 0.0 || column == keep)) {
        out.columns.push_back(column);
        out.values.push_back(acc_[column]);
      }
      acc_[column] = 0.0;
      seen_[column] = 0;
    }
    count_ = 0;
    out.offsets.push_back(static_cast<int32_t>(out.columns.size()));
  }

 private:
  std::vector<double> acc_;
  std::vector<uint8_t> seen_;
  std::vector<int32_t> touched_;
  size_t count_ = 0;
};

// Rows 0 .. count-1 of `columns` columns; build(acc, r, out) appends row r to out through acc. One
// contiguous range of rows per thread: rows are independent, so the result is the same for any split.
template <class Build>
Rows build_rows(int count, int columns, int threads, const Build& build) {
  const int parts = count < 1024 ? 1 : std::min(detail::resolve_threads(threads), 8);
  std::vector<Rows> part(parts);
  detail::parallel_for(parts, parts, [&](int p) {
    RowAccumulator acc(columns);
    const int end = static_cast<int>(int64_t(count) * (p + 1) / parts);
    for (int r = static_cast<int>(int64_t(count) * p / parts); r < end; ++r) build(acc, r, part[p]);
  });
  Rows out = std::move(part[0]);
  for (int p = 1; p < parts; ++p) {
    const int32_t base = static_cast<int32_t>(out.columns.size());
    for (size_t r = 1; r < part[p].offsets.size(); ++r) out.offsets.push_back(base + part[p].offsets[r]);
    out.columns.insert(out.columns.end(), part[p].columns.begin(), part[p].columns.end());
    out.values.insert(out.values.end(), part[p].values.begin(), part[p].values.end());
  }
  return out;
}

// B'B over the m refined color values: the Gram blocks of the refined triangles (symmetric, packed
// 00 01 02 11 12 22) plus a diagonal.
Rows gram_rows(const RefinedMesh& refined, int m, const std::vector<std::array<double, 6>>& blocks,
               const std::vector<double>& diagonal, int threads) {
  static constexpr int kPacked[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  std::vector<int32_t> first(size_t(m) + 1, 0), corners;
  if (!blocks.empty()) {
    for (const Tri& t : refined.triangle_colors)
      for (int32_t v : t) ++first[v + 1];
    std::partial_sum(first.begin(), first.end(), first.begin());
    corners.resize(first.back());
    std::vector<int32_t> fill(first.begin(), first.end() - 1);
    for (int t = 0; t < refined.num_triangles(); ++t)
      for (int k = 0; k < 3; ++k) corners[fill[refined.triangle_colors[t][k]]++] = 3 * t + k;
  }
  return build_rows(m, m, threads, [&](RowAccumulator& acc, int32_t v, Rows& out) {
    if (!diagonal.empty()) acc.add(v, diagonal[v]);
    for (int32_t i = first[v]; i < first[v + 1] && !blocks.empty(); ++i) {
      const int32_t t = corners[i] / 3, k = corners[i] % 3;
      for (int j = 0; j < 3; ++j) acc.add(refined.triangle_colors[t][j], blocks[t][kPacked[k][j]]);
    }
    acc.flush(out);
  });
}

// a * s, with s a sparse matrix of `columns` columns.
Rows multiply(const Rows& a, const SparseMatrix& s, int columns, int threads) {
  return build_rows(a.num_rows(), columns, threads, [&](RowAccumulator& acc, int r, Rows& out) {
    for (int32_t e = a.offsets[r]; e < a.offsets[r + 1]; ++e) {
      const double w = a.values[e];
      for (SparseMatrix::InnerIterator it(s, a.columns[e]); it; ++it) acc.add(static_cast<int32_t>(it.col()), w * it.value());
    }
    acc.flush(out);
  });
}

std::array<double, 3> pixel(const Image8& image, int x, int y) {
  const uint8_t* p = image.row(y) + size_t(x) * image.channels;
  return {double(p[0]), double(p[1]), double(p[2])};
}


// The lower triangle of the normal matrix S' M S, with M given as rows over the rows of S and st
// the transpose of S: row i of the result is column i of the lower triangle, from the diagonal
// (always stored) down.
Rows lower_normal(const Rows& m, const SparseMatrix& s, const Rows& st, int threads) {
  const int c = static_cast<int>(s.cols());
  const Rows ms = multiply(m, s, c, threads);
  return build_rows(c, c, threads, [&](RowAccumulator& acc, int32_t i, Rows& out) {
    for (int32_t e = st.offsets[i]; e < st.offsets[i + 1]; ++e) {
      const int32_t r = st.columns[e];
      const double w = st.values[e];
      // (Rows come out of RowAccumulator sorted: the lower triangle is a suffix.)
      const int32_t* first = ms.columns.data() + ms.offsets[r];
      const int32_t* last = ms.columns.data() + ms.offsets[r + 1];
      for (int32_t k = static_cast<int32_t>(std::lower_bound(first, last, i) - ms.columns.data());
           k < ms.offsets[r + 1]; ++k) {
        acc.add(ms.columns[k], w * ms.values[k]);
      }
    }
    acc.flush(out, i, i);
  });
}

// Solves (lower triangle, as lower_normal gives it) x = rhs, analysing the pattern only when it is
// not the one `solver` last analysed.
template <class Rhs>
Rhs solve_lower(const Rows& lower, const Rhs& rhs, NormalSolver& solver, const char* what) {
  const int c = lower.num_rows();
  const Eigen::Map<const Eigen::SparseMatrix<double, Eigen::ColMajor, int32_t>> normal(
      c, c, static_cast<int32_t>(lower.columns.size()), lower.offsets.data(), lower.columns.data(), lower.values.data());
  if (solver.offsets != lower.offsets || solver.columns != lower.columns) {
    solver.ldlt.analyzePattern(normal);
    solver.offsets = lower.offsets, solver.columns = lower.columns;
  }
  solver.ldlt.factorize(normal);
  if (solver.ldlt.info() != Eigen::Success) throw Error(ErrorCode::kInvalidMesh, std::string(what) + ": normal equations are singular");
  return Rhs(solver.ldlt.solve(rhs));
}

// The tear segments of the limit mesh, for the band and for same-side tests.
SegmentGrid tear_grid(const FitSystem& system) {
  const std::vector<float>& limit = system.limit;
  std::vector<Segment> segments;
  for (const EdgeVerts& e : system.refined.tear_edges) {
    segments.push_back({limit[2 * e[0]], limit[2 * e[0] + 1], limit[2 * e[1]], limit[2 * e[1] + 1]});
  }
  return SegmentGrid(std::move(segments), system.width, system.height, 4);
}

// The band along the tears: pixels whose centre lies closer than `band` to a tear segment.
std::vector<uint8_t> tear_band(const SegmentGrid& grid, int width, int height, double band) {
  std::vector<uint8_t> in_band(size_t(width) * height, 0);
  for (size_t i = 0; i < grid.size(); ++i) {
    const Segment& sg = grid[static_cast<int32_t>(i)];
    detail::for_pixels_near_segment(sg.ax, sg.ay, sg.bx, sg.by, band, width, height,
                                    [&](int x, int y) { in_band[size_t(y) * width + x] = 1; });
  }
  return in_band;
}

// Hole filling (the paper's): each located band pixel's target is the inverse-square-distance
// average of the non-band pixels within fill_radius on its own side of the tears (no tear segment
// between them). In parallel, image rows apart.
struct FilledTargets {
  std::vector<std::array<float, 3>> color;  // the precision of a PixelRow's target
  std::vector<uint8_t> ok;  // 0: nothing on this side nearby, the pixel is left out
};

FilledTargets fill_band(const FitSystem& system, const Image8& image, const SegmentGrid& grid,
                        const std::vector<uint8_t>& band, const ColorFitOptions& options) {
  const int width = system.width, height = system.height;
  const int r = static_cast<int>(std::ceil(options.fill_radius));
  FilledTargets filled{std::vector<std::array<float, 3>>(size_t(width) * height),
                       std::vector<uint8_t>(size_t(width) * height, 0)};
  const int parts = std::min(detail::resolve_threads(options.threads), height);
  detail::parallel_for(parts, parts, [&](int part) {
    std::vector<int32_t> nearby;
    for (int y = height * part / parts; y < height * (part + 1) / parts; ++y) {
      for (int x = 0; x < width; ++x) {
        if (system.located[size_t(y) * width + x].triangle < 0 || !band[size_t(y) * width + x]) continue;
        const double cx = x + 0.5, cy = y + 0.5;
        grid.query(cx - r, cy - r, cx + r, cy + r, nearby);
        std::array<double, 3> sum{0, 0, 0};
        double wsum = 0;
        for (int qy = std::max(0, y - r); qy <= std::min(height - 1, y + r); ++qy) {
          for (int qx = std::max(0, x - r); qx <= std::min(width - 1, x + r); ++qx) {
            if (band[size_t(qy) * width + qx]) continue;
            const double d2 = double(qx - x) * (qx - x) + double(qy - y) * (qy - y);
            if (d2 > options.fill_radius * options.fill_radius) continue;
            bool blocked = false;
            for (int32_t i : nearby) {
              if (segments_cross(cx, cy, qx + 0.5, qy + 0.5, grid[i])) {
                blocked = true;
                break;
              }
            }
            if (blocked) continue;
            const auto q = pixel(image, qx, qy);
            for (int k = 0; k < 3; ++k) sum[k] += q[k] / d2;
            wsum += 1 / d2;
          }
        }
        if (wsum == 0) continue;
        for (int k = 0; k < 3; ++k) filled.color[size_t(y) * width + x][k] = static_cast<float>(sum[k] / wsum);
        filled.ok[size_t(y) * width + x] = 1;
      }
    }
  });
  return filled;
}

}  // namespace

// The transpose of s (rows x columns) as rows.
Rows transpose(const SparseMatrix& s) {
  Rows out;
  out.offsets.assign(size_t(s.cols()) + 1, 0);
  for (int r = 0; r < s.rows(); ++r)
    for (SparseMatrix::InnerIterator it(s, r); it; ++it) ++out.offsets[it.col() + 1];
  std::partial_sum(out.offsets.begin(), out.offsets.end(), out.offsets.begin());
  out.columns.resize(out.offsets.back());
  out.values.resize(out.offsets.back());
  std::vector<int32_t> fill(out.offsets.begin(), out.offsets.end() - 1);
  for (int r = 0; r < s.rows(); ++r) {
    for (SparseMatrix::InnerIterator it(s, r); it; ++it) {
      const int32_t k = fill[it.col()]++;
      out.columns[k] = r;
      out.values[k] = it.value();
    }
  }
  return out;
}

FitSystem::FitSystem(const ControlMesh& mesh, const MeshTopology& topology, int width_, int height_, int depth)
    : width(width_), height(height_), sub(mesh, topology, depth), refined(sub.topology()), s(sub.color_stencils()),
      m(static_cast<int>(s.rows())), c(static_cast<int>(s.cols())), st(transpose(s)),
      limit(size_t(sub.num_vertices()) * 2), btt(m, {0, 0, 0}) {
  sub.evaluate_positions_once(mesh.positions, limit);
}

int locate_pixels(FitSystem& system) {
  const int width = system.width, height = system.height;
  const RefinedMesh& refined = system.refined;
  const std::vector<float>& limit = system.limit;
  int folded = 0;
  system.located.assign(size_t(width) * height, Location{});
  for (int t = 0; t < refined.num_triangles(); ++t) {
    const Tri& tri = refined.triangles[t];
    const double x0 = limit[2 * tri[0]], y0 = limit[2 * tri[0] + 1];
    const double x1 = limit[2 * tri[1]], y1 = limit[2 * tri[1] + 1];
    const double x2 = limit[2 * tri[2]], y2 = limit[2 * tri[2] + 1];
    const double area = cross(x1 - x0, y1 - y0, x2 - x0, y2 - y0);
    if (area <= 0) {
      ++folded;
      continue;
    }
    const int px0 = std::max(0, int(std::ceil(std::min({x0, x1, x2}) - 0.5)));
    const int px1 = std::min(width - 1, int(std::floor(std::max({x0, x1, x2}) - 0.5)));
    const int py0 = std::max(0, int(std::ceil(std::min({y0, y1, y2}) - 0.5)));
    const int py1 = std::min(height - 1, int(std::floor(std::max({y0, y1, y2}) - 0.5)));
    constexpr double kEps = -1e-9;
    for (int py = py0; py <= py1; ++py) {
      for (int px = px0; px <= px1; ++px) {
        Location& loc = system.located[size_t(py) * width + px];
        if (loc.triangle >= 0) continue;
        const double x = px + 0.5, y = py + 0.5;
        const double b1 = cross(x - x0, y - y0, x2 - x0, y2 - y0) / area;
        const double b2 = cross(x1 - x0, y1 - y0, x - x0, y - y0) / area;
        if (b1 < kEps || b2 < kEps || 1 - b1 - b2 < kEps) continue;
        loc = {t, static_cast<float>(b1), static_cast<float>(b2)};
      }
    }
  }
  for (const PixelRow& row : system.rows) folded += system.located[row.pixel].triangle < 0;
  return folded;
}

void accumulate_pixels(FitSystem& system, const std::vector<double>& weights) {
  const RefinedMesh& refined = system.refined;
  system.blocks.assign(refined.num_triangles(), {0, 0, 0, 0, 0, 0});
  system.btt.assign(system.m, {0, 0, 0});
  for (size_t r = 0; r < system.rows.size(); ++r) {
    const Location& loc = system.located[system.rows[r].pixel];
    const double wr = weights.empty() ? 1.0 : weights[r];
    const Tri& values = refined.triangle_colors[loc.triangle];
    const double w[3] = {1.0 - loc.b1 - loc.b2, loc.b1, loc.b2};
    std::array<double, 6>& g = system.blocks[loc.triangle];
    g[0] += wr * w[0] * w[0], g[1] += wr * w[0] * w[1], g[2] += wr * w[0] * w[2];
    g[3] += wr * w[1] * w[1], g[4] += wr * w[1] * w[2], g[5] += wr * w[2] * w[2];
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) system.btt[values[i]][k] += wr * w[i] * system.rows[r].target[k];
  }
}

void set_pixel_targets(FitSystem& system, const Image8& image, const ColorFitOptions& options,
                       ColorFitStats& stats) {
  const int width = system.width, height = system.height;
  locate_pixels(system);
  const SegmentGrid grid = tear_grid(system);
  const std::vector<uint8_t> band = tear_band(grid, width, height, options.band);
  const FilledTargets filled = fill_band(system, image, grid, band, options);
  // Targets: the pixel, or for band pixels the hole-filled color; the rows in pixel order.
  system.rows.reserve(system.located.size());  // at most a row per pixel
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      if (system.located[i].triangle < 0) continue;
      std::array<double, 3> target = pixel(image, x, y);
      if (band[i]) {
        if (!filled.ok[i]) continue;
        target = {filled.color[i][0], filled.color[i][1], filled.color[i][2]};
        ++stats.filled;
      }
      system.rows.push_back({static_cast<int32_t>(i), {float(target[0]), float(target[1]), float(target[2])}});
    }
  }
  stats.rows = static_cast<int>(system.rows.size());
  accumulate_pixels(system, {});
}

void set_refined_vertex_targets(FitSystem& system, const Image8& image, ColorFitStats& stats) {
  // One row per refined color value, its target sampled at its limit position (values on a tear
  // sample slightly inside their own side).
  const RefinedMesh& refined = system.refined;
  const std::vector<float>& limit = system.limit;
  const int m = system.m;
  std::vector<double> sx(m, 0), sy(m, 0), cnt(m, 0);
  std::vector<int32_t> vertex_of(m, -1);
  for (int t = 0; t < refined.num_triangles(); ++t) {
    const Tri& tri = refined.triangles[t];
    const double cx = (limit[2 * tri[0]] + limit[2 * tri[1]] + limit[2 * tri[2]]) / 3;
    const double cy = (limit[2 * tri[0] + 1] + limit[2 * tri[1] + 1] + limit[2 * tri[2] + 1]) / 3;
    for (int k = 0; k < 3; ++k) {
      const int32_t value = refined.triangle_colors[t][k];
      vertex_of[value] = tri[k];
      sx[value] += cx, sy[value] += cy, cnt[value] += 1;
    }
  }
  system.diagonal.assign(m, 0.0);
  std::vector<int> values_at_vertex(system.sub.num_vertices(), 0);
  for (int v = 0; v < m; ++v)
    if (vertex_of[v] >= 0) ++values_at_vertex[vertex_of[v]];
  for (int v = 0; v < m; ++v) {
    if (vertex_of[v] < 0) continue;
    double x = limit[2 * vertex_of[v]], y = limit[2 * vertex_of[v] + 1];
    if (values_at_vertex[vertex_of[v]] > 1) {
      const double dx = sx[v] / cnt[v] - x, dy = sy[v] / cnt[v] - y, len = std::hypot(dx, dy);
      if (len > 0) x += 0.75 * dx / len, y += 0.75 * dy / len;
    }
    const auto target = sample_bilinear(image, x, y);
    system.diagonal[v] += 1;
    for (int k = 0; k < 3; ++k) system.btt[v][k] += target[k];
    ++stats.rows;
  }
}

Eigen::MatrixX3d solve_colors(const FitSystem& system, const std::vector<Color>& start, double regularization,
                              int threads) {
  const int c = system.c;
  const Rows& st = system.st;
  Rows lower = lower_normal(gram_rows(system.refined, system.m, system.blocks, system.diagonal, threads), system.s,
                            st, threads);
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(c, 3);
  for (int i = 0; i < c; ++i) {
    for (int32_t e = st.offsets[i]; e < st.offsets[i + 1]; ++e)
      for (int k = 0; k < 3; ++k) rhs(i, k) += st.values[e] * system.btt[st.columns[e]][k];
  }
  // Tikhonov pull toward the current colors, scaled to the system, for colors no row reaches. Each
  // column's first entry is its diagonal.
  double trace = 0;
  for (int i = 0; i < c; ++i) trace += lower.values[lower.offsets[i]];
  const double scale = trace / std::max(1, c);
  const double lambda = regularization * std::max(scale, 1e-12);
  for (int i = 0; i < c; ++i) {
    lower.values[lower.offsets[i]] += lambda;
    rhs(i, 0) += lambda * start[i].r;
    rhs(i, 1) += lambda * start[i].g;
    rhs(i, 2) += lambda * start[i].b;
  }
  return Eigen::MatrixX3d(solve_lower(lower, rhs, system.solver, "color fit"));
}

double squared_error(const FitSystem& system, const Eigen::MatrixX3d& values) {
  double sum = 0;
  for (const PixelRow& row : system.rows) {
    const Location& loc = system.located[row.pixel];
    for (int k = 0; k < 3; ++k) {
      const double e = predict(loc, system.refined.triangle_colors[loc.triangle], values, k) - row.target[k];
      sum += e * e;
    }
  }
  return sum;
}

}  // namespace fit_detail

namespace {

using fit_detail::FitSystem;

}  // namespace

void validate(const ColorFitOptions& f, const std::string& prefix) {
  using detail::check_in;
  check_in(prefix + "depth", f.depth, -1, 8);
  check_in(prefix + "l1_iterations", f.l1_iterations, 0, 20);
  detail::check_positive(prefix + "l1_floor", f.l1_floor);
  check_in(prefix + "relocate_iterations", f.relocate_iterations, 0, 50);
  detail::check_positive(prefix + "relocate_damping", f.relocate_damping);
  detail::check_positive(prefix + "relocate_max_step", f.relocate_max_step);
  check_in(prefix + "relocate_cg_iterations", f.relocate_cg_iterations, 1, 1000);
  check_in(prefix + "relocate_refit_every", f.relocate_refit_every, 1, 1000);
}

namespace {

void check_inputs(int width, int height, const Image8& image, const ColorFitOptions& options) {
  if (image.width != width || image.height != height) {
    throw Error(ErrorCode::kInvalidArgument, "fit_colors: image is " + std::to_string(image.width) + "x" +
                                                 std::to_string(image.height) + ", the mesh domain " +
                                                 std::to_string(width) + "x" + std::to_string(height));
  }
  validate(options);
}

// One iteratively reweighted least-squares step toward the least absolute deviations fit: each
// pixel row weighted by 1 / max(its mean absolute residual under x, l1_floor), then solved again.
Eigen::MatrixX3d reweighted_fit(FitSystem& system, const Eigen::MatrixX3d& x, const std::vector<Color>& start,
                                const ColorFitOptions& options) {
  const Eigen::MatrixX3d values = system.s * x;
  const std::vector<fit_detail::PixelRow>& rows = system.rows;
  std::vector<double> weights(rows.size());
  const int parts = std::max(1, std::min(detail::resolve_threads(options.threads), 8));
  detail::parallel_for(parts, parts, [&](int part) {
    const size_t end = rows.size() * size_t(part + 1) / size_t(parts);
    for (size_t r = rows.size() * size_t(part) / size_t(parts); r < end; ++r) {
      const fit_detail::Location& loc = system.located[rows[r].pixel];
      const Tri& v = system.refined.triangle_colors[loc.triangle];
      double residual = 0;
      for (int k = 0; k < 3; ++k) residual += std::abs(fit_detail::predict(loc, v, values, k) - rows[r].target[k]);
      weights[r] = 1 / std::max(residual / 3, options.l1_floor);
    }
  });
  fit_detail::accumulate_pixels(system, weights);
  return fit_detail::solve_colors(system, start, options.regularization, options.threads);
}

// Residual over the located pixels (the paper's error, before 8-bit rounding) and the 8-bit MAE.
void measure_residual(const FitSystem& system, const Image8& image, const Eigen::MatrixX3d& x, ColorFitStats& stats) {
  const Eigen::MatrixX3d values = system.s * x;
  double sum = 0, abs_sum = 0;
  long n = 0;
  for (int y = 0; y < system.height; ++y) {
    for (int px = 0; px < system.width; ++px) {
      const fit_detail::Location& loc = system.located[size_t(y) * system.width + px];
      if (loc.triangle < 0) continue;
      const Tri& v = system.refined.triangle_colors[loc.triangle];
      const auto target = fit_detail::pixel(image, px, y);
      for (int k = 0; k < 3; ++k) {
        const double pred = fit_detail::predict(loc, v, values, k);
        sum += (pred - target[k]) * (pred - target[k]);
        abs_sum += std::abs(std::clamp(std::round(pred), 0.0, 255.0) - target[k]);
      }
      n += 3;
    }
  }
  stats.rms = n ? std::sqrt(sum / double(n)) : 0;
  stats.mae = n ? abs_sum / double(n) : 0;
}

}  // namespace

int default_fit_depth(const ControlMesh& mesh) {
  double total = 0;
  int count = 0;
  for (const Tri& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = mesh.positions[t[k]], b = mesh.positions[t[(k + 1) % 3]];
      total += std::hypot(b.x - a.x, b.y - a.y);
      ++count;
    }
  }
  return fit_depth_for_mean_edge(count ? total / count : 0);
}

int fit_depth_for_mean_edge(double mean_edge_pixels) {
  int depth = 0;
  while (mean_edge_pixels > kFitEdgePixels && depth < 5) mean_edge_pixels /= 2, ++depth;
  return depth;
}

ColorFitStats fit_colors(ControlMesh& mesh, int width, int height, const Image8& image,
                         const ColorFitOptions& options) {
  check_inputs(width, height, image, options);
  const MeshTopology topo = MeshTopology::build(mesh, width, height);
  FitSystem system(mesh, topo, width, height, options.depth >= 0 ? options.depth : default_fit_depth(mesh));
  const bool pixels = options.target == ColorFitTarget::kPixels;
  ColorFitStats stats;
  detail::check_cancel(options.cancel);
  if (pixels) {
    fit_detail::set_pixel_targets(system, image, options, stats);
  } else {
    fit_detail::set_refined_vertex_targets(system, image, stats);
  }
  const std::vector<Color> start = mesh.colors;
  detail::check_cancel(options.cancel);
  Eigen::MatrixX3d x = fit_detail::solve_colors(system, start, options.regularization, options.threads);
  if (options.relocate_iterations > 0 && pixels) {
    stats.relocations = fit_detail::relocate_vertices(mesh, topo, system, start, options, x);
  }
  // Iteratively reweighted least squares toward the least absolute deviations fit: the error we
  // report (and the one the eye forgives least on flat areas) is the mean absolute one, and the L1
  // fit lets outliers (texture, specular dots, pixels at misplaced edges) pull the colors less.
  // One reweighting gets most of the gain (docs/vectorize.md).
  for (int it = 0; it < options.l1_iterations && pixels; ++it) {
    detail::check_cancel(options.cancel);
    x = reweighted_fit(system, x, start, options);
  }
  for (int i = 0; i < system.c; ++i) {
    mesh.colors[i] = {static_cast<float>(x(i, 0)), static_cast<float>(x(i, 1)), static_cast<float>(x(i, 2))};
  }
  if (pixels && options.measure) measure_residual(system, image, x, stats);
  return stats;
}

}  // namespace subvec
