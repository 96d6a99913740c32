// The error cases docs/cli.md lists (its "### Errors" section): each "$ subvec ARGS   # STATUS"
// line is run in a folder holding photo.png and disk.svec.json, and the line after it is the
// exact stderr expected. Every case must fail with the documented status, print nothing on
// stdout and exactly one line "subvec: ..." on stderr: the documentation is the test's data, so
// the two cannot drift apart.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace subvec {
namespace {

namespace fs = std::filesystem;

struct DocumentedError {
  std::string args;      // after "subvec"
  int status = 0;        // from the "# STATUS" comment
  std::string expected;  // the whole stderr line, without its newline
  int line = 0;          // in docs/cli.md
};

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

// The transcript in the first code block after "### Errors".
std::vector<DocumentedError> documented_errors() {
  std::istringstream in(read_text(fs::path(SUBVEC_SOURCE_DIR) / "docs" / "cli.md"));
  std::vector<DocumentedError> cases;
  std::string text;
  int number = 0;
  enum { kBefore, kSection, kBlock } state = kBefore;
  while (std::getline(in, text)) {
    ++number;
    if (state == kBefore && text == "### Errors") state = kSection;
    else if (state == kSection && text.rfind("```", 0) == 0) state = kBlock;
    else if (state == kBlock && text.rfind("```", 0) == 0) break;
    else if (state == kBlock && text.rfind("$ subvec", 0) == 0) {
      DocumentedError c;
      c.line = number;
      const size_t hash = text.find('#');
      const std::string command = trim(text.substr(0, hash));
      c.args = trim(command.substr(std::string("$ subvec").size()));
      c.status = hash == std::string::npos ? 0 : std::atoi(text.c_str() + hash + 1);
      cases.push_back(c);
    } else if (state == kBlock && !cases.empty() && cases.back().expected.empty()) {
      cases.back().expected = text;
    }
  }
  return cases;
}

struct CliRun {
  int status = -1;
  std::string out, err;
};

class DocumentedErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("subvec_errors_doc_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "work");
    const fs::path source(SUBVEC_SOURCE_DIR);
    fs::copy_file(source / "examples" / "04-rocket.png", dir_ / "work" / "photo.png");
    fs::copy_file(source / "examples" / "01-disk.svec.json", dir_ / "work" / "disk.svec.json");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The documented arguments hold no quotes or shell characters: the shell splits them as a
  // reader would.
  CliRun run(const std::string& args) {
    const std::string command = "cd '" + (dir_ / "work").string() + "' && timeout 60 '" +
                                std::string(SUBVEC_CLI) + "' " + args + " </dev/null >'" +
                                (dir_ / "stdout").string() + "' 2>'" + (dir_ / "stderr").string() +
                                "'";
    const int raw = std::system(command.c_str());
    CliRun r;
    if (raw != -1 && WIFEXITED(raw)) r.status = WEXITSTATUS(raw);
    r.out = read_text(dir_ / "stdout");
    r.err = read_text(dir_ / "stderr");
    return r;
  }

  fs::path dir_;
};

TEST_F(DocumentedErrors, EachFailsWithTheDocumentedLine) {
  const std::vector<DocumentedError> cases = documented_errors();
  ASSERT_GE(cases.size(), 15u) << "docs/cli.md: no '### Errors' transcript found";
  for (const DocumentedError& c : cases) {
    SCOPED_TRACE("docs/cli.md line " + std::to_string(c.line) + ": subvec " + c.args);
    ASSERT_EQ(c.args.find_first_of("'\"$`;|&<>"), std::string::npos) << "no shell characters";
    EXPECT_GT(c.status, 0) << "each case needs '# STATUS', a failing one";
    ASSERT_EQ(c.expected.rfind("subvec: ", 0), 0u) << "the expected line: " << c.expected;
    const CliRun r = run(c.args);
    EXPECT_EQ(r.status, c.status) << r.err;
    EXPECT_NE(r.status, 0);
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_EQ(r.err, c.expected + "\n");  // one line, exactly the documented one
    EXPECT_TRUE(fs::exists(dir_ / "work" / "photo.png"));
  }
  // A failed run leaves nothing behind in the folder.
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir_ / "work")) left.push_back(e.path().filename());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"disk.svec.json", "photo.png"}));
}

// Unknown names get the closest valid one whatever the command, not only the documented ones.
TEST_F(DocumentedErrors, UnknownOptionsGetTheClosestName) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"vectorize photo.png -o p.svec --ratoi 0.02", "vectorize: unknown option --ratoi; did you mean --ratio?"},
      {"vectorize photo.png -o p.svec --level 2", "vectorize: unknown option --level; did you mean --levels?"},
      {"render disk.svec.json -o d.png --overla mesh", "render: unknown option --overla; did you mean --overlay?"},
      {"convert disk.svec.json -o d.svec --loss", "convert: unknown option --loss; did you mean --lossless?"},
      {"compare photo.png photo.png --jsno", "compare: unknown option --jsno; did you mean --json?"},
      {"infoo disk.svec.json", "unknown command 'infoo'; did you mean info?"},
      {"vectorise photo.png -o p.svec", "unknown command 'vectorise'; did you mean vectorize?"},
      {"render disk.svec.json -o d.png --frobnicate", "render: unknown option --frobnicate; see 'subvec render --help'"},
      // An unknown option is the mistake even where CLI11 first misses a required argument.
      {"info -x", "info: unknown option -x; see 'subvec info --help'"},
      {"render -o d.png --widht 3", "render: unknown option --widht; did you mean --width?"},
  };
  for (const auto& [args, expected] : cases) {
    const CliRun r = run(args);
    EXPECT_EQ(r.status, 109) << args;
    EXPECT_EQ(r.err, "subvec: " + expected + "\n") << args;
  }
}

}  // namespace
}  // namespace subvec
