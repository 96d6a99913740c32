// The shared photographs (../shared/images beside the source tree, as CI has it): where they are,
// and whether the tests that need them run in this build.
//
// They run in the Release build only. Under the sanitizers (SUBVEC_TEST_SANITIZED) the examples,
// the bundled images and the small crops exercise the same code, and the photographs would only
// repeat the Release run's tests several times slower (with them, the sanitizer stage of CI took
// 40 minutes, against 15 without; docs/reliability.md, "CI").
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "support/paths.h"

namespace subvec::test {

inline std::filesystem::path shared_photos() { return source_dir() / ".." / "shared" / "images"; }

// Why a test on the shared photographs (`path`: the folder or a file in it) cannot run here, or
// nothing when it can. A test starts with
//   if (const auto why = test::skip_shared_photos(path)) GTEST_SKIP() << *why;
inline std::optional<std::string> skip_shared_photos(const std::filesystem::path& path) {
#ifdef SUBVEC_TEST_SANITIZED
  (void)path;
  return "the shared photographs are tested in the Release build, not under the sanitizers";
#else
  if (!std::filesystem::exists(path)) return "no " + path.string() + ": shared photographs not present";
  return std::nullopt;
#endif
}

}  // namespace subvec::test
