// `subvec batch`: vectorizes every image of a folder (docs/cli.md). Registered by main(); runs as
// a CLI11 callback once the command line has parsed.
#pragma once

#include <CLI/CLI.hpp>

namespace subvec_cli {

void add_batch_command(CLI::App& app);

}  // namespace subvec_cli
