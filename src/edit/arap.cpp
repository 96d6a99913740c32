// As-rigid-as-possible deformation, Igarashi et al. 2005 (edit/arap.h has the design note).
#include "subvec/edit/arap.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "core/messages_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

using Sparse = Eigen::SparseMatrix<double>;
using Ldlt = Eigen::SimplicialLDLT<Sparse, Eigen::Lower, Eigen::AMDOrdering<int>>;
using Mat2 = Eigen::Matrix2d;
using V2 = Eigen::Vector2d;

[[noreturn]] void invalid(const std::string& message) { detail::invalid("ARAP: " + message); }

bool has(FixedAxes f, int axis) { return (static_cast<unsigned>(f) >> axis) & 1u; }

// The rotation by 90 degrees, R (x, y) = (-y, x).
const Mat2 kR90 = (Mat2() << 0, -1, 1, 0).finished();

// Rest triangle (i, j, k) in the frame of its edge (i, j): p_k = p_i + x d + y R90 d, d = p_j - p_i.
std::array<double, 2> local_coords(Vec2 pi, Vec2 pj, Vec2 pk) {
  const double dx = pj.x - pi.x, dy = pj.y - pi.y, qx = pk.x - pi.x, qy = pk.y - pi.y;
  const double d2 = dx * dx + dy * dy;
  return {(qx * dx + qy * dy) / d2, (qx * -dy + qy * dx) / d2};
}

double triangle_area(Vec2 a, Vec2 b, Vec2 c) {
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

double squared_distance(Vec2 a, Vec2 b) { return (b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y); }

// A symmetric system split by fixed / free unknowns: A_ff (factored) and A_fc.
struct ReducedSystem {
  std::vector<int32_t> free_of;   // unknown -> index among the free ones, or -1
  std::vector<int32_t> fixed_of;  // unknown -> index among the fixed ones, or -1
  int num_free = 0, num_fixed = 0;
  Ldlt ldlt;
  Sparse a_fc;

  // `full` is the symmetric matrix over all unknowns; `is_fixed` per unknown.
  void build(const Sparse& full, const std::vector<uint8_t>& is_fixed, const char* what) {
    const int n = static_cast<int>(is_fixed.size());
    free_of.assign(n, -1);
    fixed_of.assign(n, -1);
    num_free = num_fixed = 0;
    for (int u = 0; u < n; ++u) (is_fixed[u] ? fixed_of[u] = num_fixed++ : free_of[u] = num_free++);
    std::vector<Eigen::Triplet<double>> ff, fc;
    for (int col = 0; col < full.outerSize(); ++col) {
      for (Sparse::InnerIterator it(full, col); it; ++it) {
        const int row = static_cast<int>(it.row());
        if (free_of[row] < 0) continue;
        if (free_of[col] >= 0) {
          if (row >= col) ff.emplace_back(free_of[row], free_of[col], it.value());
        } else {
          fc.emplace_back(free_of[row], fixed_of[col], it.value());
        }
      }
    }
    a_fc.resize(num_free, num_fixed);
    a_fc.setFromTriplets(fc.begin(), fc.end());
    if (num_free == 0) return;
    Sparse a_ff(num_free, num_free);
    a_ff.setFromTriplets(ff.begin(), ff.end());
    ldlt.compute(a_ff);
    if (ldlt.info() != Eigen::Success) {
      invalid(std::string("the ") + what + " system is singular: the constraints do not pin the mesh");
    }
  }

  // Solves A_ff x_f = b_f - A_fc x_c for the free unknowns of `x` (b over all unknowns, or empty
  // for zero).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
    if (num_free == 0) return;
    Eigen::VectorXd xc(num_fixed), rhs(num_free);
    const int n = static_cast<int>(free_of.size());
    for (int u = 0; u < n; ++u) {
      if (fixed_of[u] >= 0) xc[fixed_of[u]] = x[u];
      else rhs[free_of[u]] = b.size() ? b[u] : 0.0;
    }
    rhs -= a_fc * xc;
    const Eigen::VectorXd xf = ldlt.solve(rhs);
    for (int u = 0; u < n; ++u)
      if (free_of[u] >= 0) x[u] = xf[free_of[u]];
  }
};

}  // namespace

struct ArapDeformer::Impl {
  std::vector<Vec2> rest;
  std::vector<Tri> triangles;
  std::vector<FixedAxes> fixed;
  ReducedSystem similarity;  // 2#V unknowns, interleaved (x0, y0, x1, y1, ...)
  ReducedSystem scale[2];    // #V unknowns, per axis
  // Step 2 fit per triangle: (w_0, w_1) = F (v'_0, v'_1, v'_2), and the rest frame of vertex 2.
  std::vector<Eigen::Matrix<double, 4, 6>> fit;
  std::vector<std::array<double, 3>> frame;  // x, y, rest length of edge (0, 1)
  std::vector<double> weight;                // per triangle, in step 2 (arap.h)

  void check_targets(std::span<const Vec2> targets, std::span<Vec2> out) const {
    if (targets.size() != rest.size() || out.size() != rest.size()) {
      invalid(std::to_string(targets.size()) + " targets and " + std::to_string(out.size()) +
              " outputs for " + std::to_string(rest.size()) + " vertices");
    }
    for (size_t v = 0; v < rest.size(); ++v) {
      for (int axis = 0; axis < 2; ++axis) {
        const double t = axis ? targets[v].y : targets[v].x;
        if (has(fixed[v], axis) && !std::isfinite(t)) {
          invalid("target of vertex " + std::to_string(v) + " is not finite");
        }
      }
    }
  }

  // Step 2's solve, per axis: the positions whose edges best match the right-hand sides `b`, with
  // the fixed coordinates from `targets` (copied to `out` bit for bit).
  void solve_edges(const Eigen::VectorXd (&b)[2], std::span<const Vec2> targets, std::span<Vec2> out) const {
    const size_t n = rest.size();
    for (int axis = 0; axis < 2; ++axis) {
      Eigen::VectorXd x(static_cast<Eigen::Index>(n));
      for (size_t v = 0; v < n; ++v) x[Eigen::Index(v)] = axis ? targets[v].y : targets[v].x;
      scale[axis].solve(b[axis], x);
      for (size_t v = 0; v < n; ++v) {
        double& o = axis ? out[v].y : out[v].x;
        o = has(fixed[v], axis) ? (axis ? targets[v].y : targets[v].x) : x[Eigen::Index(v)];
      }
    }
  }

  Eigen::VectorXd step1(std::span<const Vec2> targets) const {
    const size_t n = rest.size();
    Eigen::VectorXd x(2 * n);
    for (size_t v = 0; v < n; ++v) x[2 * v] = targets[v].x, x[2 * v + 1] = targets[v].y;
    similarity.solve(Eigen::VectorXd(), x);
    return x;
  }
};

ArapDeformer::ArapDeformer(std::span<const Vec2> rest, std::span<const Tri> triangles,
                           std::span<const FixedAxes> fixed)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const int n = static_cast<int>(rest.size());
  if (fixed.size() != rest.size()) {
    invalid(std::to_string(fixed.size()) + " constraint flags for " + std::to_string(n) +
            " vertices");
  }
  m.rest.assign(rest.begin(), rest.end());
  m.triangles.assign(triangles.begin(), triangles.end());
  m.fixed.assign(fixed.begin(), fixed.end());
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    for (int32_t v : t)
      if (v < 0 || v >= n) invalid("triangle " + std::to_string(f) + " refers to vertex " + std::to_string(v) + ", out of range");
    const Vec2 a = rest[t[0]], b = rest[t[1]], c = rest[t[2]];
    const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (!(area2 > 0)) invalid("rest triangle " + std::to_string(f) + " is flipped or degenerate");
  }

  // Every edge-connected part of the mesh needs its similarities pinned: the fixed coordinates,
  // as rows of the 4-column similarity basis (tx, ty, a, b) -> t + a p + b R90 p, must have rank 4.
  {
    std::vector<int32_t> parent(triangles.size());
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    std::vector<std::pair<int64_t, int32_t>> edges;
    for (size_t f = 0; f < triangles.size(); ++f) {
      for (int k = 0; k < 3; ++k) {
        int64_t a = triangles[f][k], b = triangles[f][(k + 1) % 3];
        if (a > b) std::swap(a, b);
        edges.emplace_back(a << 32 | b, static_cast<int32_t>(f));
      }
    }
    std::sort(edges.begin(), edges.end());
    for (size_t i = 1; i < edges.size(); ++i)
      if (edges[i].first == edges[i - 1].first) parent[find(edges[i].second)] = find(edges[i - 1].second);
    std::vector<int32_t> part_of_vertex(n, -1);
    std::vector<std::vector<int32_t>> parts_vertices(triangles.size());
    for (size_t f = 0; f < triangles.size(); ++f) {
      const int32_t p = find(static_cast<int32_t>(f));
      for (int32_t v : triangles[f]) parts_vertices[p].push_back(v);
    }
    for (auto& vs : parts_vertices) {
      if (vs.empty()) continue;
      std::sort(vs.begin(), vs.end());
      vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
      double cx = 0, cy = 0, scale = 0;
      for (int32_t v : vs) cx += rest[v].x, cy += rest[v].y;
      cx /= double(vs.size()), cy /= double(vs.size());
      for (int32_t v : vs) scale = std::max({scale, std::abs(rest[v].x - cx), std::abs(rest[v].y - cy)});
      scale = scale > 0 ? scale : 1;
      Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
      for (int32_t v : vs) {
        const double px = (rest[v].x - cx) / scale, py = (rest[v].y - cy) / scale;
        if (has(fixed[v], 0)) {
          const Eigen::Vector4d r(1, 0, px, -py);
          normal += r * r.transpose();
        }
        if (has(fixed[v], 1)) {
          const Eigen::Vector4d r(0, 1, py, px);
          normal += r * r.transpose();
        }
      }
      const Eigen::Vector4d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(normal).eigenvalues();
      if (!(eig[0] > 1e-9 * std::max(eig[3], 1.0))) {
        invalid("the constraints do not pin the part of the mesh around vertex " +
                std::to_string(vs.front()) +
                ": fix at least two vertices (both coordinates), or enough coordinates to rule out "
                "a translation, rotation and scaling");
      }
    }
  }

  // Step 1: E1 = sum |A v|^2 with A the 2x6 block of each (triangle, opposite vertex).
  std::vector<Eigen::Triplet<double>> g;
  g.reserve(triangles.size() * 3 * 36);
  const Mat2 id = Mat2::Identity();
  m.weight.resize(triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    const double area = triangle_area(rest[t[0]], rest[t[1]], rest[t[2]]);
    double sum = 0;
    for (int r = 0; r < 3; ++r) {
      const int i = t[r], j = t[(r + 1) % 3], k = t[(r + 2) % 3];
      const auto [x, y] = local_coords(rest[i], rest[j], rest[k]);
      const Mat2 c[3] = {-((1 - x) * id - y * kR90), -(x * id + y * kR90), id};
      const int vs[3] = {i, j, k};
      const double base2 = squared_distance(rest[i], rest[j]);
      const double w = base2 / (4 * area);  // = A / h_k^2, h_k the height of k (arap.h)
      sum += w;
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          const Mat2 block = w * c[a].transpose() * c[b];
          for (int p = 0; p < 2; ++p)
            for (int q = 0; q < 2; ++q) g.emplace_back(2 * vs[a] + p, 2 * vs[b] + q, block(p, q));
        }
      }
    }
    m.weight[f] = sum / 3;
  }
  Sparse big(2 * n, 2 * n);
  big.setFromTriplets(g.begin(), g.end());
  std::vector<uint8_t> is_fixed(2 * size_t(n));
  for (int v = 0; v < n; ++v) is_fixed[2 * v] = has(fixed[v], 0), is_fixed[2 * v + 1] = has(fixed[v], 1);
  m.similarity.build(big, is_fixed, "similarity");

  // Step 2: the edge Laplacian (each edge once per triangle it bounds), shared by both axes.
  std::vector<Eigen::Triplet<double>> h;
  h.reserve(triangles.size() * 12);
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    const double w = m.weight[f];
    for (int r = 0; r < 3; ++r) {
      const int a = t[r], b = t[(r + 1) % 3];
      h.emplace_back(a, a, w), h.emplace_back(b, b, w);
      h.emplace_back(a, b, -w), h.emplace_back(b, a, -w);
    }
  }
  Sparse lap(n, n);
  lap.setFromTriplets(h.begin(), h.end());
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<uint8_t> axis_fixed(n);
    for (int v = 0; v < n; ++v) axis_fixed[v] = has(fixed[v], axis);
    m.scale[axis].build(lap, axis_fixed, "scale adjustment");
  }

  // Step 2 fit: minimise |w_i - v'_i|^2 over the 3 corners, with w_2 = (1-x) w_0 + x w_1 + y R90 (w_1 - w_0).
  m.fit.resize(triangles.size());
  m.frame.resize(triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    const auto [x, y] = local_coords(rest[t[0]], rest[t[1]], rest[t[2]]);
    Eigen::Matrix<double, 6, 4> mm = Eigen::Matrix<double, 6, 4>::Zero();
    mm.block<2, 2>(0, 0) = id;
    mm.block<2, 2>(2, 2) = id;
    mm.block<2, 2>(4, 0) = (1 - x) * id - y * kR90;
    mm.block<2, 2>(4, 2) = x * id + y * kR90;
    const Eigen::Matrix4d normal = mm.transpose() * mm;
    m.fit[f] = normal.inverse() * mm.transpose();
    m.frame[f] = {x, y, std::hypot(rest[t[1]].x - rest[t[0]].x, rest[t[1]].y - rest[t[0]].y)};
  }
}

ArapDeformer::~ArapDeformer() = default;
ArapDeformer::ArapDeformer(ArapDeformer&&) noexcept = default;
ArapDeformer& ArapDeformer::operator=(ArapDeformer&&) noexcept = default;

int ArapDeformer::num_vertices() const { return static_cast<int>(impl_->rest.size()); }
const std::vector<FixedAxes>& ArapDeformer::fixed() const { return impl_->fixed; }

void ArapDeformer::solve_similarity(std::span<const Vec2> targets, std::span<Vec2> out) const {
  const Impl& m = *impl_;
  m.check_targets(targets, out);
  const Eigen::VectorXd x = m.step1(targets);
  for (size_t v = 0; v < m.rest.size(); ++v) {
    out[v] = {has(m.fixed[v], 0) ? targets[v].x : x[2 * v],
              has(m.fixed[v], 1) ? targets[v].y : x[2 * v + 1]};
  }
}

void ArapDeformer::solve(std::span<const Vec2> targets, std::span<Vec2> out,
                         std::span<Vec2> similarity) const {
  const Impl& m = *impl_;
  m.check_targets(targets, out);
  const Eigen::VectorXd s1 = m.step1(targets);
  const size_t n = m.rest.size();
  if (!similarity.empty()) {
    if (similarity.size() != n) invalid("the similarity output has the wrong size");
    for (size_t v = 0; v < n; ++v) {
      similarity[v] = {has(m.fixed[v], 0) ? targets[v].x : s1[2 * v],
                       has(m.fixed[v], 1) ? targets[v].y : s1[2 * v + 1]};
    }
  }

  // Fit each rest triangle to the step-1 triangle by a similarity, scale it back to rest size, and
  // accumulate the right-hand sides of E2 from its edge vectors.
  Eigen::VectorXd b[2] = {Eigen::VectorXd::Zero(Eigen::Index(n)), Eigen::VectorXd::Zero(Eigen::Index(n))};
  for (size_t f = 0; f < m.triangles.size(); ++f) {
    const Tri& t = m.triangles[f];
    Eigen::Matrix<double, 6, 1> v;
    for (int k = 0; k < 3; ++k) v[2 * k] = s1[2 * t[k]], v[2 * k + 1] = s1[2 * t[k] + 1];
    const Eigen::Vector4d w01 = m.fit[f] * v;
    const auto [x, y, rest_length] = m.frame[f];
    const V2 w0 = w01.head<2>(), w1 = w01.tail<2>();
    const V2 w2 = w0 + x * (w1 - w0) + y * (kR90 * (w1 - w0));
    const double fitted = (w1 - w0).norm();
    const double s = fitted > 0 ? rest_length / fitted : 1.0;
    const V2 w[3] = {w0, w1, w2};
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], c = t[(k + 1) % 3];
      const V2 e = m.weight[f] * s * (w[(k + 1) % 3] - w[k]);
      for (int axis = 0; axis < 2; ++axis) b[axis][a] -= e[axis], b[axis][c] += e[axis];
    }
  }
  m.solve_edges(b, targets, out);
}

double ArapDeformer::rigid_step(std::span<const Vec2> targets, std::span<const Vec2> current,
                                std::span<Vec2> out) const {
  const Impl& m = *impl_;
  m.check_targets(targets, out);
  const size_t n = m.rest.size();
  if (current.size() != n) invalid("the current positions have the wrong size");
  Eigen::VectorXd b[2] = {Eigen::VectorXd::Zero(Eigen::Index(n)), Eigen::VectorXd::Zero(Eigen::Index(n))};
  double energy = 0;
  for (size_t f = 0; f < m.triangles.size(); ++f) {
    const Tri& t = m.triangles[f];
    V2 p[3], q[3];
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], c = t[(k + 1) % 3];
      p[k] = {m.rest[c].x - m.rest[a].x, m.rest[c].y - m.rest[a].y};
      q[k] = {current[c].x - current[a].x, current[c].y - current[a].y};
    }
    // The best rotation maximises sum q . (R p): its angle is atan2(S10 - S01, S00 + S11) with
    // S = sum q p^T.
    Mat2 s = Mat2::Zero();
    for (int k = 0; k < 3; ++k) s += q[k] * p[k].transpose();
    const double angle = std::atan2(s(1, 0) - s(0, 1), s(0, 0) + s(1, 1));
    const double cs = std::cos(angle), sn = std::sin(angle);
    const Mat2 r = (Mat2() << cs, -sn, sn, cs).finished();
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], c = t[(k + 1) % 3];
      const V2 e = r * p[k];
      energy += m.weight[f] * (q[k] - e).squaredNorm();
      for (int axis = 0; axis < 2; ++axis) {
        b[axis][a] -= m.weight[f] * e[axis], b[axis][c] += m.weight[f] * e[axis];
      }
    }
  }
  m.solve_edges(b, targets, out);
  return energy;
}

void ArapDeformer::precondition(std::span<const Vec2> gradient, std::span<Vec2> direction) const {
  const Impl& m = *impl_;
  const size_t n = m.rest.size();
  if (gradient.size() != n || direction.size() != n) invalid("precondition: wrong sizes");
  for (int axis = 0; axis < 2; ++axis) {
    Eigen::VectorXd b(static_cast<Eigen::Index>(n)), x(static_cast<Eigen::Index>(n));
    for (size_t v = 0; v < n; ++v) {
      b[Eigen::Index(v)] = -(axis ? gradient[v].y : gradient[v].x);
      x[Eigen::Index(v)] = axis ? direction[v].y : direction[v].x;
    }
    m.scale[axis].solve(b, x);
    for (size_t v = 0; v < n; ++v) {
      if (!has(m.fixed[v], axis)) (axis ? direction[v].y : direction[v].x) = x[Eigen::Index(v)];
    }
  }
}

double rigidity_energy(std::span<const Vec2> rest, std::span<const Vec2> deformed,
                       std::span<const Tri> triangles) {
  if (rest.size() != deformed.size()) {
    throw Error(ErrorCode::kInvalidArgument, "rigidity_energy: " + std::to_string(rest.size()) +
                                                 " rest and " + std::to_string(deformed.size()) +
                                                 " deformed positions");
  }
  double energy = 0;
  for (const Tri& t : triangles) {
    // Best rotation: maximise sum e'.(R e); with S = sum e' e^T, R has angle atan2(S10 - S01, S00 + S11).
    V2 p[3], q[3];
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = rest[t[k]], b = rest[t[(k + 1) % 3]];
      const Vec2 c = deformed[t[k]], d = deformed[t[(k + 1) % 3]];
      p[k] = {b.x - a.x, b.y - a.y};
      q[k] = {d.x - c.x, d.y - c.y};
    }
    Mat2 s = Mat2::Zero();
    for (int k = 0; k < 3; ++k) s += q[k] * p[k].transpose();
    const double angle = std::atan2(s(1, 0) - s(0, 1), s(0, 0) + s(1, 1));
    const Mat2 r = (Mat2() << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle)).finished();
    for (int k = 0; k < 3; ++k) energy += (q[k] - r * p[k]).squaredNorm();
  }
  return energy;
}

}  // namespace subvec
