// Private to the library: the levels' collapse loop (levels.cpp), which vectorize() also uses to
// hold a vertex budget that the simplification's feature tolerance would exceed.
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "mesh/coarsen_p.h"
#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::detail {

// Greedy half-edge collapses by 5D quadric cost (colors scaled by `color_scale`) until `target`
// vertices remain. Kept chains stay within `tolerance` pixels of where they started; when nothing
// more can go, the tolerance doubles, up to `max_loosening` times its value, and the queue is
// planned afresh. Returns the collapses made, in order, and leaves `tolerance` at the last value
// used. Throws Error(kCancelled) when `cancel` is set.
std::vector<EdgeVerts> coarsen(coarsen_detail::Coarsener& c, int target, double& tolerance,
                               double max_loosening, double color_scale, int threads,
                               const std::atomic<bool>* cancel);

struct BudgetResult {
  // Pixels: how far the chains may be from their detected curves (`tolerance`, or `tolerance` plus
  // how far the budget let them move).
  double feature_tolerance = 0;
  std::vector<int32_t> dropped;  // ids of the features removed, least salient first
};

// Brings a simplified single-level mesh to at most `target` vertices when its features held it
// above (each chain within `tolerance` of the detected curve): first the chains may move up to 2
// times `tolerance` from where they are; then the least salient features (levels.h's saliency
// against `photo`, weight `saliency_weight`; the ids in `protected_ids` last) are dropped, their
// seams closed, a few at a time, until the budget holds. The colors are the merged means (the
// color fit comes next). Throws Error(kInvalidArgument) when even a mesh without features cannot
// get down to `target` ("a budget of N control vertices cannot be met: the image frame needs at
// least M control vertices").
BudgetResult hold_budget(ControlMesh& mesh, int width, int height, const Image8& photo, int target,
                         double tolerance, double saliency_weight, double color_scale,
                         const std::vector<int32_t>& protected_ids, int threads,
                         const std::atomic<bool>* cancel);

}  // namespace subvec::detail
