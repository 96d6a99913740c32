// Where the tests find the repository's files and the subvec command: the build's own paths, or,
// when the tests run from a copy elsewhere (the GPU check's bundle, scripts/gpu-check), the
// environment's SUBVEC_SOURCE_DIR and SUBVEC_CLI.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

namespace subvec::test {

inline std::filesystem::path source_dir() {
  const char* dir = std::getenv("SUBVEC_SOURCE_DIR");
  return std::filesystem::path(dir && *dir ? dir : SUBVEC_SOURCE_DIR);
}

inline std::string cli_path() {
  const char* cli = std::getenv("SUBVEC_CLI");
  return cli && *cli ? cli : SUBVEC_CLI;
}

}  // namespace subvec::test
