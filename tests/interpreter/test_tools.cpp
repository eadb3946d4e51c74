// Tools: the LinuxCNC tool table file, T / M6 / M61, the tool length offsets G43 / G43.1 /
// G43.2 / G49 and the table writes G10 L1 / L10 / L11. Outcomes are the machine positions of
// the emitted blocks and the values the program reads back (#5401…, #5420…).
#include <gtest/gtest.h>

#include "config/tool_table.hpp"
#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

std::vector<Block> motion_with(const std::string& text, const Options& o,
                               const MachineConfig& m = test_machine()) {
  Interpreter in(Interpreter::FromText{}, text, "tools.ngc", m, o);
  std::vector<Block> out;
  Block b;
  while (in.next(b)) {
    if (is_motion(b)) out.push_back(b);
  }
  return out;
}

std::string error_with(const std::string& text, const Options& o) {
  try {
    motion_with(text, o);
  } catch (const InputError& e) {
    return e.formatted();
  }
  return {};
}

Options with_table(const std::string& tbl) {
  Options o;
  o.tools = parse_tool_table(tbl, "t.tbl");
  return o;
}

TEST(ToolTable, LinuxCncFormatWithCommentsAndAnyOrder) {
  const ToolTable t = parse_tool_table(
      "T1 P1 Z12.5 D6 ;drill\n\n; a comment line\nt2 p5 x0.5 z+20 d10 i0 j0 q0\nZ-3 T7\n", "t.tbl");
  ASSERT_EQ(t.size(), 3u);
  EXPECT_DOUBLE_EQ(t.at(1).offset_mm[kZ], 12.5);
  EXPECT_DOUBLE_EQ(t.at(1).diameter_mm, 6.0);
  EXPECT_EQ(t.at(2).pocket, 5u);
  EXPECT_DOUBLE_EQ(t.at(2).offset_mm[kX], 0.5);
  EXPECT_DOUBLE_EQ(t.at(2).offset_mm[kZ], 20.0);
  EXPECT_DOUBLE_EQ(t.at(7).offset_mm[kZ], -3.0);
}

// LinuxCNC's older column format, mill and lathe headers: FMS is the tool number.
TEST(ToolTable, OlderColumnFormat) {
  const ToolTable mill = parse_tool_table(
      "POC     FMS     LEN     DIAM    COMMENT\n\n1 1 0.5 0.0625 first tool\n32 7 -2 4\n", "t.tbl");
  ASSERT_EQ(mill.size(), 2u);
  EXPECT_EQ(mill.at(1).pocket, 1u);
  EXPECT_DOUBLE_EQ(mill.at(1).offset_mm[kZ], 0.5);
  EXPECT_DOUBLE_EQ(mill.at(1).diameter_mm, 0.0625);
  EXPECT_EQ(mill.at(7).pocket, 32u);
  EXPECT_DOUBLE_EQ(mill.at(7).offset_mm[kZ], -2.0);
  const ToolTable lathe = parse_tool_table(
      "POC FMS ZOFFSET XOFFSET DIA FRONTANGLE BACKANGLE ORIENT COMMENT\n2 3 1.5 -0.25 0.8 95 "
      "155 2 turning\n",
      "t.tbl");
  EXPECT_DOUBLE_EQ(lathe.at(3).offset_mm[kZ], 1.5);
  EXPECT_DOUBLE_EQ(lathe.at(3).offset_mm[kX], -0.25);
  EXPECT_DOUBLE_EQ(lathe.at(3).diameter_mm, 0.8);
  try {
    parse_tool_table("POC FMS LEN DIAM\n1 1 x 2\n", "t.tbl");
    ADD_FAILURE() << "a word that is not a number is accepted";
  } catch (const InputError& e) {
    EXPECT_NE(e.formatted().find("t.tbl:2:5: error: tool table: 'x' is not a number (column LEN)"),
              std::string::npos)
        << e.formatted();
  }
}

TEST(ToolTable, ErrorsNameLineAndColumn) {
  auto err = [](const std::string& text) {
    try {
      parse_tool_table(text, "t.tbl");
    } catch (const InputError& e) {
      return e.formatted();
    }
    return std::string();
  };
  EXPECT_NE(err("T1 Z1\nT2 Zq\n").find("t.tbl:2:4: error:"), std::string::npos) << err("T1\nT2 Zq");
  EXPECT_NE(err("P1 Z1\n").find("t.tbl:1:1: error: tool table: a line without T"),
            std::string::npos);
  EXPECT_NE(err("T1\nT1\n").find("tool 1 is listed twice"), std::string::npos);
  EXPECT_NE(err("T1 K5\n").find("t.tbl:1:4: error: tool table: unknown word 'K'"),
            std::string::npos);
  EXPECT_NE(err("T1.5\n").find("non-negative integer"), std::string::npos);
  EXPECT_NE(err("T1 W2\n").find("no W axis"), std::string::npos);
}

TEST(ToolLength, G43AppliesTheLoadedToolsLengthAndG49RemovesIt) {
  const Options o = with_table("T1 P1 Z10\nT2 P2 Z25.5\n");
  const auto b =
      motion_with("T1 M6\nG43\nG0 Z5\nT2\nM6\nG43\nG0 Z5\nG43 H1 Z5\nG49\nG0 Z5\nG0 Z[#5422]\n", o);
  ASSERT_EQ(b.size(), 4u);
  EXPECT_DOUBLE_EQ(b[0].end[kZ], 15.0);  // 5 + 10
  EXPECT_DOUBLE_EQ(b[1].end[kZ], 30.5);  // 5 + 25.5: T2 then M6 in the next block
  EXPECT_DOUBLE_EQ(b[2].end[kZ], 15.0);  // G43 H1
  EXPECT_DOUBLE_EQ(b[3].end[kZ], 5.0);   // G49
  // #5422 reads Z in program coordinates: 5 after G49 (no move, so 4 blocks).
}

TEST(ToolLength, ChangingTheOffsetDoesNotMoveAndPositionReadsBackInProgramCoordinates) {
  const Options o = with_table("T3 Z10\n");
  const auto b = motion_with("G0 X1 Z2\nT3 M6 G43\nG0 X[#5420 + 1] Y[#5422]\n", o);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_DOUBLE_EQ(b[1].start[kZ], 2.0);  // G43 alone does not move
  EXPECT_DOUBLE_EQ(b[1].end[kZ], 2.0);    // Z not programmed: the machine stays
  EXPECT_DOUBLE_EQ(b[1].end[kX], 2.0);    // X 1 + 1 (no X offset)
  EXPECT_DOUBLE_EQ(b[1].end[kY], -8.0);   // #5422: Z 2 − 10 in program coordinates
}

TEST(ToolLength, DynamicAndAddedOffsetsInInch) {
  const Options o = with_table("T4 Z2\n");
  const auto b = motion_with("G20\nG43.1 Z0.5\nG0 Z0\nG43.2 H4\nG0 Z0\nG43.2 Z1\nG0 Z0\n", o);
  ASSERT_EQ(b.size(), 3u);
  EXPECT_DOUBLE_EQ(b[0].end[kZ], 12.7);         // 0.5 in
  EXPECT_DOUBLE_EQ(b[1].end[kZ], 12.7 + 2.0);   // + tool 4's 2 mm
  EXPECT_DOUBLE_EQ(b[2].end[kZ], 14.7 + 25.4);  // + 1 in
}

// G53 names the machine position (LinuxCNC backs the tool offset out): the spindle goes there.
TEST(ToolLength, G53GoesToTheMachinePositionWhateverTheToolOffset) {
  const Options o = with_table("T1 Z10\n");
  const auto b = motion_with("G10 L2 P1 Z-50\nT1 M6 G43\nG0 Z-20\nG53 G0 Z0\nG0 Z0\n", o);
  ASSERT_EQ(b.size(), 3u);
  EXPECT_DOUBLE_EQ(b[0].end[kZ], -60.0);  // -20 - 50 + 10
  EXPECT_DOUBLE_EQ(b[1].end[kZ], 0.0);
  EXPECT_DOUBLE_EQ(b[2].end[kZ], -40.0);
}

TEST(ToolTableWrites, G10L1L10L11) {
  const Options o = with_table("T1 Z0\n");
  // L1: the offset itself (program units). L10: the offset that makes the current position
  // read the value. L11: the same with G59.3's offset, without G92.
  const auto b = motion_with(
      "G20\nT1 M6\nG10 L1 P1 Z1\nG43\nG0 X[#5403]\nG21\n"
      "G10 L2 P1 Z-100\nG10 L2 P9 Z-20\nG49\nG0 Z7\n"  // machine Z = -93
      "G10 L10 P1 Z3\nG43\nG0 Y[#5403]\n"              // -93 - (-100) - 3 = 4
      "G10 L11 P1 Z3\nG43\nG0 Y[#5403]\n",             // -93 - (-20) - 3 = -76
      o);
  ASSERT_EQ(b.size(), 4u);
  EXPECT_DOUBLE_EQ(b[0].end[kX], 25.4);  // #5403 in inch after G20: 1 in
  EXPECT_DOUBLE_EQ(b[1].end[kZ], -93.0);
  EXPECT_DOUBLE_EQ(b[2].end[kY], 4.0);
  EXPECT_DOUBLE_EQ(b[3].end[kY], -76.0);
}

TEST(Tools, M61SetsTheToolWithoutAChangeAndUnknownToolsAreErrors) {
  const Options o = with_table("T5 Z8\n");
  const auto b = motion_with("M61 Q5\nG43\nG0 Z0 X#5400\n", o);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_DOUBLE_EQ(b[0].end[kZ], 8.0);
  EXPECT_DOUBLE_EQ(b[0].end[kX], 5.0);
  EXPECT_NE(error_with("T6 M6\n", o).find("tools.ngc:1:1: error: tool 6 is not in the tool table"),
            std::string::npos);
  EXPECT_NE(error_with("G43 H9\n", o).find("1:5: error: tool 9 is not in the tool table"),
            std::string::npos);
  // Without any table every tool exists, with zero offsets.
  EXPECT_EQ(motion_with("T6 M6 G43 H6\nG0 Z1\n", Options{}).at(0).end[kZ], 1.0);
}

TEST(Tools, MachineConfigurationToolsGiveLengthsAndTheFileReplacesThem) {
  MachineConfig m = test_machine();
  ToolSpec t;
  t.number = 2;
  t.length_mm = 30;
  m.cutting.tools.push_back(t);
  EXPECT_DOUBLE_EQ(motion_with("T2 M6 G43\nG0 Z0\n", Options{}, m).at(0).end[kZ], 30.0);
  EXPECT_DOUBLE_EQ(motion_with("T2 M6 G43\nG0 Z0\n", with_table("T2 Z4\n"), m).at(0).end[kZ], 4.0);
}

TEST(Tools, G43Point1WithAMotionInTheSameBlockIsAnError) {
  EXPECT_NE(error_with("G0 G43.1 Z1\n", Options{}).find("G43.1 and G0 both use the axis words"),
            std::string::npos);
}

}  // namespace
}  // namespace cncore::interp::test
