// The bad-input corpus (tests/bad-input/, README.md there): every line of cases.txt runs the built
// `subvec` on a malformed file or an absurd option and checks what a stranger's input must never
// break: the expected exit status, one line "subvec: ..." on stderr holding the expected words,
// nothing on stdout, no crash, no hang (the run is killed after a minute), a run of under 10 s,
// no output file and no temporary file left behind, and an existing output file left
// byte-identical by the failed run. A new case is one more line in cases.txt.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace subvec {
namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = fs::path(SUBVEC_SOURCE_DIR) / "tests" / "bad-input";

// A run of under this many seconds passes; sanitizer builds run several times slower.
#ifdef SUBVEC_TEST_SANITIZED
constexpr double kMaxSeconds = 60;
#else
constexpr double kMaxSeconds = 10;
#endif
// A run still going after this long is killed and reported as a hang.
constexpr int kKillSeconds = 120;

struct Case {
  std::string name;
  int status = 1;
  std::string expected;           // words the message must contain (after substitution); "-": none
  std::vector<std::string> args;  // command-line arguments, with placeholders
  int line = 0;                   // in cases.txt
};

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

// Splits the arguments at spaces; '...' quotes an argument with spaces or an empty one.
std::vector<std::string> split_args(const std::string& text) {
  std::vector<std::string> args;
  size_t i = 0;
  while (i < text.size()) {
    if (text[i] == ' ' || text[i] == '\t') {
      ++i;
      continue;
    }
    std::string arg;
    if (text[i] == '\'') {
      const size_t end = text.find('\'', i + 1);
      arg = text.substr(i + 1, end == std::string::npos ? std::string::npos : end - i - 1);
      i = end == std::string::npos ? text.size() : end + 1;
    } else {
      const size_t end = text.find_first_of(" \t", i);
      arg = text.substr(i, end == std::string::npos ? std::string::npos : end - i);
      i = end == std::string::npos ? text.size() : end;
    }
    args.push_back(arg);
  }
  return args;
}

// cases.txt: "name | status | expected words | arguments", '#' starts a comment line.
std::vector<Case> load_cases() {
  std::vector<Case> cases;
  std::ifstream in(kCorpus / "cases.txt");
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string text = trim(line);
    if (text.empty() || text[0] == '#') continue;
    std::vector<std::string> fields;
    size_t start = 0;
    for (int k = 0; k < 3; ++k) {
      const size_t bar = text.find(" | ", start);
      if (bar == std::string::npos) break;
      fields.push_back(trim(text.substr(start, bar - start)));
      start = bar + 3;
    }
    fields.push_back(trim(text.substr(start)));
    Case c;
    c.line = number;
    if (fields.size() != 4) {
      c.name = "malformed_line_" + std::to_string(number);
      c.status = -1000;  // reported by the test
      cases.push_back(c);
      continue;
    }
    c.name = fields[0];
    c.status = std::atoi(fields[1].c_str());
    c.expected = fields[2];
    c.args = split_args(fields[3]);
    cases.push_back(c);
  }
  return cases;
}

std::string q(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
  return s;
}

// Files the directory holds, recursively (temporary files included), as relative paths.
std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    names.insert(fs::relative(e.path(), dir).string());
  return names;
}

struct RunResult {
  int status = -1;  // exit status; -1 when killed by a signal (a crash)
  bool hung = false;
  double seconds = 0;
  std::string out, err;
};

class BadInput : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("subvec_bad_" + GetParam().name + "_" +
                                        std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "work");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Placeholders: {files} the corpus files, {data} tests/data, {examples} examples/, {tmp} the
  // run's empty working directory, {out} the output file's path without extension (in {tmp}).
  std::string expand(const std::string& s) const {
    std::string r = replace_all(s, "{files}", (kCorpus / "files").string());
    r = replace_all(r, "{data}", (fs::path(SUBVEC_SOURCE_DIR) / "tests" / "data").string());
    r = replace_all(r, "{examples}", (fs::path(SUBVEC_SOURCE_DIR) / "examples").string());
    r = replace_all(r, "{out}", (work() / "out").string());
    return replace_all(r, "{tmp}", work().string());
  }
  fs::path work() const { return dir_ / "work"; }

  RunResult run(const std::vector<std::string>& args) {
    std::string command = "timeout -k 5 " + std::to_string(kKillSeconds) + " " +
                          q(std::string(SUBVEC_CLI));
    for (const std::string& a : args) command += " " + q(expand(a));
    const fs::path out = dir_ / "stdout", err = dir_ / "stderr";
    command += " <" + q("/dev/null") + " >" + q(out.string()) + " 2>" + q(err.string());
    const auto start = std::chrono::steady_clock::now();
    const int raw = std::system(command.c_str());
    RunResult r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (raw != -1 && WIFEXITED(raw)) {
      r.status = WEXITSTATUS(raw);
      // timeout's own statuses: 124 killed after the limit, 128 + 9 after the second signal;
      // 128 + N is also how timeout passes on the child's death by signal N.
      r.hung = r.status == 124 || r.status == 137;
      if (r.status > 128 && !r.hung) r.status = -1;
    }
    r.out = read_text(out);
    r.err = read_text(err);
    return r;
  }

  void check_failure(const Case& c, const RunResult& r, const std::string& when) {
    SCOPED_TRACE("cases.txt line " + std::to_string(c.line) + " (" + when + ")");
    ASSERT_FALSE(r.hung) << "still running after " << kKillSeconds << " s";
    ASSERT_NE(r.status, -1) << "crashed; stderr: " << r.err;
    EXPECT_EQ(r.status, c.status) << "stderr: " << r.err;
    EXPECT_LT(r.seconds, kMaxSeconds);
    EXPECT_TRUE(r.out.empty()) << "stdout: " << r.out;
    EXPECT_EQ(r.err.rfind("subvec: ", 0), 0u) << "stderr: " << r.err;
    EXPECT_TRUE(!r.err.empty() && r.err.find('\n') == r.err.size() - 1)
        << "expected exactly one line, got: " << r.err;
    const std::string expected = expand(c.expected);
    EXPECT_NE(r.err.find(expected), std::string::npos)
        << "expected '" << expected << "' in: " << r.err;
  }

  fs::path dir_;
};

TEST_P(BadInput, FailsCleanly) {
  const Case& c = GetParam();
  ASSERT_NE(c.status, -1000) << "cases.txt line " << c.line
                             << ": expected 'name | status | expected | arguments'";
  // The output file: the argument that names {out}, if any.
  fs::path output;
  for (const std::string& a : c.args)
    if (a.find("{out}") != std::string::npos) output = expand(a);

  const RunResult first = run(c.args);
  if (c.status == 0) {  // an awkward input that must work
    ASSERT_FALSE(first.hung);
    ASSERT_EQ(first.status, 0) << "stderr: " << first.err;
    EXPECT_LT(first.seconds, kMaxSeconds);
    if (!output.empty()) {
      EXPECT_TRUE(fs::exists(output));
      EXPECT_EQ(listing(work()), std::set<std::string>{output.filename().string()});
    }
    return;
  }
  check_failure(c, first, "no output file before");
  EXPECT_TRUE(listing(work()).empty()) << "the failed run left files behind";
  if (output.empty()) return;

  // Again over an existing output: it must be left as it was.
  const std::string previous = "the user's work, not to be lost\n";
  {
    std::ofstream f(output, std::ios::binary);
    f << previous;
  }
  const RunResult second = run(c.args);
  check_failure(c, second, "over an existing output file");
  EXPECT_EQ(read_text(output), previous) << "the failed run changed the existing output";
  EXPECT_EQ(listing(work()), std::set<std::string>{output.filename().string()})
      << "the failed run left files behind";
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) { return info.param.name; }

// gtest prints a failing parameter with this: the case's name and line.
void PrintTo(const Case& c, std::ostream* os) { *os << c.name << " (cases.txt line " << c.line << ")"; }

INSTANTIATE_TEST_SUITE_P(Corpus, BadInput, ::testing::ValuesIn(load_cases()), case_name);

// The manifest itself: names unique and usable as test names, every corpus file used by a case,
// every file a case names present.
TEST(BadInputCorpus, ManifestIsConsistent) {
  const std::vector<Case> cases = load_cases();
  ASSERT_GT(cases.size(), 100u);
  std::set<std::string> names, used;
  const std::regex valid_name("[A-Za-z0-9_]+");
  for (const Case& c : cases) {
    EXPECT_TRUE(std::regex_match(c.name, valid_name)) << "line " << c.line << ": " << c.name;
    EXPECT_TRUE(names.insert(c.name).second) << "line " << c.line << ": repeated name " << c.name;
    EXPECT_FALSE(c.args.empty()) << "line " << c.line;
    if (c.status != 0) {
      EXPECT_NE(c.expected, "-") << "line " << c.line;
    }
    for (const std::string& a : c.args) {
      const size_t at = a.find("{files}/");
      if (at == std::string::npos) continue;
      const std::string file = a.substr(at + 8);
      used.insert(file);
      EXPECT_TRUE(fs::exists(kCorpus / "files" / file)) << "line " << c.line << ": " << file;
    }
  }
  for (const auto& e : fs::directory_iterator(kCorpus / "files")) {
    EXPECT_TRUE(used.count(e.path().filename().string()))
        << e.path().filename() << " is used by no case in cases.txt";
  }
}

}  // namespace
}  // namespace subvec
