// The color fit's normal equations (vectorize/fit_p.h) against a plain least-squares solve: the
// design matrix A = B S built densely from the fit's pixel locations (B: barycentric weights of
// each fitted pixel's refined triangle) and the refined color stencils (S), solved by Householder
// QR with the Tikhonov rows appended. The fast path never forms A: it assembles B'B as Gram blocks
// on the refined values, multiplies through S row by row and factors the lower triangle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "subvec/vectorize/fit.h"
#include "support/test_meshes.h"
#include "vectorize/fit_p.h"

namespace subvec {
namespace {

using fit_detail::FitSystem;

// A smooth field with a step and a deterministic ripple, so that the fit has residuals.
Image8 test_image(int width, int height) {
  Image8 image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double r = 40 + 6 * x + 50 * std::sin(0.7 * y) + (x > width / 2 ? 60 : 0);
      const double g = 200 - 5 * y + 30 * std::cos(0.9 * x + 0.4 * y);
      const double b = 128 + 90 * std::sin(0.31 * x * y);
      uint8_t* p = image.row(y) + size_t(x) * 3;
      p[0] = static_cast<uint8_t>(std::clamp(r, 0.0, 255.0));
      p[1] = static_cast<uint8_t>(std::clamp(g, 0.0, 255.0));
      p[2] = static_cast<uint8_t>(std::clamp(b, 0.0, 255.0));
    }
  }
  return image;
}

// The plain solve of min_c |W^1/2 (B S c - t)|^2 + lambda |c - c0|^2 with lambda as the fit scales
// it (regularization times the mean diagonal of the normal matrix).
Eigen::MatrixX3d reference_solve(const FitSystem& system, const std::vector<Color>& start, double regularization,
                                 const std::vector<double>& weights) {
  const Eigen::MatrixXd s = system.s.toDense();
  const int n = static_cast<int>(system.rows.size()), c = system.c;
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(n, system.m);
  Eigen::MatrixX3d t(n, 3);
  for (int r = 0; r < n; ++r) {
    const fit_detail::PixelRow& row = system.rows[r];
    const fit_detail::Location& loc = system.located[row.pixel];
    const Tri& v = system.refined.triangle_colors[loc.triangle];
    const double sw = weights.empty() ? 1.0 : std::sqrt(weights[r]);
    const double w[3] = {1.0 - loc.b1 - loc.b2, loc.b1, loc.b2};
    for (int k = 0; k < 3; ++k) b(r, v[k]) += sw * w[k];
    for (int k = 0; k < 3; ++k) t(r, k) = sw * row.target[k];
  }
  const Eigen::MatrixXd a = b * s;
  const double lambda = regularization * std::max(a.squaredNorm() / c, 1e-12);
  Eigen::MatrixXd stacked(n + c, c);
  stacked << a, std::sqrt(lambda) * Eigen::MatrixXd::Identity(c, c);
  Eigen::MatrixX3d rhs(n + c, 3);
  rhs.topRows(n) = t;
  for (int i = 0; i < c; ++i) rhs.row(n + i) << start[i].r, start[i].g, start[i].b;
  rhs.bottomRows(c) *= std::sqrt(lambda);
  return stacked.householderQr().solve(rhs);
}

// Rounding to float moves a value by at most half a float step (2^-24 relative); a little more
// allows for the fast solve's own last digits.
double float_tolerance(double v) { return 7e-8 * std::max(1.0, std::abs(v)); }

struct Case {
  testing::TestMesh mesh;
  int depth;
};

std::vector<Case> cases() {
  // A tear (band pixels with hole-filled targets, two values per tear vertex), a closed tear, and
  // a plain grid refined deep enough (more than 1024 refined values) for the threaded row builds.
  return {{testing::open_tear(), 2}, {testing::torn_disk(), 2}, {testing::grid_mesh(6, 5, 4.0, true), 3}};
}

TEST(ColorFitReference, NormalEquationsMatchAPlainLeastSquaresSolve) {
  for (const Case& k : cases()) {
    for (int threads : {1, 4}) {
      const testing::TestMesh& m = k.mesh;
      const Image8 image = test_image(m.width, m.height);
      ColorFitOptions options;
      options.threads = threads;
      const MeshTopology topology = m.topology();
      FitSystem system(m.mesh, topology, m.width, m.height, k.depth);
      ColorFitStats stats;
      fit_detail::set_pixel_targets(system, image, options, stats);
      ASSERT_GT(stats.rows, system.c) << m.name;  // more pixels than unknowns
      if (!m.mesh.features.empty()) {
        EXPECT_GT(stats.filled, 0) << m.name;
      }
      if (k.depth == 3) {
        EXPECT_GT(system.m, 1024) << m.name;
      }
      for (const double regularization : {1e-6, 1e-2}) {
        const Eigen::MatrixX3d fast = fit_detail::solve_colors(system, m.mesh.colors, regularization, threads);
        const Eigen::MatrixX3d slow = reference_solve(system, m.mesh.colors, regularization, {});
        ASSERT_EQ(fast.rows(), slow.rows());
        EXPECT_LT((fast - slow).cwiseAbs().maxCoeff(), 1e-9)
            << m.name << " threads " << threads << " regularization " << regularization;
      }
      // Weighted rows, as the L1 reweighting makes them.
      std::vector<double> weights(system.rows.size());
      for (size_t r = 0; r < weights.size(); ++r) weights[r] = 0.2 + double((r * 7919) % 13) / 4;
      fit_detail::accumulate_pixels(system, weights);
      const Eigen::MatrixX3d fast = fit_detail::solve_colors(system, m.mesh.colors, 1e-6, threads);
      const Eigen::MatrixX3d slow = reference_solve(system, m.mesh.colors, 1e-6, weights);
      EXPECT_LT((fast - slow).cwiseAbs().maxCoeff(), 1e-9) << m.name << " weighted, threads " << threads;
    }
  }
}

TEST(ColorFitReference, FitColorsStoresThePlainSolution) {
  const testing::TestMesh m = testing::open_tear();
  const Image8 image = test_image(m.width, m.height);
  ColorFitOptions options;
  options.depth = 2;
  options.l1_iterations = 0;  // the plain least-squares solution (one reweighting is the default)
  const MeshTopology topology = m.topology();
  FitSystem system(m.mesh, topology, m.width, m.height, options.depth);
  ColorFitStats expected;
  fit_detail::set_pixel_targets(system, image, options, expected);
  const Eigen::MatrixX3d slow = reference_solve(system, m.mesh.colors, options.regularization, {});
  ControlMesh fitted = m.mesh;
  const ColorFitStats stats = fit_colors(fitted, m.width, m.height, image, options);
  EXPECT_EQ(stats.rows, expected.rows);
  EXPECT_EQ(stats.filled, expected.filled);
  ASSERT_EQ(fitted.colors.size(), size_t(slow.rows()));
  for (size_t i = 0; i < fitted.colors.size(); ++i) {
    EXPECT_NEAR(fitted.colors[i].r, slow(Eigen::Index(i), 0), float_tolerance(slow(Eigen::Index(i), 0))) << i;
    EXPECT_NEAR(fitted.colors[i].g, slow(Eigen::Index(i), 1), float_tolerance(slow(Eigen::Index(i), 1))) << i;
    EXPECT_NEAR(fitted.colors[i].b, slow(Eigen::Index(i), 2), float_tolerance(slow(Eigen::Index(i), 2))) << i;
  }
}

}  // namespace
}  // namespace subvec
