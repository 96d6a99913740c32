// Vertex relocation inside the color fit: damped Gauss-Newton steps on the smooth control vertices
// (relocate_p.h). One step: linearize the pixel residual on the refined vertices (color gradients,
// barycentric Gram blocks), pull it back to the control vertices through the position stencils,
// solve the damped normal equations by preconditioned conjugate gradients, move without folding a
// triangle, and keep the move only when the squared error drops.
#include "vectorize/relocate_p.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/cancel_p.h"
#include "core/geometry_p.h"

namespace subvec::fit_detail {
namespace {

using detail::cross;

constexpr int kPacked[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};

class Relocator {
 public:
  Relocator(ControlMesh& mesh, const MeshTopology& topology, FitSystem& system, const ColorFitOptions& options)
      : mesh_(mesh), system_(system), options_(options), p_(system.sub.position_stencils()), pt_(transpose(p_)),
        n_(system.sub.num_vertices()), nv_(mesh.num_vertices()), nt_(system.refined.num_triangles()),
        damping_(options.relocate_damping), movable_(nv_, 0), gram_(nt_), gradient_(nt_), tensor_(nt_),
        precondition_(nv_), rhs_refined_(size_t(2) * n_), u_(size_t(2) * n_), hu_(size_t(2) * n_) {
    for (int v = 0; v < nv_; ++v) movable_[v] = topology.vertex_tags[v] == VertexTag::kSmooth;
  }

  int run(const std::vector<Color>& start, Eigen::MatrixX3d& x) {
    int kept = 0;
    Eigen::MatrixX3d values = system_.s * x;
    double error = squared_error(system_, values);
    const int folded = folded_triangles();
    for (int it = 0; it < options_.relocate_iterations; ++it) {
      detail::check_cancel(options_.cancel);
      linearize(values);
      const std::vector<double> step = conjugate_gradients(right_hand_side());
      const std::vector<Vec2> before = mesh_.positions;
      move(before, step);
      const std::vector<float> limit_before = system_.limit;
      const std::vector<Location> located_before = system_.located;
      update_limit();
      const double moved_error =
          locate_pixels(system_) <= folded ? squared_error(system_, values) : std::numeric_limits<double>::infinity();
      if (moved_error < error) {
        error = moved_error, damping_ = std::max(damping_ / 2, 1e-3);
        ++kept;
      } else {
        mesh_.positions = before, system_.limit = limit_before, system_.located = located_before;
        damping_ *= 4;
      }
      if ((it + 1) % options_.relocate_refit_every == 0 || it + 1 == options_.relocate_iterations) {
        accumulate_pixels(system_, {});
        x = solve_colors(system_, start, options_.regularization, options_.threads);
        values = system_.s * x;
        error = squared_error(system_, values);
      }
    }
    return kept;
  }

 private:
  int folded_triangles() const {
    const std::vector<float>& limit = system_.limit;
    int folded = 0;
    for (const Tri& tv : system_.refined.triangles) {
      folded += !(cross(limit[2 * tv[1]] - limit[2 * tv[0]], limit[2 * tv[1] + 1] - limit[2 * tv[0] + 1],
                        limit[2 * tv[2]] - limit[2 * tv[0]], limit[2 * tv[2] + 1] - limit[2 * tv[0] + 1]) > 0);
    }
    return folded;
  }

  // Color gradients and their structure tensors per refined triangle; then the barycentric Gram
  // blocks and the gradient of half the squared error on refined coordinates.
  void linearize(const Eigen::MatrixX3d& values) {
    const RefinedMesh& refined = system_.refined;
    const std::vector<float>& limit = system_.limit;
    for (int t = 0; t < nt_; ++t) {
      const Tri& tv = refined.triangles[t];
      const Tri& tc = refined.triangle_colors[t];
      const double e1x = limit[2 * tv[1]] - limit[2 * tv[0]], e1y = limit[2 * tv[1] + 1] - limit[2 * tv[0] + 1];
      const double e2x = limit[2 * tv[2]] - limit[2 * tv[0]], e2y = limit[2 * tv[2] + 1] - limit[2 * tv[0] + 1];
      const double det = e1x * e2y - e1y * e2x;
      gradient_[t] = {0, 0, 0, 0, 0, 0}, tensor_[t] = {0, 0, 0}, gram_[t] = {0, 0, 0, 0, 0, 0};
      if (!(det > 0)) continue;
      for (int k = 0; k < 3; ++k) {
        const double d1 = values(tc[1], k) - values(tc[0], k), d2 = values(tc[2], k) - values(tc[0], k);
        const double gx = (d1 * e2y - e1y * d2) / det, gy = (e1x * d2 - d1 * e2x) / det;
        gradient_[t][2 * k] = gx, gradient_[t][2 * k + 1] = gy;
        tensor_[t][0] += gx * gx, tensor_[t][1] += gx * gy, tensor_[t][2] += gy * gy;
      }
    }
    std::fill(rhs_refined_.begin(), rhs_refined_.end(), 0.0);
    for (const PixelRow& row : system_.rows) {
      const Location& loc = system_.located[row.pixel];
      const Tri& tv = refined.triangles[loc.triangle];
      const double w[3] = {1.0 - loc.b1 - loc.b2, loc.b1, loc.b2};
      std::array<double, 6>& g = gram_[loc.triangle];
      g[0] += w[0] * w[0], g[1] += w[0] * w[1], g[2] += w[0] * w[2];
      g[3] += w[1] * w[1], g[4] += w[1] * w[2], g[5] += w[2] * w[2];
      double rx = 0, ry = 0;
      for (int k = 0; k < 3; ++k) {
        const double e = predict(loc, refined.triangle_colors[loc.triangle], values, k) - row.target[k];
        rx += e * gradient_[loc.triangle][2 * k], ry += e * gradient_[loc.triangle][2 * k + 1];
      }
      for (int i = 0; i < 3; ++i) rhs_refined_[2 * tv[i]] += w[i] * rx, rhs_refined_[2 * tv[i] + 1] += w[i] * ry;
    }
  }

  // The right-hand side on the control vertices, and a block-Jacobi preconditioner (the diagonal
  // terms of P'HP) per vertex.
  std::vector<double> right_hand_side() {
    const RefinedMesh& refined = system_.refined;
    std::vector<double> r(size_t(2) * nv_, 0.0);
    std::vector<std::array<double, 3>> hjj(n_, {0, 0, 0});
    for (int t = 0; t < nt_; ++t)
      for (int k = 0; k < 3; ++k)
        for (int c3 = 0; c3 < 3; ++c3) hjj[refined.triangles[t][k]][c3] += gram_[t][kPacked[k][k]] * tensor_[t][c3];
    for (int v = 0; v < nv_; ++v) {
      precondition_[v] = {0, 0, 0};
      if (!movable_[v]) continue;
      for (int32_t e = pt_.offsets[v]; e < pt_.offsets[v + 1]; ++e) {
        const int32_t j = pt_.columns[e];
        const double w2 = pt_.values[e] * pt_.values[e];
        r[2 * v] += pt_.values[e] * rhs_refined_[2 * j], r[2 * v + 1] += pt_.values[e] * rhs_refined_[2 * j + 1];
        for (int c3 = 0; c3 < 3; ++c3) precondition_[v][c3] += w2 * hjj[j][c3];
      }
      precondition_[v][0] += 1e-9, precondition_[v][2] += 1e-9;
    }
    return r;
  }

  // out = (P'HP + damping * diag) d over the movable vertices.
  void apply(const std::vector<double>& d, std::vector<double>& out) {
    const RefinedMesh& refined = system_.refined;
    for (int j = 0; j < n_; ++j) {
      double ux = 0, uy = 0;
      for (SparseMatrix::InnerIterator it(p_, j); it; ++it) ux += it.value() * d[2 * it.col()], uy += it.value() * d[2 * it.col() + 1];
      u_[2 * j] = ux, u_[2 * j + 1] = uy;
    }
    std::fill(hu_.begin(), hu_.end(), 0.0);
    for (int t = 0; t < nt_; ++t) {
      const Tri& tv = refined.triangles[t];
      const std::array<double, 3>& tt = tensor_[t];
      for (int k = 0; k < 3; ++k) {
        double sx = 0, sy = 0;
        for (int l = 0; l < 3; ++l) {
          const double g = gram_[t][kPacked[k][l]];
          sx += g * u_[2 * tv[l]], sy += g * u_[2 * tv[l] + 1];
        }
        hu_[2 * tv[k]] += tt[0] * sx + tt[1] * sy, hu_[2 * tv[k] + 1] += tt[1] * sx + tt[2] * sy;
      }
    }
    for (int v = 0; v < nv_; ++v) {
      double ox = 0, oy = 0;
      if (movable_[v]) {
        for (int32_t e = pt_.offsets[v]; e < pt_.offsets[v + 1]; ++e)
          ox += pt_.values[e] * hu_[2 * pt_.columns[e]], oy += pt_.values[e] * hu_[2 * pt_.columns[e] + 1];
        const std::array<double, 3>& pc = precondition_[v];
        ox += damping_ * (pc[0] * d[2 * v] + pc[1] * d[2 * v + 1]), oy += damping_ * (pc[1] * d[2 * v] + pc[2] * d[2 * v + 1]);
      }
      out[2 * v] = ox, out[2 * v + 1] = oy;
    }
  }

  void preconditioned(const std::vector<double>& in, std::vector<double>& out) const {
    for (int v = 0; v < nv_; ++v) {
      const std::array<double, 3>& pc = precondition_[v];
      const double scale = 1 + damping_, a = scale * pc[0], b2 = scale * pc[1], d = scale * pc[2];
      const double det = a * d - b2 * b2;
      if (!movable_[v] || !(det > 0)) {
        out[2 * v] = out[2 * v + 1] = 0;
        continue;
      }
      out[2 * v] = (d * in[2 * v] - b2 * in[2 * v + 1]) / det;
      out[2 * v + 1] = (a * in[2 * v + 1] - b2 * in[2 * v]) / det;
    }
  }

  // Conjugate gradients from 0 on the residual r.
  std::vector<double> conjugate_gradients(std::vector<double> r) {
    std::vector<double> step(size_t(2) * nv_, 0.0), z(size_t(2) * nv_), dir(size_t(2) * nv_), ad(size_t(2) * nv_);
    preconditioned(r, z);
    dir = z;
    double rz = std::inner_product(r.begin(), r.end(), z.begin(), 0.0);
    for (int cg = 0; cg < options_.relocate_cg_iterations && rz > 0; ++cg) {
      apply(dir, ad);
      const double dad = std::inner_product(dir.begin(), dir.end(), ad.begin(), 0.0);
      if (!(dad > 0)) break;
      const double alpha = rz / dad;
      for (size_t i = 0; i < step.size(); ++i) step[i] += alpha * dir[i], r[i] -= alpha * ad[i];
      preconditioned(r, z);
      const double rz_next = std::inner_product(r.begin(), r.end(), z.begin(), 0.0);
      for (size_t i = 0; i < dir.size(); ++i) dir[i] = z[i] + rz_next / rz * dir[i];
      rz = rz_next;
    }
    return step;
  }

  // Moves from `before` by `step`, at most max_step px a vertex; a vertex of a triangle that would
  // flip or thin stays (all stay after 8 rounds).
  void move(const std::vector<Vec2>& before, const std::vector<double>& step) {
    std::vector<uint8_t> held(nv_, 0);
    for (int round = 0; round < 8; ++round) {
      for (int v = 0; v < nv_; ++v) {
        if (!movable_[v] || held[v]) {
          mesh_.positions[v] = before[v];
          continue;
        }
        double dx = step[2 * v], dy = step[2 * v + 1];
        const double len = std::hypot(dx, dy);
        if (len > options_.relocate_max_step) dx *= options_.relocate_max_step / len, dy *= options_.relocate_max_step / len;
        mesh_.positions[v] = {before[v].x + dx, before[v].y + dy};
      }
      bool bad = false;
      for (const Tri& t : mesh_.triangles) {
        const Vec2 a = mesh_.positions[t[0]], b = mesh_.positions[t[1]], q = mesh_.positions[t[2]];
        if (cross(b.x - a.x, b.y - a.y, q.x - a.x, q.y - a.y) > 2e-3) continue;
        bad = true;
        for (int32_t v : t) held[v] = 1;
      }
      if (!bad) break;
      if (round == 7) mesh_.positions = before;
    }
  }

  // The limit positions of the moved control vertices.
  void update_limit() {
    for (int j = 0; j < n_; ++j) {
      double lx = 0, ly = 0;
      for (SparseMatrix::InnerIterator e(p_, j); e; ++e) lx += e.value() * mesh_.positions[e.col()].x, ly += e.value() * mesh_.positions[e.col()].y;
      system_.limit[2 * j] = static_cast<float>(lx), system_.limit[2 * j + 1] = static_cast<float>(ly);
    }
  }

  ControlMesh& mesh_;
  FitSystem& system_;
  const ColorFitOptions& options_;
  const SparseMatrix& p_;
  const Rows pt_;
  const int n_, nv_, nt_;
  double damping_;
  std::vector<uint8_t> movable_;
  std::vector<std::array<double, 6>> gram_, gradient_;
  std::vector<std::array<double, 3>> tensor_, precondition_;
  std::vector<double> rhs_refined_, u_, hu_;
};

}  // namespace

int relocate_vertices(ControlMesh& mesh, const MeshTopology& topology, FitSystem& system,
                      const std::vector<Color>& start, const ColorFitOptions& options, Eigen::MatrixX3d& x) {
  return Relocator(mesh, topology, system, options).run(start, x);
}

}  // namespace subvec::fit_detail
