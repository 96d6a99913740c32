// CLI11 validators for numeric options, shared by the commands. Each accepts only finite numbers
// and its error says what it expected and what it got ("expected a positive number, got '0'").
// Ranges of the library's parameter structs are not checked here but by the library (e.g.
// subvec::validate(VectorizeOptions), vectorize_options.h).
#pragma once

#include <CLI/CLI.hpp>

namespace subvec_cli {

CLI::Validator finite_number();    // any finite number
CLI::Validator positive_number();  // > 0
CLI::Validator integer();          // an int (its range is the library's check)

}  // namespace subvec_cli
