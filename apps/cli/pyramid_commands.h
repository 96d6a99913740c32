// Levels of abstraction and the vector image pyramid on the command line (docs/cli.md,
// docs/levels.md): the level options of `subvec vectorize` and the `subvec filter` command.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "subvec/core/image.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/vectorize/levels.h"

namespace subvec_cli {

struct LevelArgs {
  int levels = 3;
  double saliency_weight = 2;
  double reduction = 0.5;
  std::vector<std::string> feature_levels;  // ID=L
};

// Adds --levels, --saliency-weight, --level-reduction and --feature-level to `vectorize`.
void add_level_options(CLI::App* vectorize, LevelArgs& args);

// Builds the levels of `image` (vectorized from `photo`) as the arguments ask and stores every
// feature's saliency (also with one level).
subvec::LevelReport build_levels(const LevelArgs& args, subvec::VectorImage& image,
                                 const subvec::Image8& photo);

// `subvec filter`.
void add_pyramid_commands(CLI::App& app);

}  // namespace subvec_cli
