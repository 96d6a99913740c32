#include "validators.h"

#include <cmath>
#include <functional>
#include <string>

namespace subvec_cli {
namespace {

// A finite number for which `accept` holds; otherwise "expected <expected>, got '<text>'".
CLI::Validator number_check(std::function<bool(double)> accept, const std::string& expected,
                            const std::string& description, const std::string& name) {
  return CLI::Validator(
      [accept = std::move(accept), expected](std::string& text) {
        double v = 0;
        const bool ok = CLI::detail::lexical_cast(text, v) && std::isfinite(v) && accept(v);
        return ok ? std::string() : "expected " + expected + ", got '" + text + "'";
      },
      description, name);
}

}  // namespace

CLI::Validator finite_number() {
  return number_check([](double) { return true; }, "a number", "NUMBER", "finite");
}

CLI::Validator positive_number() {
  return number_check([](double v) { return v > 0; }, "a positive number", "POSITIVE", "positive");
}

CLI::Validator integer() {
  return CLI::Validator(
      [](std::string& text) {
        int v = 0;
        return CLI::detail::lexical_cast(text, v) ? std::string() : "expected an integer, got '" + text + "'";
      },
      "INT", "integer");
}

}  // namespace subvec_cli
