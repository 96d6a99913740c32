// `subvec vectorize --levels ...`, `subvec filter` and the levels in `info` and `render`, end to end
// through the built binary (SUBVEC_CLI).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "../pyramid/pyramid_test_util.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/pyramid/pyramid.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

std::string q(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}
std::string q(const fs::path& p) { return q(p.string()); }

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct Result {
  int status = -1;
  std::string out, err;
};

class LevelsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("subvec_levels_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
            "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    photo_ = dir_ / "shapes.png";
    write_png(photo_, test::shapes_image());
  }
  void TearDown() override { fs::remove_all(dir_); }
  Result subvec(const std::string& args) {
    const fs::path out = dir_ / ".stdout", err = dir_ / ".stderr";
    const int raw = std::system((q(std::string(SUBVEC_CLI)) + " " + args + " >" + q(out) + " 2>" + q(err)).c_str());
    Result r;
    r.status = (raw != -1 && WIFEXITED(raw)) ? WEXITSTATUS(raw) : -1;
    r.out = read_text(out);
    r.err = read_text(err);
    return r;
  }
  void expect_failure(const Result& r, const std::string& needle) {
    EXPECT_GT(r.status, 0) << r.err;
    EXPECT_EQ(r.err.rfind("subvec: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << "'" << needle << "' not in: " << r.err;
  }
  fs::path dir_, photo_;
};

TEST_F(LevelsCli, VectorizeBuildsThreeLevelsByDefault) {
  const fs::path out = dir_ / "s.svec";
  const Result r = subvec("vectorize " + q(photo_) + " -o " + q(out) + " --ratio 0.04 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["levels"].size(), 3u);
  EXPECT_EQ(j["levels"][0]["vertices"], j["vertices"]);
  EXPECT_TRUE(j["seconds"].contains("levels"));
  const VectorImage image = read_svec(out);
  ASSERT_EQ(image.levels.size(), 3u);
  EXPECT_TRUE(has_pyramid(image));
  for (size_t l = 0; l < 3; ++l) EXPECT_EQ(j["levels"][l]["vertices"], image.levels[l].num_vertices());
  // info lists every level with its feature ids; render draws each.
  const Result info = subvec("info " + q(out) + " --json");
  ASSERT_EQ(info.status, 0) << info.err;
  const auto ji = nlohmann::json::parse(info.out);
  ASSERT_EQ(ji["levels"].size(), 3u);
  EXPECT_EQ(ji["levels"][2]["feature_ids"].size(), image.levels[2].features.size());
  EXPECT_EQ(ji["levels"][1]["collapses"], image.levels[1].collapses.size());
  for (int l = 0; l < 3; ++l)
    EXPECT_EQ(subvec("render " + q(out) + " -o " + q(dir_ / "l.png") + " --level " + std::to_string(l)).status, 0);
  // One level on request, and byte-identical runs.
  const fs::path one = dir_ / "one.svec";
  ASSERT_EQ(subvec("vectorize " + q(photo_) + " -o " + q(one) + " --ratio 0.04 --levels 1").status, 0);
  EXPECT_EQ(read_svec(one).levels.size(), 1u);
  const fs::path again = dir_ / "again.svec";
  ASSERT_EQ(subvec("vectorize " + q(photo_) + " -o " + q(again) + " --ratio 0.04").status, 0);
  EXPECT_EQ(read_text(out), read_text(again));
}

TEST_F(LevelsCli, FeatureLevelOverride) {
  const fs::path out = dir_ / "s.svec";
  ASSERT_EQ(subvec("vectorize " + q(photo_) + " -o " + q(out) + " --ratio 0.04").status, 0);
  const VectorImage plain = read_svec(out);
  // A feature of level 0 that level 1 lacks, kept to level 2 on request.
  int32_t id = -1;
  for (const Feature& f : plain.levels[0].features) {
    bool in1 = false;
    for (const Feature& g : plain.levels[1].features) in1 |= g.id == f.id;
    if (!in1) id = f.id;
  }
  ASSERT_GE(id, 0);
  const fs::path kept = dir_ / "kept.svec";
  const Result r = subvec("vectorize " + q(photo_) + " -o " + q(kept) + " --ratio 0.04 --feature-level " +
                          std::to_string(id) + "=2 --saliency-weight 3 --level-reduction 0.5");
  ASSERT_EQ(r.status, 0) << r.err;
  const VectorImage image = read_svec(kept);
  for (int l = 0; l < 3; ++l) {
    bool found = false;
    for (const Feature& f : image.levels[l].features) found |= f.id == id;
    EXPECT_TRUE(found) << "level " << l;
  }
  expect_failure(subvec("vectorize " + q(photo_) + " -o " + q(dir_ / "x.svec") + " --feature-level 99999=1"),
                 "no feature has id 99999");
  expect_failure(subvec("vectorize " + q(photo_) + " -o " + q(dir_ / "x.svec") + " --feature-level 3=5"),
                 "level 5 is outside 0..2");
  expect_failure(subvec("vectorize " + q(photo_) + " -o " + q(dir_ / "x.svec") + " --feature-level abc"),
                 "ID=LEVEL");
  expect_failure(subvec("vectorize " + q(photo_) + " -o " + q(dir_ / "x.svec") + " --levels 0"), "--levels");
  expect_failure(subvec("vectorize " + q(photo_) + " -o " + q(dir_ / "x.svec") + " --level-reduction 1"),
                 "--level-reduction");
  EXPECT_FALSE(fs::exists(dir_ / "x.svec"));
}

TEST_F(LevelsCli, Filter) {
  const fs::path in = dir_ / "s.svec";
  ASSERT_EQ(subvec("vectorize " + q(photo_) + " -o " + q(in) + " --ratio 0.04").status, 0);
  const fs::path smooth = dir_ / "smooth.svec.json";
  const Result r = subvec("filter " + q(in) + " -o " + q(smooth) + " --eta 0.3");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("2 bands"), std::string::npos) << r.out;
  const VectorImage a = read_svec(in), b = read_svec(smooth);
  ASSERT_EQ(b.levels.size(), 3u);
  EXPECT_NE(a.levels[0].colors, b.levels[0].colors);
  EXPECT_TRUE(has_pyramid(b));
  // The result renders, and filters again.
  ASSERT_EQ(subvec("render " + q(smooth) + " -o " + q(dir_ / "s.png")).status, 0);
  ASSERT_EQ(subvec("filter " + q(smooth) + " -o " + q(dir_ / "twice.svec") + " --eta-levels 1,0.5 --color-eta").status, 0);
  ASSERT_EQ(subvec("filter " + q(in) + " -o " + q(dir_ / "g.svec") + " --eta 0.5 --geometry-eta").status, 0);
  EXPECT_EQ(read_svec(dir_ / "g.svec").levels[0].colors.size(), a.levels[0].colors.size());
  // Bad requests: one line, no output.
  const fs::path bad = dir_ / "bad.svec";
  expect_failure(subvec("filter " + q(in) + " -o " + q(bad) + " --eta-levels 1,1,1"), "3 values");
  expect_failure(subvec("filter " + q(in) + " -o " + q(bad) + " --eta-levels 1,,2"), "--eta-levels");
  expect_failure(subvec("filter " + q(in) + " -o " + q(bad) + " --eta nan"), "--eta");
  expect_failure(subvec("filter " + q(in) + " -o " + q(bad) + " --eta 1 --eta-levels 1"), "excludes");
  const fs::path one = dir_ / "one.svec";
  ASSERT_EQ(subvec("vectorize " + q(photo_) + " -o " + q(one) + " --ratio 0.04 --levels 1").status, 0);
  expect_failure(subvec("filter " + q(one) + " -o " + q(bad)), "one level");
  expect_failure(subvec("filter " + q(dir_ / "missing.svec") + " -o " + q(bad)), "missing.svec");
  EXPECT_FALSE(fs::exists(bad));
}

}  // namespace
}  // namespace subvec
