// `subvec serve`: registered by the CLI's main() (apps/cli/main.cpp), run as a CLI11 callback.
#pragma once

#include <CLI/CLI.hpp>

namespace subvec_serve {

void add_serve_command(CLI::App& app);

}  // namespace subvec_serve
