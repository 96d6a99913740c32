// Text helpers the commands share.
#pragma once

#include <algorithm>
#include <string>

namespace subvec_cli {

// Messages are printed on one line whatever they contain (and without trailing blanks).
inline std::string one_line(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

}  // namespace subvec_cli
