// Docs that cannot drift: every fenced block marked as an example in README.md and docs/*.md is
// run against the built binary and its output compared with the text of the block, numbers
// included.
//
// The marker: a fence whose info string is `example`. Inside, a line starting with "$ " is a
// command (run by sh from a scratch directory where examples/ is the repository's, with the
// built `cncore` first on the PATH); the lines after it, up to the next command or the end of
// the block, are its output, stdout and stderr together, compared line by line after trailing
// blanks are cut. The exit code is not compared: errors are output too.
//
//   ```example
//   $ cncore check examples/seed-line-arc-line.ngc
//   examples/seed-line-arc-line.ngc: ok, 3 motion blocks
//   ```
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

struct Command {
  std::string doc;  // file relative to the repository, e.g. docs/cli.md
  int line = 0;     // of the "$ " line
  std::string command;
  std::vector<std::string> expected;
};

// gtest prints the parameter of a failed test: the place in the docs.
void PrintTo(const Command& c, std::ostream* os) {
  *os << c.doc << ":" << c.line;
}

std::string rstrip(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.pop_back();
  return s;
}

std::vector<Command> commands_in(const fs::path& file, const std::string& doc) {
  std::vector<Command> out;
  std::ifstream in(file);
  std::string line;
  int n = 0;
  bool in_example = false, in_other_fence = false;
  while (std::getline(in, line)) {
    ++n;
    const std::string t = rstrip(line);
    if (!in_example && !in_other_fence && t.rfind("```", 0) == 0) {
      (t == "```example" ? in_example : in_other_fence) = true;
      continue;
    }
    if (t == "```") {
      in_example = in_other_fence = false;
      continue;
    }
    if (!in_example) continue;
    if (t.rfind("$ ", 0) == 0) {
      out.push_back({doc, n, t.substr(2), {}});
    } else if (!out.empty()) {
      out.back().expected.push_back(t);
    }
  }
  return out;
}

std::vector<Command> all_commands() {
  const fs::path root = CNCORE_SOURCE_DIR;
  std::vector<Command> all = commands_in(root / "README.md", "README.md");
  std::vector<fs::path> docs;
  for (const auto& e : fs::directory_iterator(root / "docs")) {
    if (e.path().extension() == ".md") docs.push_back(e.path());
  }
  std::sort(docs.begin(), docs.end());
  for (const fs::path& d : docs) {
    auto c = commands_in(d, "docs/" + d.filename().string());
    all.insert(all.end(), c.begin(), c.end());
  }
  return all;
}

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  std::string l;
  while (std::getline(in, l)) out.push_back(rstrip(l));
  while (!out.empty() && out.back().empty()) out.pop_back();
  return out;
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

class DocExample : public ::testing::TestWithParam<Command> {};

TEST_P(DocExample, OutputMatchesTheDocs) {
  const Command& c = GetParam();
  // A scratch directory per command: outputs the command writes land there.
  const fs::path dir = fs::path(CNCORE_TEST_TMP_DIR) / "docs-examples" /
                       (fs::path(c.doc).stem().string() + "-" + std::to_string(c.line));
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::create_directory_symlink(fs::path(CNCORE_SOURCE_DIR) / "examples", dir / "examples");
  const std::string bin_dir = fs::path(CNCORE_BIN).parent_path().string();
  const std::string cmd = "cd " + quote(dir.string()) + " && PATH=" + quote(bin_dir) +
                          ":\"$PATH\" sh -c " + quote(c.command) + " >.output 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << c.command;
  std::vector<std::string> expected = c.expected;
  while (!expected.empty() && expected.back().empty()) expected.pop_back();
  const std::vector<std::string> got = lines_of(dir / ".output");
  std::string diff;
  for (std::size_t i = 0; i < std::max(expected.size(), got.size()); ++i) {
    const std::string e = i < expected.size() ? expected[i] : "<nothing>";
    const std::string g = i < got.size() ? got[i] : "<nothing>";
    if (e != g)
      diff +=
          "  line " + std::to_string(i + 1) + "\n    docs:   " + e + "\n    binary: " + g + "\n";
  }
  EXPECT_TRUE(diff.empty()) << c.doc << ":" << c.line << ": $ " << c.command << "\n" << diff;
}

INSTANTIATE_TEST_SUITE_P(Docs, DocExample, ::testing::ValuesIn(all_commands()),
                         [](const ::testing::TestParamInfo<Command>& param) {
                           std::string name =
                               param.param.doc + "_" + std::to_string(param.param.line);
                           for (char& ch : name) {
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           }
                           return name;
                         });

TEST(DocExamples, TheDocsHaveExamples) {
  EXPECT_GE(all_commands().size(), 5U);
}

}  // namespace
