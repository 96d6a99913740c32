// The README's bytes-per-vertex claims, recomputed: the bundled photograph (examples/04-rocket.png)
// vectorized with the defaults (three levels), then `subvec info --json`'s bytes_per_vertex
// (the file's bytes over the control vertices of all levels), and the same for its level 0 alone,
// which is what `--levels 1` writes. The README states both to one decimal ("about 7.0 bytes per
// control vertex with the default three levels (...; 5.3 with one level"); a change of the coder,
// the vectorizer or the levels that moves them fails here until the sentence is updated. One
// vectorization, a few seconds.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <utility>

#include "subvec/io/svec.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The numbers in the README's sentence "... about X bytes per control vertex with the default
// three levels (...; Y with one level ...", or NaN when the sentence is not there. Lines are
// joined first: the sentence may wrap.
std::pair<double, double> readme_bytes_per_vertex() {
  std::string text = read_text(fs::path(SUBVEC_SOURCE_DIR) / "README.md");
  for (char& c : text)
    if (c == '\n') c = ' ';
  text = std::regex_replace(text, std::regex(" +"), " ");
  std::smatch m;
  const std::regex sentence(
      R"(about ([0-9]+\.[0-9]) bytes per control vertex with the default three levels \([^;)]*; ([0-9]+\.[0-9]) with one level)");
  if (!std::regex_search(text, m, sentence)) return {std::nan(""), std::nan("")};
  return {std::stod(m[1].str()), std::stod(m[2].str())};
}

double one_decimal(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", x);
  return std::stod(text);
}

TEST(ReadmeFigures, BytesPerVertexOfTheBundledPhotographAtTheDefaults) {
  const auto [claimed, claimed_one_level] = readme_bytes_per_vertex();
  ASSERT_FALSE(std::isnan(claimed)) << "README.md: no 'about X.Y bytes per control vertex with the "
                                       "default three levels (...; Z.W with one level'";

  const fs::path dir = fs::temp_directory_path() / ("subvec_readme_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path svec = dir / "rocket.svec", json = dir / "info.json";
  const std::string cli = std::string("'") + SUBVEC_CLI + "'";
  const std::string photo = (fs::path(SUBVEC_SOURCE_DIR) / "examples" / "04-rocket.png").string();
  const std::string command = cli + " vectorize '" + photo + "' -o '" + svec.string() +
                              "' >/dev/null && " + cli + " info '" + svec.string() + "' --json >'" +
                              json.string() + "'";
  const int raw = std::system(command.c_str());
  ASSERT_TRUE(raw != -1 && WIFEXITED(raw) && WEXITSTATUS(raw) == 0) << command;
  const nlohmann::json info = nlohmann::json::parse(read_text(json));
  // One level: level 0 alone, in the same compact form.
  VectorImage image = read_svec(svec);
  image.levels.resize(1);
  const double one_level = double(to_svec_binary(image).size()) / image.levels[0].num_vertices();
  fs::remove_all(dir);

  ASSERT_EQ(info["levels"].size(), 3u) << "the default is no longer three levels";
  const double measured = info["bytes_per_vertex"].get<double>();
  EXPECT_EQ(one_decimal(measured), claimed)
      << std::setprecision(3) << "README.md says about " << claimed << " bytes per control vertex; the bundled photograph "
      << "at the defaults takes " << measured << " (" << info["bytes"] << " bytes): update the "
      << "sentence (and docs/format.md's figures)";
  EXPECT_EQ(one_decimal(one_level), claimed_one_level)
      << std::setprecision(3) << "README.md says " << claimed_one_level << " bytes per control vertex with one level; "
      << "level 0 of the bundled photograph alone takes " << one_level << ": update the sentence";
}

}  // namespace
}  // namespace subvec
