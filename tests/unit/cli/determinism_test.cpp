// Determinism of every command (issue 9): the same input and options give byte-identical outputs
// across runs and, where the command takes --threads, across thread counts (1, 2, 3 and the
// default, all cores). Outputs are files (vectorize, render, convert, edit, stylize) or stdout
// (info, compare --json, stylize's summary, edit -v).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "subvec/core/image.h"
#include "subvec/io/image_io.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

std::string q(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class Determinism : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("subvec_det_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `subvec ARGS` ({dir} is the test's directory); returns stdout, failing on a non-zero exit.
  std::string subvec(std::string args) {
    for (size_t at = args.find("{dir}"); at != std::string::npos; at = args.find("{dir}"))
      args.replace(at, 5, dir_.string());
    const fs::path out = dir_ / ".stdout", err = dir_ / ".stderr";
    const std::string command =
        q(SUBVEC_CLI) + " " + args + " >" + q(out.string()) + " 2>" + q(err.string());
    const int raw = std::system(command.c_str());
    EXPECT_TRUE(raw != -1 && WIFEXITED(raw) && WEXITSTATUS(raw) == 0)
        << args << ": " << read_bytes(err);
    return read_bytes(out);
  }
  std::string file(const std::string& name) const { return read_bytes(dir_ / name); }

  // A photograph-like test image: a gradient, a disk, a bar touching the border, some texture.
  void write_photo(const std::string& name, int w, int h) const {
    Image8 img(w, h, 3);
    uint32_t state = 3;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        state = state * 1664525u + 1013904223u;
        const bool disk = std::hypot(x - 0.4 * w, y - 0.5 * h) < 0.25 * h;
        const bool bar = x > 0.75 * w && x < 0.85 * w;
        uint8_t* p = img.row(y) + 3 * x;
        const int texture = int(state >> 29);
        p[0] = static_cast<uint8_t>(disk ? 220 : bar ? 30 : 60 + 120 * x / w + texture);
        p[1] = static_cast<uint8_t>(disk ? 80 + 60 * y / h : bar ? 160 : 90 + texture);
        p[2] = static_cast<uint8_t>(disk ? 40 : bar ? 40 : 200 - 80 * y / h);
      }
    }
    write_png(dir_ / name, img);
  }

  fs::path dir_;
};

const fs::path kExamples = fs::path(SUBVEC_SOURCE_DIR) / "examples";

TEST_F(Determinism, VectorizeAcrossRunsAndThreads) {
  write_photo("photo.png", 120, 90);
  const std::string base = "vectorize {dir}/photo.png --ratio 0.03";
  subvec(base + " -o {dir}/a.svec");
  const std::string reference = file("a.svec");
  ASSERT_FALSE(reference.empty());
  subvec(base + " -o {dir}/b.svec");
  EXPECT_EQ(file("b.svec"), reference) << "second run";
  for (int threads : {1, 2, 3}) {
    subvec(base + " -o {dir}/t.svec --threads " + std::to_string(threads));
    EXPECT_EQ(file("t.svec"), reference) << threads << " threads";
  }
  // The segment path (GrabCut draws seeded random numbers) and the JSON form.
  const std::string segment = "vectorize {dir}/photo.png --segment 20,15,60,60 -o {dir}/s";
  subvec(segment + "1.svec.json --threads 1");
  subvec(segment + "2.svec.json --threads 2");
  EXPECT_EQ(file("s1.svec.json"), file("s2.svec.json"));
  EXPECT_FALSE(file("s1.svec.json").empty());
}

TEST_F(Determinism, RenderAcrossRunsAndThreads) {
  for (const char* name : {"01-disk", "03-junction"}) {
    SCOPED_TRACE(name);
    const std::string in = q((kExamples / (std::string(name) + ".svec.json")).string());
    for (const std::string options :
         {"--scale 3", "--window 10.5,7.25,60,50 --width 211 --overlay mesh", "--no-aa --scale 2"}) {
      subvec("render " + in + " -o {dir}/a.png " + options);
      const std::string reference = file("a.png");
      subvec("render " + in + " -o {dir}/b.png " + options);
      EXPECT_EQ(file("b.png"), reference) << options;
      for (int threads : {1, 2, 3}) {
        subvec("render " + in + " -o {dir}/t.png --threads " + std::to_string(threads) + " " +
               options);
        EXPECT_EQ(file("t.png"), reference) << options << ", " << threads << " threads";
      }
    }
    for (const char* ext : {"pdf", "svg"}) {
      subvec("render " + in + " -o {dir}/a." + ext + " --scale 2");
      subvec("render " + in + " -o {dir}/b." + ext + " --scale 2");
      EXPECT_EQ(file(std::string("a.") + ext), file(std::string("b.") + ext)) << ext;
    }
  }
}

TEST_F(Determinism, ConvertInfoCompareEditStylize) {
  const std::string junction = q((kExamples / "03-junction.svec.json").string());
  // convert: both directions, both binary versions.
  for (const std::string out : {"a.svec", "a.svec.json"}) {
    subvec("convert " + junction + " -o {dir}/1" + out);
    subvec("convert " + junction + " -o {dir}/2" + out);
    EXPECT_EQ(file("1" + out), file("2" + out)) << out;
  }
  subvec("convert " + junction + " -o {dir}/l1.svec --lossless");
  subvec("convert " + junction + " -o {dir}/l2.svec --lossless");
  EXPECT_EQ(file("l1.svec"), file("l2.svec"));
  // info, text and JSON.
  for (const std::string options : {"", " --json"}) {
    EXPECT_EQ(subvec("info " + junction + options), subvec("info " + junction + options));
    EXPECT_EQ(subvec("info {dir}/1a.svec" + options), subvec("info {dir}/1a.svec" + options));
  }
  // compare --json.
  subvec("render " + junction + " -o {dir}/x.png");
  subvec("render " + junction + " -o {dir}/y.png --no-aa");
  const std::string compare = subvec("compare {dir}/x.png {dir}/y.png --json");
  EXPECT_NE(compare.find("\"mae\""), std::string::npos);
  EXPECT_EQ(subvec("compare {dir}/x.png {dir}/y.png --json"), compare);
  // edit (shape and color operations, with the log) and stylize (seeded choice, its summary).
  {
    std::ofstream ops(dir_ / "ops.json");
    ops << R"([{"op": "drag", "select": "vertex", "from": [48, 48], "to": [52, 45]},
               {"op": "color", "mode": "blend", "at": [30, 30], "radius": 20, "color": [0, 90, 200], "amount": 0.5}])";
  }
  const std::string edit = "edit " + junction + " --ops {dir}/ops.json -v -o {dir}/e";
  const std::string log = subvec(edit + "1.svec");
  EXPECT_EQ(subvec(edit + "2.svec"), log);
  EXPECT_EQ(file("e1.svec"), file("e2.svec"));
  EXPECT_FALSE(file("e1.svec").empty());
  const std::string stylize = "stylize " + junction + " --probability 0.5 --seed 3 -o {dir}/s";
  const std::string summary = subvec(stylize + "1.svec.json");
  EXPECT_EQ(subvec(stylize + "2.svec.json"), summary);
  EXPECT_EQ(file("s1.svec.json"), file("s2.svec.json"));
}

}  // namespace
}  // namespace subvec
