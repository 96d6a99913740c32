// The vector image pyramid on the command line (docs/cli.md, docs/levels.md): `subvec filter`.
// (The level options of `subvec vectorize` are in vectorize_options.h.)
#pragma once

#include <CLI/CLI.hpp>

namespace subvec_cli {

// `subvec filter`.
void add_pyramid_commands(CLI::App& app);

}  // namespace subvec_cli
