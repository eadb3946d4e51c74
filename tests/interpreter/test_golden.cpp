// Golden tests: every folder tests/interpreter/golden/<case>/ holds program.ngc and
// expected.blocks (the format_block listing, written by hand); every folder
// tests/interpreter/reject/<case>/ holds program.ngc and expected.txt ("LINE:COL" on the first
// line, a fragment of the message on the second). Each folder is its own test.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> case_names(const char* sub) {
  std::vector<std::string> names;
  const fs::path dir = fs::path(CNCORE_INTERP_TEST_DIR) / sub;
  if (!fs::exists(dir)) return names;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_directory()) names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::string cur;
  for (char c : text) {
    if (c == '\n') {
      if (!cur.empty() && cur.back() == '\r') cur.pop_back();
      lines.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  if (!cur.empty()) lines.push_back(cur);
  // Blank lines and lines starting with '#' in expected files are comments.
  std::erase_if(lines, [](const std::string& l) { return l.empty() || l[0] == '#'; });
  return lines;
}

std::string test_name(const testing::TestParamInfo<std::string>& info) {
  std::string n = info.param;
  for (char& c : n) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return n;
}

class Golden : public testing::TestWithParam<std::string> {};

TEST_P(Golden, ListingMatchesHandWrittenExpectation) {
  const fs::path dir = fs::path(CNCORE_INTERP_TEST_DIR) / "golden" / GetParam();
  const MachineConfig m = test_machine();
  std::vector<std::string> got;
  try {
    Interpreter in((dir / "program.ngc").string(), m, Options{});
    Block b;
    while (in.next(b)) got.push_back(format_block(b, m));
  } catch (const InputError& e) {
    FAIL() << "unexpected error: " << e.formatted();
  }
  const std::vector<std::string> want = split_lines(read_text((dir / "expected.blocks").string()));
  ASSERT_FALSE(want.empty()) << "empty expected.blocks";
  const std::size_t n = std::max(got.size(), want.size());
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(i < want.size() ? want[i] : "<nothing>", i < got.size() ? got[i] : "<nothing>")
        << "block " << i + 1;
  }
}

INSTANTIATE_TEST_SUITE_P(Interpreter, Golden, testing::ValuesIn(case_names("golden")), test_name);

class Reject : public testing::TestWithParam<std::string> {};

TEST_P(Reject, FailsAtTheExpectedPositionWithTheMessage) {
  const fs::path dir = fs::path(CNCORE_INTERP_TEST_DIR) / "reject" / GetParam();
  const std::vector<std::string> want = split_lines(read_text((dir / "expected.txt").string()));
  ASSERT_GE(want.size(), 2u) << "expected.txt needs LINE:COL and a message fragment";
  const MachineConfig m = test_machine();
  try {
    Interpreter in((dir / "program.ngc").string(), m, Options{});
    Block b;
    std::size_t count = 0;
    while (in.next(b)) ++count;
    FAIL() << "the program was accepted (" << count << " blocks)";
  } catch (const InputError& e) {
    EXPECT_EQ(want[0], std::to_string(e.line()) + ":" + std::to_string(e.col())) << e.formatted();
    EXPECT_NE(std::string(e.what()).find(want[1]), std::string::npos)
        << "message '" << e.what() << "' lacks '" << want[1] << "'";
    EXPECT_NE(e.formatted().find("program.ngc:" + want[0] + ": error: "), std::string::npos)
        << e.formatted();
  }
}

INSTANTIATE_TEST_SUITE_P(Interpreter, Reject, testing::ValuesIn(case_names("reject")), test_name);

}  // namespace
}  // namespace cncore::interp::test
