// Private helpers of the editing layer shared between its translation units.
#pragma once

#include "subvec/mesh/topology.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::edit_detail {

// Re-derives the face-varying color values of `mesh` from its tears (`topology`, built after the
// tears changed): each new value is the mean of the values its corners had. Where a new tear only
// splits groups of corners they agree, and each side keeps its value exactly; where a tear is gone
// the two sides' values merge into their mean.
void split_colors_at_tears(ControlMesh& mesh, const MeshTopology& topology);

}  // namespace subvec::edit_detail
