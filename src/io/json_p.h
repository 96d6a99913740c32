// Private: how error messages name the type of a JSON value, for the readers of .svec.json
// (io/svec_json.cpp) and of edit operations (edit/ops.cpp).
#pragma once

#include <nlohmann/json.hpp>

namespace subvec::detail {

// "a number" for any number, or with exact_numbers "an integer" and "a number with a fraction or
// exponent"; "a string", "a boolean", "null", "an array", "an object".
template <class Json>
const char* json_type_name(const Json& j, bool exact_numbers = false) {
  switch (j.type()) {
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
      return exact_numbers ? "an integer" : "a number";
    case Json::value_t::number_float:
      return exact_numbers ? "a number with a fraction or exponent" : "a number";
    case Json::value_t::string:
      return "a string";
    case Json::value_t::boolean:
      return "a boolean";
    case Json::value_t::null:
      return "null";
    case Json::value_t::array:
      return "an array";
    case Json::value_t::object:
      return "an object";
    default:
      return "an unsupported value";
  }
}

}  // namespace subvec::detail
