// The vectorization options that `subvec vectorize` and `subvec batch` share, registered and
// turned into the library's parameter structs in one place, so that batch makes what vectorize
// makes with the same options (tests/python/test_batch.py checks that the files are identical).
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "pyramid_commands.h"
#include "subvec/vectorize/vectorize.h"

namespace subvec_cli {

struct VectorizeParams {
  double ratio = 0.01;
  int vertices = 0;
  std::string fit = "pixels";  // pixels or vertices (checked by CLI11)
  std::string segment;         // X,Y,W,H, or empty
  int grid_step = 0;           // 0: automatic
  int l1_iterations = 0;
  int relocate = 0;            // Gauss-Newton relocation steps (--relocate)
  int refine = subvec::RefineOptions{}.rounds;  // --refine rounds
  subvec::FeatureOptions features;  // --edge-*, --min-feature-length, --spur-length, --max-gap
  double max_feature_error = 1.0;   // --max-feature-error
  int threads = 0;  // 0: all cores; the output does not depend on it
  LevelArgs levels;  // --levels, --saliency-weight, ... (pyramid_commands.h)
};

// Adds --ratio and --vertices (one or the other) to `command`.
void add_vertex_count_options(CLI::App* command, VectorizeParams& params);

// Adds the options that shape the result (--fit, --l1-iterations, --relocate, --refine, --grid-step, the
// feature detector's and --max-feature-error), with the library's defaults and ranges.
void add_quality_options(CLI::App* command, VectorizeParams& params);

// Parses "X,Y,W,H" (integers); returns an error message, or "" and fills `r`. Whether the
// rectangle lies inside the image is the library's check, once the image is read.
std::string parse_rect(const std::string& text, subvec::PixelRect& r);

// The library's options for `params` (a valid --segment; no progress callback).
subvec::VectorizeOptions vectorize_options(const VectorizeParams& params);

}  // namespace subvec_cli
