// A rotated coordinate system (G10 L2 R): machine = R(θ)·(program + G92) + work + tool. The
// expected machine positions are worked out by hand from that formula.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

struct Outcome {
  std::vector<Block> blocks;
  std::vector<std::string> messages;
};

Outcome interpret(const std::string& text) {
  Options o;
  Outcome r;
  o.on_message = [&](const std::string& m) { r.messages.push_back(m); };
  Interpreter in(Interpreter::FromText{}, text, "rotation.ngc", test_machine(), o);
  Block b;
  while (in.next(b)) {
    if (b.kind == BlockKind::kRapid || b.kind == BlockKind::kLine || b.kind == BlockKind::kArc)
      r.blocks.push_back(b);  // motion only (M2 is an event)
  }
  return r;
}

TEST(Rotation, MovesArcsAndReadingsTurnAboutTheWorkOrigin) {
  // G54 at (10, 5) turned 90°: program (x, y) is machine (10 − y, 5 + x).
  const Outcome r = interpret(
      "G10 L2 P1 X10 Y5 R90\n"
      "G0 X1 Y0\n"
      "G3 X0 Y1 I-1 J0 F100\n"
      "G91 G1 X1\n"
      "G90 (debug,#5420 #5421 #5021 #5022 #<_x> #<_abs_y> #5230)\n"
      "G53 G0 X0 Y0\n"
      "G92 X0 Y0\n"
      "(debug,#5420 #5421 #5211 #5212)\n"
      "G0 X1\n"
      "M2\n");
  ASSERT_EQ(r.blocks.size(), 5u);
  EXPECT_NEAR(r.blocks[0].end[kX], 10.0, 1e-12);
  EXPECT_NEAR(r.blocks[0].end[kY], 6.0, 1e-12);
  const Block& arc = r.blocks[1];
  ASSERT_EQ(arc.kind, BlockKind::kArc);
  EXPECT_NEAR(arc.center.x, 10.0, 1e-12);  // the centre turns too
  EXPECT_NEAR(arc.center.y, 5.0, 1e-12);
  EXPECT_NEAR(arc.end[kX], 9.0, 1e-12);
  EXPECT_NEAR(arc.end[kY], 5.0, 1e-12);
  EXPECT_EQ(arc.normal.z, 1.0);
  // G91 X1: along the turned X axis, i.e. machine +Y.
  EXPECT_NEAR(r.blocks[2].end[kX], 9.0, 1e-12);
  EXPECT_NEAR(r.blocks[2].end[kY], 6.0, 1e-12);
  // G53 is not turned.
  EXPECT_NEAR(r.blocks[3].end[kX], 0.0, 1e-12);
  EXPECT_NEAR(r.blocks[3].end[kY], 0.0, 1e-12);
  ASSERT_EQ(r.messages.size(), 2u);
  EXPECT_EQ(r.messages[0], "1.000000 1.000000 9.000000 6.000000 1.000000 6.000000 90.000000");
  // At machine (0, 0) the program reads R(−90°)·(−10, −5) = (−5, 10); G92 makes it 0 0 with
  // its offset in the turned frame.
  EXPECT_EQ(r.messages[1], "0.000000 0.000000 -5.000000 10.000000");
  // G0 X1 after G92: program (1, 0) + G92 (−5, 10) turned, plus the work offset.
  EXPECT_NEAR(r.blocks[4].end[kX], 10.0 - 10.0, 1e-12);
  EXPECT_NEAR(r.blocks[4].end[kY], 5.0 - 4.0, 1e-12);
}

TEST(Rotation, G10L20KeepsTheReadingOfTheAxesItDoesNotName) {
  const Outcome r = interpret(
      "G0 X3 Y4\n"
      "G10 L20 P1 X1 R30\n"
      "(debug,#5420 #5421)\n"
      "M2\n");
  ASSERT_EQ(r.messages.size(), 1u);
  EXPECT_EQ(r.messages[0], "1.000000 4.000000");
}

}  // namespace
}  // namespace cncore::interp::test
