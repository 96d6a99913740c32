// End-to-end tests of the `subvec` command-line tool: they run the built binary (SUBVEC_CLI) in a
// shell and check exit statuses, stderr messages and the files left behind.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "subvec/core/memory.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/vectorize/vectorize.h"
#include "support/shared_photos.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

const char* const kExamples[] = {"01-disk", "02-open-tear", "03-junction"};

fs::path example(const std::string& name) {
  return fs::path(SUBVEC_SOURCE_DIR) / "examples" / (name + ".svec.json");
}

// Single quotes for the shell.
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

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

struct CliResult {
  int status = -1;  // exit status, or -1 when the process did not exit normally (a crash)
  std::string out, err;
};

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("subvec_cli_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `subvec <args>` with stdout and stderr captured in files of the test's directory.
  CliResult subvec(const std::string& args) {
    const fs::path out = dir_ / ".stdout", err = dir_ / ".stderr";
    const std::string command =
        q(std::string(SUBVEC_CLI)) + " " + args + " >" + q(out) + " 2>" + q(err);
    const int raw = std::system(command.c_str());
    CliResult r;
    r.status = (raw != -1 && WIFEXITED(raw)) ? WEXITSTATUS(raw) : -1;
    r.out = read_text(out);
    r.err = read_text(err);
    fs::remove(out);
    fs::remove(err);
    return r;
  }

  // Expects a clean failure: a non-zero exit (not a crash), one line "subvec: ..." on stderr that
  // contains `needle`, and nothing on stdout.
  void expect_failure(const CliResult& r, const std::string& needle) {
    EXPECT_GT(r.status, 0) << "stderr: " << r.err;
    ASSERT_FALSE(r.err.empty());
    EXPECT_EQ(r.err.rfind("subvec: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "expected one line, got: " << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << "'" << needle << "' not in: " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }

  // Files the test's directory holds, temporary files included.
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_))
      names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path dir_;
};

TEST_F(Cli, RenderHasTheRequestedSize) {
  const VectorImage img = read_svec(example("01-disk"));
  const fs::path png = dir_ / "a.png";

  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(png)).status, 0);
  Image8 out = read_image(png);
  EXPECT_EQ(out.width, img.width);
  EXPECT_EQ(out.height, img.height);

  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(png) + " --scale 4").status, 0);
  out = read_image(png);
  EXPECT_EQ(out.width, 4 * img.width);
  EXPECT_EQ(out.height, 4 * img.height);

  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(png) + " --width 100").status, 0);
  out = read_image(png);
  EXPECT_EQ(out.width, 100);
  EXPECT_EQ(out.height, int(std::lround(100.0 * img.height / img.width)));

  // A window of the top-left quarter at 2x: the image's own size again.
  const std::string window =
      "0,0," + std::to_string(img.width / 2.0) + "," + std::to_string(img.height / 2.0);
  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(png) + " --window " + window +
                   " --scale 2")
                .status,
            0);
  out = read_image(png);
  EXPECT_EQ(out.width, img.width);
  EXPECT_EQ(out.height, img.height);
  EXPECT_EQ(files(), std::vector<std::string>{"a.png"});  // no temporary left behind
}

TEST_F(Cli, RenderIsByteIdenticalAcrossRunsAndThreads) {
  for (const char* name : kExamples) {
    SCOPED_TRACE(name);
    const std::string in = q(example(name));
    const fs::path a = dir_ / "a.png", b = dir_ / "b.png", c = dir_ / "c.png";
    ASSERT_EQ(subvec("render " + in + " -o " + q(a) + " --scale 4 --threads 1").status, 0);
    ASSERT_EQ(subvec("render " + in + " -o " + q(b) + " --scale 4 --threads 1").status, 0);
    ASSERT_EQ(subvec("render " + in + " -o " + q(c) + " --scale 4 --threads 2").status, 0);
    const std::string bytes = read_text(a);
    EXPECT_GT(bytes.size(), 8u);
    EXPECT_EQ(bytes, read_text(b));
    EXPECT_EQ(bytes, read_text(c));
  }
}

TEST_F(Cli, RenderOptionsChangeTheImage) {
  const std::string in = q(example("01-disk"));
  const fs::path plain = dir_ / "plain.png", mesh = dir_ / "mesh.png", level = dir_ / "l.png";
  ASSERT_EQ(subvec("render " + in + " -o " + q(plain) + " --scale 2").status, 0);
  ASSERT_EQ(subvec("render " + in + " -o " + q(mesh) + " --scale 2 --overlay mesh").status, 0);
  EXPECT_NE(read_text(plain), read_text(mesh));
  ASSERT_EQ(subvec("render " + in + " -o " + q(level) +
                   " --scale 2 --overlay Features --no-aa "
                   "--depth 2 --level 0")
                .status,
            0);
  EXPECT_TRUE(fs::exists(level));
}

TEST_F(Cli, InfoJson) {
  for (const char* name : kExamples) {
    SCOPED_TRACE(name);
    const CliResult r = subvec("info " + q(example(name)) + " --json");
    ASSERT_EQ(r.status, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    const VectorImage img = read_svec(example(name));
    EXPECT_EQ(j.at("width").get<int>(), img.width);
    EXPECT_EQ(j.at("height").get<int>(), img.height);
    EXPECT_EQ(j.at("bytes").get<uint64_t>(), fs::file_size(example(name)));
    ASSERT_EQ(j.at("levels").size(), img.levels.size());
    for (size_t i = 0; i < img.levels.size(); ++i) {
      const nlohmann::json& l = j["levels"][i];
      const ControlMesh& m = img.levels[i];
      EXPECT_EQ(l.at("vertices").get<int>(), m.num_vertices());
      EXPECT_EQ(l.at("triangles").get<int>(), m.num_triangles());
      EXPECT_EQ(l.at("features").get<size_t>(), m.features.size());
      EXPECT_EQ(l.at("colors").get<int>(), m.num_colors());
      EXPECT_EQ(l.at("creases").get<size_t>(), m.creases.size());
      // Every feature edge is a tear edge and no edge belongs to two features.
      size_t feature_edges = 0;
      for (const Feature& f : m.features) feature_edges += f.vertices.size() - 1;
      EXPECT_EQ(l.at("tear_edges").get<size_t>(), feature_edges);
      EXPECT_GT(feature_edges, 0u) << "every example has a tear";
    }
  }
}

TEST_F(Cli, InfoText) {
  const VectorImage img = read_svec(example("01-disk"));
  const CliResult r = subvec("info " + q(example("01-disk")));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find(std::to_string(img.width) + " x " + std::to_string(img.height)),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("tear edges"), std::string::npos) << r.out;
}

TEST_F(Cli, ConvertRoundTrip) {
  const fs::path bin = dir_ / "a.svec", json = dir_ / "b.svec.json", direct = dir_ / "c.svec.json",
                 bin2 = dir_ / "d.svec";
  ASSERT_EQ(subvec("convert " + q(example("03-junction")) + " -o " + q(bin) + " --lossless").status,
            0);
  ASSERT_EQ(subvec("convert " + q(bin) + " -o " + q(json)).status, 0);
  ASSERT_EQ(subvec("convert " + q(example("03-junction")) + " -o " + q(direct)).status, 0);
  ASSERT_EQ(subvec("convert " + q(json) + " -o " + q(bin2) + " --lossless").status, 0);
  // json -> svec -> json gives the text json -> json gives; svec -> json -> svec the same bytes.
  EXPECT_EQ(read_text(json), read_text(direct));
  EXPECT_EQ(read_text(bin), read_text(bin2));
  EXPECT_NE(read_text(bin), read_text(json));  // really two formats
  // And the binary file renders like the JSON one.
  ASSERT_EQ(subvec("render " + q(bin) + " -o " + q(dir_ / "x.png")).status, 0);
  ASSERT_EQ(subvec("render " + q(example("03-junction")) + " -o " + q(dir_ / "y.png")).status, 0);
  EXPECT_EQ(read_text(dir_ / "x.png"), read_text(dir_ / "y.png"));
}

TEST_F(Cli, ConvertWritesCompactVersion2OnRequest) {
  // --compact-version 2 writes the older compact payload (varint sections): the header says 2,
  // and it holds the same image as version 3 (both read back to the same JSON). Other versions are
  // refused by the library, naming the two it writes, and nothing is written.
  const fs::path v2 = dir_ / "v2.svec", v3 = dir_ / "v3.svec", j2 = dir_ / "v2.svec.json", j3 = dir_ / "v3.svec.json";
  ASSERT_EQ(subvec("convert " + q(example("02-open-tear")) + " -o " + q(v2) + " --compact-version 2").status, 0);
  ASSERT_EQ(subvec("convert " + q(example("02-open-tear")) + " -o " + q(v3)).status, 0);
  const std::string bytes = read_text(v2);
  ASSERT_GE(bytes.size(), 12u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[8]), 2);
  EXPECT_EQ(static_cast<unsigned char>(read_text(v3)[8]), 3);
  ASSERT_EQ(subvec("convert " + q(v2) + " -o " + q(j2)).status, 0);
  ASSERT_EQ(subvec("convert " + q(v3) + " -o " + q(j3)).status, 0);
  EXPECT_EQ(read_text(j2), read_text(j3));
  const fs::path v4 = dir_ / "v4.svec";
  expect_failure(subvec("convert " + q(example("02-open-tear")) + " -o " + q(v4) + " --compact-version 4"),
                 "compact .svec version 4 is not one this build writes (2 or 3)");
  EXPECT_FALSE(fs::exists(v4));
}

TEST_F(Cli, ConvertCompactIsStableAndRendersAlike) {
  // The compact form (the default) rounds values and renumbers the mesh: a second conversion
  // gives the same bytes, and the picture barely moves.
  const fs::path bin = dir_ / "a.svec", json = dir_ / "b.svec.json", bin2 = dir_ / "c.svec";
  ASSERT_EQ(subvec("convert " + q(example("03-junction")) + " -o " + q(bin)).status, 0);
  ASSERT_EQ(subvec("convert " + q(bin) + " -o " + q(json)).status, 0);
  ASSERT_EQ(subvec("convert " + q(json) + " -o " + q(bin2)).status, 0);
  EXPECT_EQ(read_text(bin), read_text(bin2));
  EXPECT_LT(fs::file_size(bin), fs::file_size(example("03-junction")) / 4);
  ASSERT_EQ(subvec("render " + q(bin) + " -o " + q(dir_ / "x.png")).status, 0);
  ASSERT_EQ(subvec("render " + q(example("03-junction")) + " -o " + q(dir_ / "y.png")).status, 0);
  const CliResult r = subvec("compare " + q(dir_ / "y.png") + " " + q(dir_ / "x.png") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_LT(nlohmann::json::parse(r.out)["mae_mean"].get<double>(), 0.5);
  const CliResult info = subvec("info " + q(bin) + " --json");
  ASSERT_EQ(info.status, 0) << info.err;
  const nlohmann::json j = nlohmann::json::parse(info.out);
  EXPECT_NEAR(j["bytes_per_vertex"].get<double>(),
              j["bytes"].get<double>() / j["levels"][0]["vertices"].get<double>(), 1e-9);
}

TEST_F(Cli, RenderExportsPdfAndSvg) {
  const fs::path pdf = dir_ / "a.pdf", svg = dir_ / "a.SVG";
  CliResult r = subvec("render " + q(example("01-disk")) + " -o " + q(pdf) + " --scale 2");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(r.out.empty());
  EXPECT_EQ(read_text(pdf).rfind("%PDF-1.4", 0), 0u);
  EXPECT_NE(read_text(pdf).find("/MediaBox [0 0 192 192]"), std::string::npos);
  EXPECT_EQ(read_text(pdf).find("/BM /Lighten"), std::string::npos);
  r = subvec("render " + q(example("01-disk")) + " -o " + q(pdf) + " --pdf-target Poppler");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(read_text(pdf).find("/BM /Lighten"), std::string::npos);  // docs/export.md, "PDF"
  r = subvec("render " + q(example("01-disk")) + " -o " + q(svg) + " --width 48 --tolerance 0.5");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(read_text(svg).find("width=\"48\" height=\"48\""), std::string::npos);
  r = subvec("render " + q(example("01-disk")) + " -o " + q(svg) + " --svg-target inkscape -v");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(read_text(svg).find("<meshgradient"), std::string::npos);
  EXPECT_NE(r.err.find("96 mesh patches (one per control face), 0 tear hints, 0 strokes, " +
                       std::to_string(fs::file_size(svg)) + " bytes"),
            std::string::npos)
      << r.err;
  r = subvec("render " + q(example("01-disk")) + " -o " + q(pdf) + " -v");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find(" triangles (control faces at depths "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(std::to_string(fs::file_size(pdf)) + " bytes"), std::string::npos) << r.err;
  expect_failure(subvec("render " + q(example("01-disk")) + " -o " + q(dir_ / "b.pdf") +
                        " --window 0,0,10,10"),
                 "--window and --overlay apply to .png output only");
  const CliResult bad = subvec("render " + q(example("01-disk")) + " -o " + q(dir_ / "c.svg") +
                               " --tolerance 0");
  EXPECT_EQ(bad.status, 105) << bad.err;
  EXPECT_EQ(files(), (std::vector<std::string>{"a.SVG", "a.pdf"}));
}

TEST_F(Cli, CompareIdenticalImages) {
  const fs::path png = dir_ / "a.png";
  ASSERT_EQ(subvec("render " + q(example("02-open-tear")) + " -o " + q(png)).status, 0);
  CliResult r = subvec("compare " + q(png) + " " + q(png) + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("mae_mean").get<double>(), 0.0);
  for (const char* c : {"r", "g", "b"}) EXPECT_EQ(j.at("mae").at(c).get<double>(), 0.0);
  EXPECT_TRUE(j.at("psnr").is_null());
  EXPECT_DOUBLE_EQ(j.at("ssim").get<double>(), 1.0);

  r = subvec("compare " + q(png) + " " + q(png));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("MAE"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("inf"), std::string::npos) << r.out;
}

TEST_F(Cli, CompareDifferentImages) {
  const fs::path a = dir_ / "a.png", b = dir_ / "b.png";
  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(a)).status, 0);
  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(b) + " --overlay mesh").status,
            0);
  const CliResult r = subvec("compare " + q(a) + " " + q(b) + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_GT(j.at("mae_mean").get<double>(), 0.0);
  EXPECT_TRUE(j.at("psnr").is_number());
  EXPECT_LT(j.at("ssim").get<double>(), 1.0);

  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(b) + " --scale 2").status, 0);
  expect_failure(subvec("compare " + q(a) + " " + q(b)), "differ in size");
}

// ---- failures --------------------------------------------------------------------------------

TEST_F(Cli, MissingInputFile) {
  const fs::path out = dir_ / "out.png";
  expect_failure(subvec("render " + q(dir_ / "nope.svec.json") + " -o " + q(out)),
                 "nope.svec.json");
  expect_failure(subvec("info " + q(dir_ / "nope.svec")), "nope.svec");
  expect_failure(subvec("compare " + q(dir_ / "nope.png") + " " + q(dir_ / "nope.png")),
                 "nope.png");
  EXPECT_TRUE(files().empty());
}

TEST_F(Cli, UnsupportedOutputExtension) {
  expect_failure(subvec("render " + q(example("01-disk")) + " -o " + q(dir_ / "out.jpg")), ".jpg");
  expect_failure(subvec("render " + q(example("01-disk")) + " -o " + q(dir_ / "out")),
                 "no extension");
  expect_failure(subvec("convert " + q(example("01-disk")) + " -o " + q(dir_ / "out.txt")),
                 "out.txt");
  EXPECT_TRUE(files().empty());
}

TEST_F(Cli, BadOptionValues) {
  const std::string render = "render " + q(example("01-disk")) + " -o " + q(dir_ / "out.png");
  expect_failure(subvec(render + " --width 0"), "--width");
  expect_failure(subvec(render + " --width -3"), "--width");
  expect_failure(subvec(render + " --scale 0"), "--scale");
  expect_failure(subvec(render + " --width 10 --scale 2"), "--width");
  expect_failure(subvec(render + " --window 10,0,5,20"), "X0 < X1");
  expect_failure(subvec(render + " --window 0,20,10,5"), "Y0 < Y1");
  expect_failure(subvec(render + " --window 1,2,3"), "four numbers");
  expect_failure(subvec(render + " --window 0,0,nan,4"), "four numbers");
  expect_failure(subvec(render + " --level 5"), "level 5");
  expect_failure(subvec(render + " --overlay sparkles"), "--overlay");
  expect_failure(subvec(render + " --threads -1"), "--threads");
  expect_failure(subvec(render + " --depth 11"), "--depth");
  expect_failure(subvec(render + " --scale 100000"), "too large");
  expect_failure(subvec("render " + q(example("01-disk"))), "--output");
  expect_failure(subvec("frobnicate"), "frobnicate");
  EXPECT_TRUE(files().empty());
}

TEST_F(Cli, UsageErrorsUseCli11ExitCodes) {
  EXPECT_EQ(subvec("").status, 106);  // RequiredError: no command
  EXPECT_EQ(
      subvec("render " + q(example("01-disk")) + " -o " + q(dir_ / "o.png") + " --width 0").status,
      105);  // ValidationError
  EXPECT_EQ(
      subvec("render " + q(example("01-disk")) + " -o " + q(dir_ / "o.png") + " --level 5").status,
      1);  // found only once the file is read
}

TEST_F(Cli, BadVectorFiles) {
  const fs::path bad_bin = dir_ / "bad.svec", bad_json = dir_ / "bad.svec.json",
                 empty = dir_ / "empty.svec";
  write_text(bad_bin, "this is not a vector image at all");
  write_text(bad_json, "{\"width\": 10, \"height\": ");
  write_text(empty, "");
  for (const fs::path& in : {bad_bin, bad_json, empty}) {
    SCOPED_TRACE(in.string());
    expect_failure(subvec("render " + q(in) + " -o " + q(dir_ / "out.png")), "");
    expect_failure(subvec("info " + q(in)), "");
    expect_failure(subvec("convert " + q(in) + " -o " + q(dir_ / "out.svec")), "");
  }
  // A truncated copy of a valid binary file.
  ASSERT_EQ(subvec("convert " + q(example("01-disk")) + " -o " + q(dir_ / "good.svec")).status, 0);
  std::string bytes = read_text(dir_ / "good.svec");
  write_text(dir_ / "cut.svec", bytes.substr(0, bytes.size() / 2));
  expect_failure(subvec("render " + q(dir_ / "cut.svec") + " -o " + q(dir_ / "out.png")), "");
  EXPECT_FALSE(fs::exists(dir_ / "out.png"));
  EXPECT_FALSE(fs::exists(dir_ / "out.svec"));
  EXPECT_EQ(files(), (std::vector<std::string>{"bad.svec", "bad.svec.json", "cut.svec",
                                               "empty.svec", "good.svec"}));
}

TEST_F(Cli, BadImagesForCompare) {
  write_text(dir_ / "junk.png", "not a png");
  const fs::path good = dir_ / "good.png";
  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(good)).status, 0);
  expect_failure(subvec("compare " + q(good) + " " + q(dir_ / "junk.png")),
                 "not a PNG, JPEG, WebP, TIFF or BMP file");
}

TEST_F(Cli, FailedRunDoesNotClobberExistingOutput) {
  const fs::path out = dir_ / "out.png", svec = dir_ / "out.svec";
  write_text(out, "precious");
  write_text(svec, "precious too");
  write_text(dir_ / "bad.svec", "garbage");
  expect_failure(subvec("render " + q(example("01-disk")) + " -o " + q(out) + " --level 5"),
                 "level");
  expect_failure(subvec("render " + q(dir_ / "bad.svec") + " -o " + q(out)), "");
  expect_failure(subvec("convert " + q(dir_ / "bad.svec") + " -o " + q(svec)), "");
  EXPECT_EQ(read_text(out), "precious");
  EXPECT_EQ(read_text(svec), "precious too");
  EXPECT_EQ(files(), (std::vector<std::string>{"bad.svec", "out.png", "out.svec"}));
  // A successful run replaces it.
  ASSERT_EQ(subvec("render " + q(example("01-disk")) + " -o " + q(out)).status, 0);
  EXPECT_NE(read_text(out), "precious");
}

TEST_F(Cli, HelpAndVersion) {
  CliResult r = subvec("--version");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("subvec ", 0), 0u) << r.out;
  r = subvec("--help");
  EXPECT_EQ(r.status, 0);
  for (const char* word : {"render", "info", "convert", "compare", "Examples"}) {
    EXPECT_NE(r.out.find(word), std::string::npos) << word;
  }
  r = subvec("render --help");
  EXPECT_EQ(r.status, 0);
  for (const char* word : {"--width", "--scale", "--window", "--level", "--overlay", "--no-aa",
                           "--threads", "--depth"}) {
    EXPECT_NE(r.out.find(word), std::string::npos) << word;
  }
}

// ---- vectorize -------------------------------------------------------------------------------

// A 64 x 48 picture: a disk over a gradient, written as PNG through the library.
void write_test_photo(const fs::path& path) {
  subvec::Image8 img(64, 48, 3);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      const bool inside = (x - 30.5) * (x - 30.5) + (y - 22.5) * (y - 22.5) < 15.0 * 15.0;
      uint8_t* p = img.row(y) + 3 * x;
      p[0] = inside ? 220 : static_cast<uint8_t>(40 + 2 * x);
      p[1] = inside ? 180 : 90;
      p[2] = inside ? 40 : static_cast<uint8_t>(200 - 2 * y);
    }
  }
  subvec::write_png(path, img);
}

TEST_F(Cli, VectorizeWritesAValidImageAndReportsIt) {
  const fs::path photo = dir_ / "photo.png", out = dir_ / "photo.svec";
  write_test_photo(photo);
  const CliResult r = subvec("vectorize " + q(photo) + " -o " + q(out) + " --vertices 60 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["width"], 64);
  EXPECT_EQ(j["height"], 48);
  EXPECT_LE(j["vertices"].get<int>(), 60);
  EXPECT_GE(j["features"].get<int>(), 1);
  EXPECT_LT(j["mae"].get<double>(), 6.0);
  for (const char* stage : {"features", "mesh", "simplify", "refine", "fit"})
    EXPECT_TRUE(j["seconds"].contains(stage));
  EXPECT_GT(j["refine"]["moves"].get<int>(), 0);
  // The output is a valid vector image that renders at the photo's size.
  const CliResult info = subvec("info " + q(out) + " --json");
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["levels"][0]["vertices"], j["vertices"]);
  // Same input and options, same bytes.
  const fs::path again = dir_ / "again.svec";
  ASSERT_EQ(subvec("vectorize " + q(photo) + " -o " + q(again) + " --vertices 60").status, 0);
  EXPECT_EQ(read_text(out), read_text(again));
}

// The feature detector's options reach it: no features when none may be that long, more when the
// threshold's floor is lower; --refine 0 keeps the simplified mesh.
TEST_F(Cli, VectorizeFeatureAndRefineOptions) {
  const fs::path photo = dir_ / "photo.png", out = dir_ / "photo.svec";
  write_test_photo(photo);
  auto run = [&](const std::string& options) {
    const CliResult r = subvec("vectorize " + q(photo) + " -o " + q(out) + " --vertices 60 --levels 1 --json " + options);
    EXPECT_EQ(r.status, 0) << options << ": " << r.err;
    return r.status == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
  };
  const auto plain = run(""), none = run("--min-feature-length 100000"), unrefined = run("--refine 0");
  ASSERT_FALSE(plain.is_null() || none.is_null() || unrefined.is_null());
  EXPECT_GE(plain["features"].get<int>(), 1);
  EXPECT_EQ(none["features"], 0);
  EXPECT_EQ(none["tear_vertices"], 0);
  EXPECT_EQ(unrefined["refine"]["flips"], 0);
  EXPECT_EQ(unrefined["refine"]["moves"], 0);
  EXPECT_GT(plain["refine"]["moves"].get<int>(), 0);
}

TEST_F(Cli, VectorizeBadInputs) {
  const fs::path photo = dir_ / "photo.png", out = dir_ / "out.svec";
  write_test_photo(photo);
  expect_failure(subvec("vectorize " + q(dir_ / "missing.png") + " -o " + q(out)), "missing.png");
  write_text(dir_ / "garbage.png", "this is not an image");
  expect_failure(subvec("vectorize " + q(dir_ / "garbage.png") + " -o " + q(out)), "garbage.png");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --ratio 0"), "--ratio");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --ratio 1.5"), "--ratio");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --ratio -1"), "--ratio");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --vertices 2"), "--vertices");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --edge-quantile 2"), "--edge-quantile");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --edge-blur nan"), "--edge-blur");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --max-feature-error 0"),
                 "--max-feature-error");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --refine -1"), "--refine");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(dir_ / "out.png")), ".png");
  expect_failure(subvec("vectorize " + q(photo) + " -o " + q(out) + " --max-pixels 100"),
                 "64x48 pixels is over the limit of 100 pixels (--max-pixels raises the limit)");
  write_text(dir_ / "empty.png", "");
  expect_failure(subvec("vectorize " + q(dir_ / "empty.png") + " -o " + q(out)), "file is empty");
  const std::string png = read_text(photo);
  write_text(dir_ / "cut.png", png.substr(0, png.size() / 2));
  expect_failure(subvec("vectorize " + q(dir_ / "cut.png") + " -o " + q(out)), "truncated");
  write_text(dir_ / "photo.ppm", "P6\n1 1\n255\nabc");
  expect_failure(subvec("vectorize " + q(dir_ / "photo.ppm") + " -o " + q(out)),
                 "not a PNG, JPEG, WebP, TIFF or BMP file");
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Cli, VectorizeSegment) {
  const fs::path photo = dir_ / "photo.png", out = dir_ / "photo.svec";
  write_test_photo(photo);  // the disk: centre (30.5, 22.5), radius 15
  const CliResult r = subvec("vectorize " + q(photo) + " -o " + q(out) +
                             " --vertices 60 --segment 10,3,42,40 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j["segment"].is_object()) << r.out;
  EXPECT_EQ(j["segment"]["rect"], nlohmann::json::parse("[10, 3, 42, 40]"));
  EXPECT_EQ(j["segment"]["features"], 1);
  EXPECT_EQ(j["segment"]["closed"], true);
  EXPECT_NEAR(j["segment"]["foreground_pixels"].get<double>(), M_PI * 15 * 15, 60);
  EXPECT_TRUE(j["seconds"].contains("segment"));
  // GrabCut draws random numbers: same input and options, still the same bytes.
  const fs::path again = dir_ / "again.svec";
  const CliResult text =
      subvec("vectorize " + q(photo) + " -o " + q(again) + " --vertices 60 --segment 10,3,42,40");
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_EQ(read_text(out), read_text(again));
  EXPECT_NE(text.out.find("segment   10,3,42,40: "), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("boundary is 1 closed feature"), std::string::npos) << text.out;
  // Without --segment the JSON says so.
  const CliResult plain =
      subvec("vectorize " + q(photo) + " -o " + q(again) + " --vertices 60 --json");
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_TRUE(nlohmann::json::parse(plain.out)["segment"].is_null());
}

// The bundled photograph that scripts/demo vectorizes: public domain, in the repository.
TEST_F(Cli, VectorizeTheExamplePhotograph) {
  const fs::path photo = fs::path(SUBVEC_SOURCE_DIR) / "examples" / "04-rocket.png";
  ASSERT_TRUE(fs::exists(photo));
  EXPECT_LE(fs::file_size(photo), 150u * 1024);
  const fs::path out = dir_ / "rocket.svec";
  const CliResult r = subvec("vectorize " + q(photo) + " -o " + q(out) + " --ratio 0.005 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["width"], 384);
  EXPECT_EQ(j["height"], 256);
  EXPECT_LT(j["mae"].get<double>(), 8.0);
  ASSERT_EQ(subvec("render " + q(out) + " -o " + q(dir_ / "mesh.png") + " --scale 4 --overlay mesh")
                .status,
            0);
}

// Full-size photographs (issue 24): a 20 MP image (5472 x 3648, a 1-inch sensor's) is read by
// default and refused by --max-memory below its estimate, with the estimate, before any work.
TEST_F(Cli, ATwentyMegapixelImageIsReadAndRefusedOnlyByItsMemoryEstimate) {
  EXPECT_GE(subvec::kDefaultMaxInputPixels, int64_t{6000} * 4000);  // a 24 MP photograph too
  const fs::path photo = dir_ / "20mp.png", out = dir_ / "out.svec";
  subvec::Image8 img(5472, 3648, 3);
  for (int y = 0; y < img.height; ++y) std::fill_n(img.row(y), 3 * img.width, static_cast<uint8_t>(y));
  subvec::write_png(photo, img);
  const CliResult r = subvec("vectorize " + q(photo) + " -o " + q(out) + " --max-memory 2GB");
  expect_failure(r, "subvec: --max-memory is 2.0 GB, and vectorizing this 5472x3648 image needs an estimated ");
  EXPECT_EQ(r.err.find("over the limit"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // The estimate named is the library's, and batch refuses the image with the same words.
  const int64_t estimate = subvec::estimate_vectorize_bytes(5472, 3648, {});
  EXPECT_GT(estimate, int64_t{2'000'000'000});
  EXPECT_NE(r.err.find(subvec::format_bytes(estimate)), std::string::npos) << r.err;
  fs::create_directories(dir_ / "in");
  fs::rename(photo, dir_ / "in" / "20mp.png");
  const CliResult b = subvec("batch " + q(dir_ / "in") + " -o " + q(dir_ / "batch") + " --max-memory 2GB");
  EXPECT_EQ(b.status, 1);
  EXPECT_NE(b.err.find("--max-memory is 2.0 GB"), std::string::npos) << b.err;
  EXPECT_FALSE(fs::exists(dir_ / "batch" / "20mp.svec"));
  // A lower --max-pixels is still the reader's limit, checked first.
  expect_failure(subvec("vectorize " + q(dir_ / "in" / "20mp.png") + " -o " + q(out) + " --max-pixels 19000000"),
                 "5472x3648 pixels is over the limit of 19000000 pixels (--max-pixels raises the limit)");
  expect_failure(subvec("vectorize " + q(dir_ / "in" / "20mp.png") + " -o " + q(out) + " --max-memory lots"),
                 "--max-memory");
}

// The estimate bounds the measured peak (the JSON's `memory`), without being far above it, on a
// 1 MP crop of the most feature-rich photograph, whose band of pixel-resolution mesh around the
// features is the estimate's largest unknown (scripts/bench-scaling's runs are the others:
// docs/performance.md, "Memory").
TEST_F(Cli, TheMemoryEstimateBoundsThePeak) {
  const fs::path large = subvec::test::shared_photos() / ".." / "images-large";
  if (const auto why = subvec::test::skip_shared_photos(large / "OneStandsOut.jpg")) GTEST_SKIP() << *why;
  const subvec::Image8 whole = subvec::read_image(large / "OneStandsOut.jpg");
  subvec::Image8 crop(1280, 800, 3);
  const int x0 = (whole.width - crop.width) / 2, y0 = (whole.height - crop.height) / 2;
  for (int y = 0; y < crop.height; ++y) std::copy_n(whole.row(y0 + y) + 3 * x0, 3 * crop.width, crop.row(y));
  const fs::path photo = dir_ / "crop.png";
  subvec::write_png(photo, crop);
  const CliResult r = subvec("vectorize " + q(photo) + " -o " + q(dir_ / "crop.svec") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const double estimate = j["memory"]["estimate_bytes"].get<double>(), peak = j["memory"]["peak_bytes"].get<double>();
  EXPECT_EQ(estimate, double(subvec::estimate_vectorize_bytes(1280, 800, {})));
  EXPECT_GE(estimate, peak);
  EXPECT_LE(estimate, 2 * peak);
}

TEST_F(Cli, VectorizeSegmentBadRectangles) {
  const fs::path photo = dir_ / "photo.png", out = dir_ / "out.svec";
  write_test_photo(photo);  // 64 x 48
  const std::string run = "vectorize " + q(photo) + " -o " + q(out) + " --segment ";
  for (const char* malformed :
       {"1,2,3", "a,b,c,d", "1,2,3,4,5", "1,2,3,4,", "1.5,2,3,4", "", " 1,2,3,4"}) {
    const CliResult r = subvec(run + q(std::string(malformed)));
    expect_failure(r, "expected four integers X,Y,W,H");
    EXPECT_EQ(r.status, 105) << malformed;
  }
  expect_failure(subvec(run + "10,10,0,5"), "is empty");
  expect_failure(subvec(run + "10,10,5,-3"), "is empty");
  for (const char* outside : {"-1,0,10,10", "60,0,10,10", "0,40,10,10", "100,100,5,5"}) {
    const CliResult r = subvec(run + outside);
    expect_failure(r, "is not inside the 64x48 image");
    EXPECT_EQ(r.status, 1) << outside;
  }
  expect_failure(subvec(run + "0,0,64,48"), "GrabCut needs background pixels");
  expect_failure(subvec(run + "10,10,2,2"), "too small");
  EXPECT_FALSE(fs::exists(out));
}

// Runs `subvec <args...>` with stderr on a pseudo-terminal and stdout in a file; returns what the
// terminal received and the exit status. With `interrupt_at`, types Ctrl+C on the terminal once
// it shows that text.
std::pair<std::string, int> run_on_terminal(const std::vector<std::string>& args,
                                            const fs::path& stdout_file,
                                            const char* progress_delay,
                                            const char* interrupt_at = nullptr) {
  int master = -1;
  const pid_t pid = forkpty(&master, nullptr, nullptr, nullptr);
  if (pid == 0) {
    const int fd = ::open(stdout_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0 || ::dup2(fd, STDOUT_FILENO) < 0) _exit(126);
    ::setenv("SUBVEC_PROGRESS_DELAY", progress_delay, 1);
    std::vector<char*> argv{const_cast<char*>(SUBVEC_CLI)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(SUBVEC_CLI, argv.data());
    _exit(127);
  }
  if (pid < 0) return {"forkpty failed", -1};
  std::string terminal;
  char buf[4096];
  bool interrupted = false;
  while (true) {
    const ssize_t n = ::read(master, buf, sizeof buf);
    if (n <= 0) break;  // EIO once the child has closed the terminal
    terminal.append(buf, size_t(n));
    if (interrupt_at && !interrupted && terminal.find(interrupt_at) != std::string::npos) {
      interrupted = ::write(master, "\x03", 1) == 1;  // the terminal sends SIGINT
    }
  }
  int raw = 0;
  ::waitpid(pid, &raw, 0);
  ::close(master);
  return {terminal, WIFEXITED(raw) ? WEXITSTATUS(raw) : -1};
}

TEST_F(Cli, VectorizeProgressOnlyOnATerminal) {
  const fs::path photo = dir_ / "photo.png", out = dir_ / "photo.svec",
                 summary = dir_ / "summary.txt";
  write_test_photo(photo);
  // On a terminal, with the delay at 0 so that even this short run shows it: a line redrawn with
  // '\r' per stage, erased at the end (the last thing written is spaces and '\r').
  const auto [terminal, status] = run_on_terminal(
      {"vectorize", photo.string(), "-o", out.string(), "--vertices", "60"}, summary, "0");
  ASSERT_EQ(status, 0) << terminal;
  EXPECT_NE(terminal.find("\rsubvec: vectorizing photo.png: "), std::string::npos) << terminal;
  EXPECT_NE(terminal.find("%, 0 s"), std::string::npos) << terminal;
  ASSERT_FALSE(terminal.empty());
  EXPECT_EQ(terminal.back(), '\r') << terminal;
  EXPECT_EQ(terminal.find('\n'), std::string::npos) << terminal;
  EXPECT_NE(read_text(summary).find("mesh      "), std::string::npos);
  // A delay longer than the run hides it (an hour here, so that a slow machine or a sanitizer
  // build cannot make this run outlast it; the default is a second).
  const auto [quiet, quiet_status] = run_on_terminal(
      {"vectorize", photo.string(), "-o", out.string(), "--vertices", "60"}, summary, "3600");
  ASSERT_EQ(quiet_status, 0) << quiet;
  EXPECT_EQ(quiet, "");
  // Not a terminal: nothing on stderr whatever the delay.
  const CliResult piped = subvec("vectorize " + q(photo) + " -o " + q(out) + " --vertices 60");
  ASSERT_EQ(piped.status, 0);
  EXPECT_EQ(piped.err, "");
  // An error on a terminal: the progress line is erased before the one-line message.
  const auto [failed, failed_status] = run_on_terminal(
      {"vectorize", photo.string(), "-o", out.string(), "--segment", "0,0,64,48"}, summary, "0");
  EXPECT_EQ(failed_status, 1);
  const size_t message = failed.find("subvec: segment rectangle");
  ASSERT_NE(message, std::string::npos) << failed;
  EXPECT_TRUE(message == 0 || failed[message - 1] == '\r') << failed;
}

// Ctrl+C stops a vectorization at its next stage (cancel.h): one line, exit status 130, no output
// file and no summary. Ctrl+C is typed on the terminal once the progress line shows the
// simplification running, with several stages still to come.
TEST_F(Cli, VectorizeStopsOnCtrlC) {
  const fs::path photo = dir_ / "large.png", out = dir_ / "large.svec", summary = dir_ / "summary.txt";
  subvec::Image8 img(640, 640, 3);  // a few seconds of work from the simplification on
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const bool inside = std::hypot(x % 160 - 80, y % 160 - 80) < 50;
      uint8_t* p = img.row(y) + 3 * x;
      p[0] = inside ? 230 : static_cast<uint8_t>(x * 255 / img.width);
      p[1] = inside ? 40 : static_cast<uint8_t>(y * 255 / img.height);
      p[2] = static_cast<uint8_t>((x + y) % 200);
    }
  }
  subvec::write_png(photo, img);
  const auto [terminal, status] =
      run_on_terminal({"vectorize", photo.string(), "-o", out.string()}, summary, "0", ": simplify");
  EXPECT_EQ(status, 130) << terminal;
  EXPECT_NE(terminal.find("subvec: cancelled"), std::string::npos) << terminal;
  // The job itself stopped (VectorizeOptions::cancel): it never reached the levels, two stages on.
  EXPECT_EQ(terminal.find(": levels"), std::string::npos) << terminal;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(read_text(summary), "");
}

// `subvec vectorize`, `subvec batch` and `subvec serve` take the vectorize options from one
// registration (vectorize_options.h), with the library's defaults in the help and the library's
// ranges (subvec::validate) reported as usage errors naming the flag.
TEST_F(Cli, VectorizeOptionsAreSharedWithServeAndBatch) {
  for (const char* command : {"vectorize", "serve"}) {
    const CliResult help = subvec(std::string(command) + " --help");
    ASSERT_EQ(help.status, 0) << command;
    for (const char* word : {"--ratio", "--vertices", "--segment", "--refine", "--relocate", "--levels",
                             "--level-reduction", "--feature-level", "--edge-blur", "--threads",
                             "(default 0.01)"}) {
      EXPECT_NE(help.out.find(word), std::string::npos) << command << ": " << word;
    }
  }
  const fs::path photo = dir_ / "photo.png";
  write_test_photo(photo);
  for (const char* command : {"vectorize", "serve", "batch"}) {
    const std::string input = std::string(command) == "batch" ? dir_.string() : photo.string();
    const std::string out = std::string(command) == "serve" ? "" : " -o " + q(dir_ / "out");
    CliResult r = subvec(std::string(command) + " " + q(input) + out + " --ratio 2");
    EXPECT_EQ(r.status, 105) << command;
    expect_failure(r, "--ratio must be in (0, 1], got 2");
    r = subvec(std::string(command) + " " + q(input) + out + " --levels 17");
    EXPECT_EQ(r.status, 105) << command;
    expect_failure(r, "--levels must be in [1, 16], got 17");
  }
}

}  // namespace
}  // namespace subvec
