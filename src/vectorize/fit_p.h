// Private: the color fit's least-squares system (paper §4, "Color optimization"), shared by the
// fit's stages (fit.cpp), the vertex relocation (relocate.cpp) and the reference tests.
//
// With S the color limit stencils (refined color values = S * control colors) and B the sparse
// matrix that interpolates refined values at the fitted points, the fit solves
//     min_c |W^1/2 (B S c - t)|^2 + lambda |c - c0|^2
// through the normal equations S' (B'WB) S c = S' B'W t + lambda c0, with B'WB kept as 3x3 Gram
// blocks per refined triangle (pixel target) or a diagonal (refined-vertex target) and B'Wt per
// refined value.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>

#include "subvec/core/image.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/subdiv/subdivision.h"
#include "subvec/vectorize/fit.h"

namespace subvec::fit_detail {

// Sparse rows, CSR.
struct Rows {
  std::vector<int32_t> offsets{0}, columns;
  std::vector<double> values;
  int num_rows() const { return static_cast<int>(offsets.size()) - 1; }
};

// The transpose of s (rows x columns) as rows.
Rows transpose(const SparseMatrix& s);

// Where a pixel centre lies: a refined triangle and barycentric weights (1 - b1 - b2, b1, b2).
struct Location {
  int32_t triangle = -1;
  float b1 = 0, b2 = 0;
};

// A fitted pixel: its image index and target color.
struct PixelRow {
  int32_t pixel;
  std::array<float, 3> target;
};

// Channel k of the prediction at a located pixel: the refined triangle's values interpolated.
inline double predict(const Location& loc, const Tri& v, const Eigen::MatrixX3d& values, int k) {
  return (1.0 - loc.b1 - loc.b2) * values(v[0], k) + loc.b1 * values(v[1], k) + loc.b2 * values(v[2], k);
}

// The factorization of the normal equations, kept between the solves of one system: a reweighted
// solve has the same sparsity, so the fill-reducing ordering and the symbolic analysis are done
// once (the numbers, and so the solution, are those of a fresh factorization).
struct NormalSolver {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double, Eigen::ColMajor, int32_t>, Eigen::Lower> ldlt;
  std::vector<int32_t> offsets, columns;  // the analysed pattern
};

// The fit's state over one subdivision of the mesh.
struct FitSystem {
  FitSystem(const ControlMesh& mesh, const MeshTopology& topology, int width, int height, int depth);

  int width, height;
  Subdivision sub;
  const RefinedMesh& refined;  // sub's topology
  const SparseMatrix& s;       // color stencils, m x c
  int m, c;                    // refined and control color values
  Rows st;                     // s transposed
  std::vector<float> limit;    // limit positions of the refined vertices (x, y)
  std::vector<Location> located;   // per image pixel (pixel target)
  std::vector<PixelRow> rows;      // the fitted pixels, in pixel order (pixel target)
  std::vector<std::array<double, 6>> blocks;  // B'WB per refined triangle, packed 00 01 02 11 12 22
  std::vector<double> diagonal;                // B'WB as a diagonal (refined-vertex target)
  std::vector<std::array<double, 3>> btt;      // B'Wt per refined value
  mutable NormalSolver solver;                 // solve_colors()' factorization
};

// Stage 1: the fitted points. Pixel target: every located pixel centre, the band along the tears
// with targets hole-filled from its own side (§4.4); then B'B and B't. Refined-vertex target (the
// paper's): one row per refined value, sampled at its limit position.
void set_pixel_targets(FitSystem& system, const Image8& image, const ColorFitOptions& options,
                       ColorFitStats& stats);
void set_refined_vertex_targets(FitSystem& system, const Image8& image, ColorFitStats& stats);

// Locates every pixel centre in a refined triangle of the limit mesh (first one wins on shared
// edges). Returns the number of folded refined triangles, plus the number of pixels with a row that
// no triangle holds.
int locate_pixels(FitSystem& system);

// B'WB and B'Wt over the pixel rows (weights: one per row; empty: all 1).
void accumulate_pixels(FitSystem& system, const std::vector<double>& weights);

// Stage 2: the control colors (c x 3) from the normal equations, with the Tikhonov pull of relative
// weight `regularization` toward `start`.
Eigen::MatrixX3d solve_colors(const FitSystem& system, const std::vector<Color>& start, double regularization,
                              int threads);

// Sum over the pixel rows and channels of the squared residual of the refined values.
double squared_error(const FitSystem& system, const Eigen::MatrixX3d& values);

}  // namespace subvec::fit_detail
