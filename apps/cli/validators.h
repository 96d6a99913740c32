// CLI11 validators for numeric options, shared by the commands. Each accepts only finite numbers
// and its error says what it expected and what it got ("expected a positive number, got '0'").
#pragma once

#include <CLI/CLI.hpp>

namespace subvec_cli {

CLI::Validator finite_number();                  // any finite number
CLI::Validator positive_number();                // > 0
CLI::Validator fraction();                       // in (0, 1]
CLI::Validator number_in(double lo, double hi);  // in [lo, hi]

}  // namespace subvec_cli
