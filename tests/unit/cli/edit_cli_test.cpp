// End-to-end tests of `subvec edit` and `subvec stylize`: they run the built binary (SUBVEC_CLI)
// and check outputs, exit statuses, one-line messages, and that a failed run writes nothing.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/validate.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

// A 96 x 96 disk whose boundary is a closed tear (centre (48, 48), radius 28).
const fs::path kDisk = fs::path(SUBVEC_SOURCE_DIR) / "examples" / "01-disk.svec.json";

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

struct CliResult {
  int status = -1;
  std::string out, err;
};

class EditCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("subvec_edit_cli_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  CliResult subvec(const std::string& args) {
    const fs::path out = dir_ / ".stdout", err = dir_ / ".stderr";
    const std::string command = q(std::string(SUBVEC_CLI)) + " " + args + " >" + q(out) + " 2>" + q(err);
    const int raw = std::system(command.c_str());
    CliResult r;
    r.status = (raw != -1 && WIFEXITED(raw)) ? WEXITSTATUS(raw) : -1;
    r.out = read_text(out);
    r.err = read_text(err);
    fs::remove(out);
    fs::remove(err);
    return r;
  }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

  // Runs `subvec edit` on `input` with `ops` and expects a one-line failure naming `needle`, with
  // no output file left behind.
  void expect_edit_failure(const std::string& ops, const std::string& needle,
                           const fs::path& input = kDisk) {
    const fs::path ops_file = write("ops.json", ops);
    const fs::path out = dir_ / "out.svec";
    const CliResult r = subvec("edit " + q(input) + " -o " + q(out) + " --ops " + q(ops_file));
    EXPECT_GT(r.status, 0) << ops;
    EXPECT_EQ(r.err.rfind("subvec: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << "'" << needle << "' not in: " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    // Neither the output nor a temporary file of it.
    for (const auto& e : fs::directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().find("out.svec"), std::string::npos) << e.path();
  }

  fs::path dir_;
};

TEST_F(EditCli, AppliesShapeAndColorOperations) {
  const fs::path ops = write("ops.json", R"([
    {"op": "drag", "select": "feature", "from": [76, 48], "to": [82, 48], "sigma": 10},
    {"op": "drag", "select": "vertex", "from": [48, 48], "to": [50, 46]},
    {"op": "move-feature", "at": [48, 20], "translate": [1, 1], "rotate": 3, "level": 0},
    {"op": "color", "mode": "blend", "at": [48, 48], "select": "vertex", "radius": 10, "color": [0, 128, 255], "amount": 0.5},
    {"op": "color", "mode": "transform", "at": [10, 10], "select": "feature", "radius": 12, "color": [40, 200, 90]}
  ])");
  const fs::path out = dir_ / "edited.svec.json";
  const CliResult r = subvec("edit " + q(kDisk) + " -o " + q(out) + " --ops " + q(ops) + " -v");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 5) << r.out;
  EXPECT_NE(r.out.find("ops[0] (drag feature): feature 0 (id 0)"), std::string::npos) << r.out;
  const VectorImage before = read_svec(kDisk), after = read_svec(out);
  EXPECT_NE(after.levels[0].positions, before.levels[0].positions);
  EXPECT_NE(after.levels[0].colors, before.levels[0].colors);
  EXPECT_EQ(after.levels[0].triangles, before.levels[0].triangles);
  EXPECT_EQ(after.levels[0].features[0].vertices, before.levels[0].features[0].vertices);
  // The feature's right end moved by the full drag (its vertex sits at the click).
  const int v = before.levels[0].features[0].vertices[0];
  EXPECT_NE(after.levels[0].positions[v].x, before.levels[0].positions[v].x);
}

TEST_F(EditCli, BadOpsFilesAreRefusedWithOneLine) {
  expect_edit_failure("[{\"op\": \"drag\",", "invalid JSON");
  expect_edit_failure("{\"op\": \"drag\"}", "must be a JSON array");
  expect_edit_failure(R"([{"op": "squash", "at": [1, 1]}])", "ops[0]: unknown op \"squash\"");
  expect_edit_failure(R"([{"op": "drag", "select": "vertex", "from": [10, 10]}])",
                      "ops[0] (drag): missing key \"to\"");
  expect_edit_failure(R"([{"op": "drag", "from": "here", "to": [1, 1]}])",
                      "\"from\": expected [x, y] (two numbers), got a string");
  expect_edit_failure(R"([{"op": "color", "mode": "blend", "at": [1, 1], "color": [1, 2]}])",
                      "\"color\": expected [r, g, b]");
  expect_edit_failure(R"([{"op": "color", "mode": "tint", "at": [1, 1], "color": [1, 2, 3]}])",
                      "\"mode\": expected \"blend\" or \"transform\"");
  expect_edit_failure(R"([{"op": "drag", "from": [1, 1], "to": [2, 2], "sigma": 3}])",
                      "unknown key \"sigma\"");
  expect_edit_failure(R"([{"op": "drag", "from": [1, 1], "from": [2, 2], "to": [2, 2]}])",
                      "duplicate key \"from\"");
  expect_edit_failure(R"([{"op": "move-feature", "at": [30, 30]}])", "missing key \"translate\" or \"rotate\"");
  expect_edit_failure(R"([{"op": "drag", "level": 1.5, "from": [1, 1], "to": [2, 2]}])", "\"level\"");
}

TEST_F(EditCli, OperationsTheImageRulesOutAreRefused) {
  expect_edit_failure(R"([{"op": "drag", "select": "vertex", "from": [100, 10], "to": [12, 12]}])",
                      "ops[0] (drag vertex): \"from\" [100, 10] is outside the image [0, 96] x [0, 96]");
  expect_edit_failure(R"([{"op": "color", "mode": "blend", "at": [5, -1], "color": [1, 2, 3]}])",
                      "\"at\" [5, -1] is outside the image");
  expect_edit_failure(R"([{"op": "drag", "from": [40, 40], "to": [41, 41], "level": 2}])",
                      "level 2 is out of range (the image has 1 level)");
  expect_edit_failure(R"([{"op": "drag", "select": "vertex", "from": [1, 1], "to": [5, 5]}])",
                      "is the image corner [0, 0], which stays fixed");
  expect_edit_failure(R"([{"op": "color", "mode": "transform", "at": [48, 48], "color": [1, 2, 3]},
                          {"op": "drag", "select": "vertex", "from": [100, 10], "to": [95, 48]}])",
                      "ops[1] (drag vertex)");
  // A drag the mesh cannot take all the way (issue 25) is not refused: it stops at the last
  // fold-free position, and its line says so. (The centre into the corner: the triangles between
  // it and the corner's sides have no room left.)
  const fs::path ops = write("far.json", R"([{"op": "drag", "select": "vertex", "from": [48, 48], "to": [95, 95]}])");
  const CliResult far = subvec("edit " + q(kDisk) + " -o " + q(dir_ / "far.svec") + " --ops " + q(ops) + " -v");
  EXPECT_EQ(far.status, 0) << far.err;
  EXPECT_NE(far.out.find("% of the way, the last position before the control mesh would fold"), std::string::npos) << far.out;
  // No features: nothing to select.
  const fs::path gradient = write("gradient.svec.json", R"({
    "format": "subvec", "version": 1, "width": 4, "height": 4,
    "levels": [{"vertices": [[0, 0], [4, 0], [4, 4], [0, 4], [2, 2]],
                "colors": [[255, 0, 0], [255, 0, 0], [0, 0, 255], [0, 0, 255], [127.5, 0, 127.5]],
                "triangles": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]}]})");
  expect_edit_failure(R"([{"op": "move-feature", "at": [2, 2], "rotate": 10}])",
                      "nothing to select: level 0 has no features", gradient);
  expect_edit_failure(R"([{"op": "color", "mode": "blend", "select": "feature", "at": [2, 2], "color": [1, 2, 3]}])",
                      "nothing to select", gradient);
}

TEST_F(EditCli, StylizeIsDeterministicAndItsStrokesRender) {
  const fs::path a = dir_ / "a.svec", b = dir_ / "b.svec";
  const CliResult r = subvec("stylize " + q(kDisk) + " -o " + q(a) + " --threshold 0 --seed 3");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("1 strokes on 1 of 1 features"), std::string::npos) << r.out;
  ASSERT_EQ(subvec("stylize " + q(kDisk) + " -o " + q(b) + " --threshold 0 --seed 3").status, 0);
  EXPECT_EQ(read_text(a), read_text(b));
  EXPECT_EQ(read_svec(a).strokes.size(), 1u);

  const fs::path plain = dir_ / "plain.png", styled = dir_ / "styled.png";
  ASSERT_EQ(subvec("render " + q(kDisk) + " -o " + q(plain)).status, 0);
  ASSERT_EQ(subvec("render " + q(a) + " -o " + q(styled)).status, 0);
  const Image8 p = read_image(plain), s = read_image(styled);
  size_t darker = 0;
  for (size_t i = 0; i < p.pixels.size(); ++i) darker += s.pixels[i] + 40 < p.pixels[i];
  EXPECT_GT(darker, 200u);

  // The region of interest and bad options.
  ASSERT_EQ(subvec("stylize " + q(kDisk) + " -o " + q(b) + " --roi 0,0,10,10").status, 0);
  EXPECT_EQ(read_svec(b).strokes.size(), 0u);
  const CliResult bad = subvec("stylize " + q(kDisk) + " -o " + q(dir_ / "c.svec") + " --roi 1,2,3");
  EXPECT_EQ(bad.status, 105);
  EXPECT_FALSE(fs::exists(dir_ / "c.svec"));
  const CliResult level = subvec("stylize " + q(kDisk) + " -o " + q(dir_ / "c.svec") + " --level 1");
  EXPECT_EQ(level.status, 1);
  EXPECT_NE(level.err.find("--level 1 is out of range"), std::string::npos) << level.err;
  EXPECT_FALSE(fs::exists(dir_ / "c.svec"));
}

}  // namespace
}  // namespace subvec
