// Measures of rendered vector images for the pyramid's tests (tests/unit/pyramid) and its
// evaluation (bench/tools/levels_eval.cpp): how much high-frequency energy a filter leaves away
// from the features, and the contrast it keeps across them.
#pragma once

#include <cstdint>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::test {

// Per pixel of `image` (row-major), 1 when it lies farther than `margin` pixels from every feature
// polygon of level 0 (the limit curves stay within about a pixel of them), else 0.
std::vector<uint8_t> away_from_features(const VectorImage& image, double margin);

// Mean squared 5-point Laplacian of the RGB image `img` over the pixels that `mask` keeps (an
// interior pixel's channels summed).
double laplacian_energy(const Image8& img, const std::vector<uint8_t>& mask);

// laplacian_energy() of level 0 of `image` as rendered to about 1/16 of a color level rather than
// to whole levels: the mean of 16 renders whose control colors are all offset by
// (j + 1/2) / 16 - 1/2 (Loop subdivision reproduces constants, so each render is the same color
// field shifted). The 8-bit render alone gives a smooth field a floor of rounding noise that hides
// small differences.
double fine_laplacian_energy(const VectorImage& image, const std::vector<uint8_t>& mask);

// Mean color difference across feature `f` of `mesh` in `img`: points 1 px apart along its limit
// curve, sampled `offset` pixels to each side.
double contrast_across(const Image8& img, const ControlMesh& mesh, const Feature& f, double offset);

}  // namespace subvec::test
