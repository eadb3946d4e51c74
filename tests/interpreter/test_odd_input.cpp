// Bad and odd input: what a careless editor, a hostile file or another controller's habits
// put into a program. Each case either runs as LinuxCNC runs it or fails with a clean
// InputError (never a crash, never a message holding raw bytes).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

std::vector<Block> blocks_of(const std::string& text, const MachineConfig& m = test_machine()) {
  Interpreter in(Interpreter::FromText{}, text, "odd.ngc", m, Options{});
  std::vector<Block> out;
  Block b;
  while (in.next(b)) out.push_back(b);
  return out;
}

std::vector<Block> motion_of(const std::string& text, const MachineConfig& m = test_machine()) {
  std::vector<Block> out = blocks_of(text, m);
  std::erase_if(out, [](const Block& b) { return !is_motion(b); });
  return out;
}

// The InputError of a program that must fail (an empty message when it runs).
std::string error_of(const std::string& text, const MachineConfig& m = test_machine()) {
  try {
    blocks_of(text, m);
  } catch (const InputError& e) {
    return e.formatted();
  }
  return {};
}

TEST(OddInput, AChainOfSignsIsBoundedLikeBrackets) {
  const std::string err = error_of("G0 X" + std::string(40000, '-') + "1\n");
  EXPECT_NE(err.find("odd.ngc:1:"), std::string::npos) << err;
  EXPECT_NE(err.find("too many signs"), std::string::npos) << err;
  EXPECT_NE(error_of("G0 X" + std::string(40000, '+') + "1\n").find("too many signs"),
            std::string::npos);
  const auto b = motion_of("G0 X--+-2\n");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_DOUBLE_EQ(b[0].end[kX], -2.0);
}

TEST(OddInput, FanucMainProgramNumberAfterParameterLinesRuns) {
  const auto b = motion_of("#1=1\n(title)\nO1\nG0 X1\nG0 X[#1+1]\nG0 X3\nM99\n");
  ASSERT_EQ(b.size(), 3u);
  EXPECT_DOUBLE_EQ(b[2].end[kX], 3.0);
  // After a move, an O number starts a subprogram that is skipped in sequence.
  const auto sub = motion_of("G0 X1\nO200\nG0 Y9\nM99\nG0 X2\nM2\n");
  ASSERT_EQ(sub.size(), 2u);
  EXPECT_DOUBLE_EQ(sub[1].end[kY], 0.0);
}

TEST(OddInput, NestedLoopsRunOutOfTheWholeProgramsBudget) {
  MachineConfig m = test_machine();
  m.max_loop_iterations = 1000000;
  m.max_total_iterations = 20000;
  const std::string program =
      "#1=0\no1 while [#1 LT 999999]\n#2=0\no2 while [#2 LT 999999]\n#2=[#2+1]\n"
      "o2 endwhile\n#1=[#1+1]\no1 endwhile\nM2\n";
  const std::string err = error_of(program, m);
  EXPECT_NE(err.find("max_total_iterations (20000)"), std::string::npos) << err;
  // Subroutine calls spend from the same budget.
  m.max_total_iterations = 50;
  const std::string calls = "o10 sub\nG0 X1\no10 endsub\no1 repeat [40]\no10 call\no1 endrepeat\n";
  EXPECT_NE(error_of(calls, m).find("max_total_iterations (50)"), std::string::npos);
  m.max_total_iterations = 100;
  EXPECT_EQ(error_of(calls, m), "");
}

TEST(OddInput, CarriageReturnAloneEndsALine) {
  const auto b = motion_of("G0 X1\rG0 X2\r\rG0 X3\r\nG0 X4\n");
  ASSERT_EQ(b.size(), 4u);
  EXPECT_EQ(b[1].line, 2u);
  EXPECT_EQ(b[2].line, 4u);
  EXPECT_EQ(b[3].line, 5u);
  EXPECT_DOUBLE_EQ(b[3].end[kX], 4.0);
}

TEST(OddInput, CrLfAcrossTheReadersChunkBoundaryInAFileWithALoop) {
  // The reader reads 64 KiB chunks: put a "\r" as the last byte of the first chunk and its
  // "\n" in the second, inside a loop that seeks back over the boundary.
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / "cncore_odd_input_crlf.ngc";
  std::string text = "#1=0\ro1 while [#1 LT 2]\r\n";
  const std::size_t chunk = 1 << 16;
  while (text.size() < chunk - 40) text += "(padding padding padding padding)\r\n";
  std::string last = "G0 X[#1+1]";
  while (text.size() + last.size() + 1 < chunk) last += ' ';
  text += last + "\r\n#1=[#1+1]\r\no1 endwhile\rG0 Y5\r\n";
  ASSERT_EQ(text[chunk - 1], '\r');
  ASSERT_EQ(text[chunk], '\n');
  {
    std::ofstream f(path, std::ios::binary);
    f << text;
  }
  const MachineConfig m = test_machine();
  Interpreter in(path.string(), m, Options{});
  std::vector<Block> got;
  Block b;
  while (in.next(b)) got.push_back(b);
  std::filesystem::remove(path);
  ASSERT_EQ(got.size(), 3u);
  const auto lines = static_cast<std::uint32_t>(std::count(text.begin(), text.end(), '\n'));
  EXPECT_EQ(got[0].line, got[1].line);
  EXPECT_DOUBLE_EQ(got[1].end[kX], 2.0);
  EXPECT_EQ(got[2].line, lines + 2);  // "\r" alone ends line 1 and the endwhile line
  EXPECT_DOUBLE_EQ(got[2].end[kY], 5.0);
}

TEST(OddInput, Utf8ByteOrderMarkIsIgnored) {
  const auto b = motion_of("\xEF\xBB\xBFG0 X1\nG0 X2\n");
  ASSERT_EQ(b.size(), 2u);
  EXPECT_DOUBLE_EQ(b[0].end[kX], 1.0);
  // Not at the start of the file it is what it is: bytes that are not G-code.
  EXPECT_NE(error_of("G0 X1\n\xEF\xBB\xBFG0 X2\n").find("odd.ngc:2:1:"), std::string::npos);
}

TEST(OddInput, NulAndNonAsciiBytesAreEscapedInMessages) {
  const std::string nul = error_of(std::string("G0 X1 \0 Y2\n", 11));
  EXPECT_NE(nul.find("unexpected character '\\x00'"), std::string::npos) << nul;
  EXPECT_EQ(nul.find('\0'), std::string::npos);
  const std::string utf8 = error_of("G0 X\xC3\xA9\n");
  EXPECT_NE(utf8.find("\\xC3"), std::string::npos) << utf8;
  for (const char c : utf8) EXPECT_LT(static_cast<unsigned char>(c), 0x80) << utf8;
  const std::string name = error_of("G0 X#<caf\xC3\xA9>\n");
  EXPECT_NE(name.find("#<caf\\xC3\\xA9>"), std::string::npos) << name;
}

TEST(OddInput, ExponentsAreNamedAsSuch) {
  const std::string err = error_of("G0 X1e400\n");
  EXPECT_NE(err.find("odd.ngc:1:5: error: bad number '1e400'"), std::string::npos) << err;
  EXPECT_NE(err.find("no exponent"), std::string::npos) << err;
  EXPECT_NE(error_of("G0 X2.5E-3\n").find("'2.5e-3'"), std::string::npos);
  EXPECT_NE(error_of("G0 E5\n").find("1:4: error: unknown word 'E'"), std::string::npos);
  EXPECT_NE(error_of("G0 X10 E5\n").find("1:8: error: unknown word 'E'"), std::string::npos);
  // EQ after a number is an operator, not an exponent.
  EXPECT_EQ(motion_of("G0 X[1 EQ 1]\n").at(0).end[kX], 1.0);
}

// An I J K arc whose radius differs within the tolerance: one arc block about the programmed
// centre, from the start to the programmed end (the radius blends along it: the trajectory is
// measured in test_spiral_trajectory.cpp).
TEST(OddInput, ArcWithUnequalRadiiKeepsTheProgrammedCentre) {
  for (const char* j : {"0.01", "0.00001"}) {
    const auto b = motion_of(std::string("G0 X10\nG3 X0 Y10 I-10 J") + j + " F100\n");
    ASSERT_EQ(b.size(), 2u) << j;
    const Block& a = b[1];
    ASSERT_EQ(a.kind, BlockKind::kArc);
    EXPECT_DOUBLE_EQ(a.center.x, 0.0);
    EXPECT_DOUBLE_EQ(a.center.y, std::stod(j));
    EXPECT_DOUBLE_EQ(a.end[kX], 0.0);
    EXPECT_DOUBLE_EQ(a.end[kY], 10.0);
  }
}

TEST(OddInput, ComputedONumbersValueAndExists) {
  const std::string subs = "o100 sub\nG0 X#1\no100 endsub\n";
  auto b = motion_of(subs + "#5=50\nO[#5*2] call [7]\n#<p>=100\no#<p> call [8]\nM2\n");
  ASSERT_EQ(b.size(), 2u);
  EXPECT_DOUBLE_EQ(b[0].end[kX], 7.0);
  EXPECT_DOUBLE_EQ(b[1].end[kX], 8.0);
  b = motion_of("G0 X[#<_value> + 1] Y[EXISTS[#99999] + EXISTS[#7] * 2]\n");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_DOUBLE_EQ(b[0].end[kX], 1.0);
  EXPECT_DOUBLE_EQ(b[0].end[kY], 2.0);
  // The index itself is checked only at the outermost level (LinuxCNC's exists-3).
  EXPECT_NE(error_of("#2=99999\nG0 X EXISTS[###2]\n").find("out of range"), std::string::npos);
}

TEST(OddInput, G80WithAnotherMotionCodeInOneBlock) {
  auto b = motion_of("G0 G80 X5\nG80 G1 X6 F100\n");
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b[0].kind, BlockKind::kRapid);
  EXPECT_EQ(b[1].kind, BlockKind::kLine);
  EXPECT_NE(error_of("G0 G1 X1\n").find("same modal group"), std::string::npos);
}

}  // namespace
}  // namespace cncore::interp::test
