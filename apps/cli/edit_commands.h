// The editing commands of `subvec`: edit (shape and color operations from an ops file) and
// stylize (strokes along features). Registered by main(); they run as CLI11 callbacks once the
// command line has parsed, and report failures by throwing like every other command.
#pragma once

#include <CLI/CLI.hpp>

namespace subvec_cli {

void add_edit_commands(CLI::App& app);

}  // namespace subvec_cli
