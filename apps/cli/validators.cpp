#include "validators.h"

#include <cmath>
#include <functional>
#include <sstream>
#include <string>

namespace subvec_cli {
namespace {

std::string text_of(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

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

CLI::Validator fraction() {
  return number_check([](double v) { return v > 0 && v <= 1; }, "a number in (0, 1]", "RATIO", "ratio");
}

CLI::Validator number_in(double lo, double hi) {
  const std::string range = "[" + text_of(lo) + ", " + text_of(hi) + "]";
  return number_check([lo, hi](double v) { return v >= lo && v <= hi; }, "a number in " + range,
                      "FLOAT in [" + text_of(lo) + " - " + text_of(hi) + "]", "number_in");
}

}  // namespace subvec_cli
