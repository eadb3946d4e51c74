// Canned cycles: the moves each cycle expands into (checked on the emitted blocks: positions
// along the drill axis, rapid or feed, the dwell and spindle events between them).
#include <gtest/gtest.h>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

std::vector<Block> blocks(const std::string& text, const MachineConfig& m = test_machine()) {
  Interpreter in(Interpreter::FromText{}, text, "cycle.ngc", m, Options{});
  std::vector<Block> out;
  Block b;
  while (in.next(b)) out.push_back(b);
  return out;
}

std::string error_of(const std::string& text, const MachineConfig& m = test_machine()) {
  try {
    blocks(text, m);
  } catch (const InputError& e) {
    return e.formatted();
  }
  return {};
}

// "R z" for a rapid to height z along `axis`, "F z" for a feed, "D s" dwell, "M n" spindle.
std::vector<std::string> trace(const std::vector<Block>& bs, std::size_t axis) {
  std::vector<std::string> out;
  for (const Block& b : bs) {
    if (b.kind == BlockKind::kRapid || b.kind == BlockKind::kLine) {
      out.push_back(std::string(b.kind == BlockKind::kRapid ? "R " : "F ") +
                    std::to_string(static_cast<int>(std::lround(b.end[axis] * 100))));
    } else if (b.kind == BlockKind::kDwell) {
      out.push_back("D " + std::to_string(b.dwell_s));
    } else if (b.kind == BlockKind::kAux && b.aux_letter == 'M') {
      out.push_back("M " + std::to_string(static_cast<int>(b.aux_value)));
    }
  }
  return out;
}

using Trace = std::vector<std::string>;

TEST(CannedCycles, G83PecksOutToRAndBackToJustAboveTheLastPeck) {
  const auto t = trace(blocks("G0 Z10\nG83 Z-7 R2 Q3 F100\n"), kZ);
  // R at 2: pecks to -1 and -4, each followed by a rapid to R and back to 0.254 above it.
  const Trace want = {"R 1000", "R 200", "F -100", "R 200",  "R -75",
                      "F -400", "R 200", "R -375", "F -700", "R 1000"};
  EXPECT_EQ(t, want);
}

TEST(CannedCycles, G73BacksOffALittleBetweenPecks) {
  const auto t = trace(blocks("G0 Z10\nG99 G73 Z-7 R2 Q3 F100\n"), kZ);
  const Trace want = {"R 1000", "R 200", "F -100", "R -75", "F -400", "R -375", "F -700", "R 200"};
  EXPECT_EQ(t, want);
}

TEST(CannedCycles, TappingReversesTheSpindleAtTheBottom) {
  const auto t = trace(blocks("G0 Z10\nG98 G84 Z-5 R2 P0.5 F100\nG74 Z-5 R2\n"), kZ);
  // In G98 the tap feeds out to the start height, as LinuxCNC's G84 does.
  const Trace want = {"R 1000", "R 200",      "F -500", "M 5",   "M 4",    "D 0.500000",
                      "F 1000", "M 5",        "M 3",    "R 200", "F -500", "M 5",
                      "M 3",    "D 0.500000", "F 1000", "M 5",   "M 4"};
  EXPECT_EQ(t, want);
}

TEST(CannedCycles, BoringCycles) {
  EXPECT_EQ(trace(blocks("G0 Z10\nG99 G85 Z-5 R2 F100\n"), kZ),
            (Trace{"R 1000", "R 200", "F -500", "F 200"}));
  EXPECT_EQ(trace(blocks("G0 Z10\nG98 G89 Z-5 R2 P1 F100\n"), kZ),
            (Trace{"R 1000", "R 200", "F -500", "D 1.000000", "F 1000"}));
  EXPECT_EQ(trace(blocks("G0 Z10\nG98 G86 Z-5 R2 F100\n"), kZ),
            (Trace{"R 1000", "R 200", "F -500", "M 5", "R 1000", "M 3"}));
  EXPECT_EQ(trace(blocks("G0 Z10\nG98 G88 Z-5 R2 F100\n"), kZ),
            (Trace{"R 1000", "R 200", "F -500", "M 5", "M 0", "R 1000", "M 3"}));
  EXPECT_EQ(trace(blocks("G0 Z10\nG98 G82 Z-5 R2 P2 F100\n"), kZ),
            (Trace{"R 1000", "R 200", "F -500", "D 2.000000", "R 1000"}));
}

// G87: in beside the hole (I J) with the spindle stopped, below the part, centred, bore up to
// K and back at feed, out the same way; in G91 K counts from the bottom.
TEST(CannedCycles, BackBoringEntersBesideTheHoleAndBoresUpward) {
  const auto bs = blocks(
      "S500 M3\nG0 X10 Y10 Z20\nG98 G87 Z-20 R5 I3 J-2 K-10 F100\n"
      "G91 G87 X10 Z-25 R-15 K6\n");
  const Trace want = {"M 3",     "R 2000",  "R 500",  "R 500",   "M 5",
                      "R -2000", "R -2000", "M 3",    "F -1000", "F -2000",
                      "M 5",     "R -2000", "R 2000", "R 2000",  "M 3"};
  const auto t = trace(bs, kZ);
  ASSERT_GE(t.size(), want.size());
  EXPECT_EQ(Trace(t.begin(), t.begin() + static_cast<long>(want.size())), want);
  // The entry beside the hole, and the second hole 10 mm on with its back bore to -20 + 6.
  double top_second = -1e9;
  bool entered_beside = false;
  for (const Block& b : bs) {
    if (b.kind == BlockKind::kRapid && b.end[2] == -20 && b.end[0] == 13 && b.end[1] == 8) {
      entered_beside = true;
    }
    if (b.kind == BlockKind::kLine && b.end[0] == 20) top_second = std::max(top_second, b.end[2]);
  }
  EXPECT_TRUE(entered_beside);
  EXPECT_DOUBLE_EQ(top_second, -14);
  EXPECT_NE(error_of("S500\nG0 Z20\nG87 Z-20 R5 I3 J0 K-10 F100\n").find("G87 needs the spindle"),
            std::string::npos);
  EXPECT_NE(error_of("S500 M3\nG0 Z20\nG87 Z-20 R5 I3 K-10 F100\n").find("G87 without J"),
            std::string::npos);
}

TEST(CannedCycles, OtherPlanesDrillAlongTheirNormal) {
  // G18: the hole at Z X, drilled along Y; G19: at Y Z, along X.
  auto b = blocks("G0 Y10\nG18 G99 G81 Z4 X3 Y-5 R2 F100\n");
  ASSERT_GE(b.size(), 4u);
  EXPECT_EQ(trace(b, kY), (Trace{"R 1000", "R 1000", "R 200", "F -500", "R 200"}));
  EXPECT_DOUBLE_EQ(b[1].end[kX], 3.0);
  EXPECT_DOUBLE_EQ(b[1].end[kZ], 4.0);
  b = blocks("G0 X10\nG19 G99 G81 Y4 Z3 X-5 R2 F100\n");
  EXPECT_EQ(trace(b, kX), (Trace{"R 1000", "R 1000", "R 200", "F -500", "R 200"}));
  EXPECT_DOUBLE_EQ(b[1].end[kY], 4.0);
  EXPECT_DOUBLE_EQ(b[1].end[kZ], 3.0);
}

TEST(CannedCycles, WordsStayInForceUntilG80) {
  const auto b = blocks("G0 Z10\nG99 G81 X1 Y1 Z-1 R1 F100\nX5\nY7\nG80\nG0 X0\n");
  std::vector<double> holes;
  for (const Block& x : b) {
    if (x.kind == BlockKind::kLine) holes.push_back(x.end[kX] * 100 + x.end[kY]);
  }
  EXPECT_EQ(holes, (std::vector<double>{101, 501, 507}));
  EXPECT_NE(error_of("G81 X1 Y1 Z-1 F100\n").find("G81 without R"), std::string::npos);
  EXPECT_NE(error_of("G81 X1 Y1 R1 F100\n").find("G81 without Z"), std::string::npos);
  EXPECT_NE(error_of("G81 X1 Y1 Z-1 R1 F100\nG80\nX2\n").find("without a motion mode"),
            std::string::npos);
}

TEST(CannedCycles, RotaryWordsAreRefused) {
  MachineConfig m = test_machine();
  m.axes[kA].enabled = true;
  m.axes[kA].rotary = true;
  m.axes[kA].min_mm = -360;
  m.axes[kA].max_mm = 360;
  EXPECT_NE(error_of("G81 X0 Y0 Z-1 R0 F12\nA90\n", m)
                .find("cycle.ngc:2:1: error: A word in a "
                      "canned cycle"),
            std::string::npos);
}

TEST(CannedCycles, RepeatsInAbsoluteModeDrillTheSameHole) {
  const auto t = trace(blocks("G0 Z10\nG98 G81 X1 Z-1 R1 L3 F100\n"), kZ);
  EXPECT_EQ(t, (Trace{"R 1000", "R 1000", "R 100", "F -100", "R 1000", "R 100", "F -100", "R 1000",
                      "R 100", "F -100", "R 1000"}));
}

}  // namespace
}  // namespace cncore::interp::test
