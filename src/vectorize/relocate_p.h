// Private: vertex relocation inside the color fit (docs/vectorize.md, "Vertex relocation").
//
// Beyond the paper: the smooth control vertices move where the pixel residual asks, by damped
// Gauss-Newton steps on the squared error with the colors held, each kept only when it lowers the
// error; then the colors are refitted. The color field is carried by the surface: moving refined
// vertex j by e changes the prediction at a fixed pixel by -w_j g.e (w_j its barycentric weight, g
// the color gradient of the refined triangle), and refined vertex j moves by sum_v P_jv e_v (P the
// position stencils). Tear, crease, border and corner vertices stay, so the feature curves and the
// image border do not move. The normal equations P'HP are applied matrix-free in a few
// preconditioned conjugate-gradient iterations.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "subvec/mesh/topology.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/vectorize/fit.h"
#include "vectorize/fit_p.h"

namespace subvec::fit_detail {

// options.relocate_iterations steps on mesh.positions (and system's limit positions and pixel
// locations), refitting the colors x (from `start`, as solve_colors() does) every
// options.relocate_refit_every steps and after the last. Pixel target only. Returns the number of
// steps kept.
int relocate_vertices(ControlMesh& mesh, const MeshTopology& topology, FitSystem& system,
                      const std::vector<Color>& start, const ColorFitOptions& options, Eigen::MatrixX3d& x);

}  // namespace subvec::fit_detail
