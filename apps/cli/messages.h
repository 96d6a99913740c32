// Text helpers the commands share.
#pragma once

#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

namespace subvec_cli {

// Messages are printed on one line whatever they contain (and without trailing blanks).
inline std::string one_line(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

// "Value 0 not in range" -> "value 0 not in range"; "PNG ..." stays (a capital that is not a word's
// only one).
inline std::string lower_first(std::string s) {
  if (s.size() >= 2 && std::isupper(static_cast<unsigned char>(s[0])) &&
      std::islower(static_cast<unsigned char>(s[1])))
    s[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(s[0])));
  return s;
}

// Edits (insert, delete, substitute, swap two neighbours) from `a` to `b`.
inline size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    for (size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1])});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

// The name in `names` closest to a mistyped `word` ("--jsn" -> "--json", "rendr" -> "render"), or
// "" when none is close: at most 1 edit for words of 2 to 4 letters, 2 for longer ones, or the
// only name that `word` (3 letters or more, dashes aside) begins; none for one letter.
inline std::string closest_name(const std::string& word, const std::vector<std::string>& names) {
  const size_t letters = word.size() - std::min(word.find_first_not_of('-'), word.size());
  if (letters < 2) return "";  // "-x": any one-letter option is one edit away
  const size_t limit = letters <= 4 ? 1 : 2;
  std::string best;
  size_t best_distance = limit + 1;
  for (const std::string& name : names) {
    const size_t d = edit_distance(word, name);
    if (d < best_distance) best = name, best_distance = d;
  }
  if (!best.empty() || letters < 3) return best;
  std::string prefixed;
  for (const std::string& name : names) {
    if (name.rfind(word, 0) != 0) continue;
    if (!prefixed.empty()) return "";
    prefixed = name;
  }
  return prefixed;
}

}  // namespace subvec_cli
