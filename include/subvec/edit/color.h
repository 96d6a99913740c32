// Color editing (paper §6.2): BLEND and TRANSFORM over a selection of color values
// (edit/selection.h). Both act on control color values only, so the edit is as smooth as the
// image: subdivision blends it into the unselected neighbours over about one control edge, and
// stops it at the tears the selection did not cross.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "subvec/mesh/vector_image.h"

namespace subvec {

// BLEND: c <- (1 - amount) c + amount * target for every selected color value, amount in [0, 1].
// The variation inside the selection is kept, scaled by (1 - amount); amount 0 changes nothing
// (bit for bit), amount 1 paints the selection flat. Throws Error(kInvalidArgument) for an amount
// outside [0, 1], a non-finite target or an index out of range.
void blend_colors(ControlMesh& mesh, std::span<const int32_t> colors, Color target, double amount);

// TRANSFORM: the diagonal 3x3 transform M = diag(target / seed) that maps the seed's color to
// `target` is applied to every selected color value, c <- M c. Per-channel ratios between the
// selected values are kept exactly (each channel is scaled by one factor). Throws
// Error(kInvalidArgument) when a channel of `seed` is not positive (no diagonal transform maps 0 to
// a non-zero value: use BLEND there), for a non-finite or negative target, or an index out of
// range. Returns the three factors.
std::array<double, 3> transform_colors(ControlMesh& mesh, std::span<const int32_t> colors,
                                       Color seed, Color target);

}  // namespace subvec
