// Spindle-synchronised motion on the blocks: G33 and G33.1 carry their pitch and the feed it
// makes with S, a series of them starts from rest, G76's passes follow LinuxCNC's depths, G96
// sets the spindle speed from the radius; and the errors a threading program can make.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

std::vector<Block> blocks(const std::string& text) {
  Interpreter in(Interpreter::FromText{}, text, "thread.ngc", test_machine(), Options{});
  std::vector<Block> out;
  Block b;
  while (in.next(b)) out.push_back(b);
  return out;
}

std::string error_of(const std::string& text) {
  return error_of_text(text, "thread.ngc");
}

TEST(Threading, G33FollowsTheSpindleAndStartsFromRest) {
  const auto b = blocks("G18 G21 G90 S400 M3\nG0 X10 Z5\nG33 Z-40 K1.5\nG33 X12 Z-45 K2\nG0 X20\n");
  std::vector<Block> sync;
  std::size_t waits = 0;
  for (const Block& x : b) {
    if (x.kind == BlockKind::kLine && x.sync_mm_rev > 0) sync.push_back(x);
    if (x.kind == BlockKind::kDwell && x.dwell_s == 0 && x.index_wait) ++waits;
  }
  ASSERT_EQ(sync.size(), 2U);
  EXPECT_DOUBLE_EQ(sync[0].feed_mm_min, 1.5 * 400);
  EXPECT_DOUBLE_EQ(sync[1].feed_mm_min, 2 * 400);
  EXPECT_TRUE(sync[0].override_fixed);
  EXPECT_EQ(waits, 1U) << "one index wait before the series, none between its moves";
}

// M19 orients the spindle and stops it there: an event the motion waits for, after which a
// synchronised move needs M3 or M4 again.
TEST(Threading, M19OrientsAndStopsTheSpindle) {
  const auto b = blocks("G18 G21 G90 S400 M3\nG0 X10 Z5\nM19 R90 P2 Q5\nG0 X12\n");
  std::vector<double> m;
  bool waits = false;
  for (const Block& x : b) {
    if (x.kind != BlockKind::kAux || x.aux_letter != 'M') continue;
    m.push_back(x.aux_value);
    if (x.aux_value == 19) waits = x.aux_waits;
  }
  EXPECT_EQ(m, (std::vector<double>{3, 19}));
  EXPECT_TRUE(waits);
  EXPECT_NE(error_of("G18 G21 S400 M3\nM19\nG33 Z-10 K1\n").find("needs the spindle turning"),
            std::string::npos);
  EXPECT_NE(error_of("M19 P3\n").find("thread.ngc:1:5: error: M19 P must be 0, 1 or 2"),
            std::string::npos);
  EXPECT_NE(error_of("M19 R10 Q0\n").find("M19 Q (the time allowed) must be > 0"),
            std::string::npos);
}

// G64 R (a LinuxCNC-derived planner's scale) changes nothing; beside M19 its R is ambiguous.
TEST(Threading, G64RChangesNothingAndBesideM19IsRefused) {
  const auto plain = blocks("G21 G64 P0.1\nG1 X10 F100\n");
  const auto with_r = blocks("G21 G64 P0.1 R0.5\nG1 X10 F100\n");
  ASSERT_EQ(plain.size(), with_r.size());
  EXPECT_EQ(plain.back().path_mode, with_r.back().path_mode);
  EXPECT_EQ(plain.back().tolerance_mm, with_r.back().tolerance_mm);
  EXPECT_NE(error_of("G64 R-1\n").find("thread.ngc:1:5: error: negative G64 R"), std::string::npos);
  EXPECT_NE(error_of("G64 M19 R90 S0\n").find("thread.ngc:1:9: error: R is ambiguous"),
            std::string::npos);
}

// As rs274 lists them: the pitch before the synchronised moves, no DWELL for the index wait.
TEST(Threading, CanonicalListingHasTheSyncCallsAndNoIndexWait) {
  Interpreter in(Interpreter::FromText{}, "G18 G21 G90 S400 M3\nG0 X10 Z5\nG33 Z-40 K1.5\nG0 X20\n",
                 "thread.ngc", test_machine(), Options{});
  CanonPrinter p;
  std::string canon;
  Block b;
  while (in.next(b)) canon += p.print(b, in.canon_frame());
  EXPECT_EQ(canon,
            "STRAIGHT_TRAVERSE(10.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n"
            "START_SPEED_FEED_SYNC(1.500000,0)\n"
            "STRAIGHT_FEED(10.0000, 0.0000, -40.0000, 0.0000, 0.0000, 0.0000)\n"
            "STOP_SPEED_FEED_SYNCH()\n"
            "STRAIGHT_TRAVERSE(20.0000, 0.0000, -40.0000, 0.0000, 0.0000, 0.0000)\n");
}

std::string canon_of(const std::string& text) {
  Interpreter in(Interpreter::FromText{}, text, "thread.ngc", test_machine(), Options{});
  CanonPrinter p;
  std::string canon;
  Block b;
  while (in.next(b)) canon += p.print(b, in.canon_frame());
  return canon;
}

// D reaches the listing as the start angle of each synchronisation (its magnitude), and a
// G33.1 is LinuxCNC's one RIGID_TAP call, the way out below the interface.
TEST(Threading, CanonicalListingCarriesTheStartAngleAndOneRigidTap) {
  EXPECT_EQ(canon_of("G18 G21 G90 S400 M3\nG0 X10 Z5\nG33 Z-40 K1.5 D-90\nG0 X20\n"),
            "STRAIGHT_TRAVERSE(10.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n"
            "START_SPEED_FEED_SYNC(1.500000,0,90.000000)\n"
            "STRAIGHT_FEED(10.0000, 0.0000, -40.0000, 0.0000, 0.0000, 0.0000)\n"
            "STOP_SPEED_FEED_SYNCH()\n"
            "STRAIGHT_TRAVERSE(20.0000, 0.0000, -40.0000, 0.0000, 0.0000, 0.0000)\n");
  EXPECT_EQ(canon_of("G17 G21 G90 S300 M3\nG0 X5 Y5 Z2\nG33.1 Z-10 K1.25\nG0 Z20\n"),
            "STRAIGHT_TRAVERSE(5.0000, 5.0000, 2.0000, 0.0000, 0.0000, 0.0000)\n"
            "START_SPEED_FEED_SYNC(1.250000,0)\n"
            "RIGID_TAP(5.0000, 5.0000, -10.0000)\n"
            "STOP_SPEED_FEED_SYNCH()\n"
            "STRAIGHT_TRAVERSE(5.0000, 5.0000, 20.0000, 0.0000, 0.0000, 0.0000)\n");
  // G76 with an exit taper: every start of a pass has the angle but the exit taper's.
  const std::string g76 =
      canon_of("G18 G21 G90 S500 M3\nG0 X20 Z5\nG76 P2 Z-30 I-1 J1 K1 E2 L2 D30\n");
  EXPECT_NE(g76.find("START_SPEED_FEED_SYNC(2.000000,0,30.000000)"), std::string::npos) << g76;
  EXPECT_NE(g76.find("START_SPEED_FEED_SYNC(2.236068,0)"), std::string::npos) << g76;
  EXPECT_EQ(g76.find("2.236068,0,30"), std::string::npos) << g76;
}

// `check --blocks` shows which moves follow the spindle: the pitch, D's start angle, the rigid
// tap's way in and out, and the index wait before a series.
TEST(Threading, BlockListingMarksSynchronisedMoves) {
  const MachineConfig m = test_machine();
  const auto g33 = listing("G18 G21 G90 S400 M3\nG0 X10 Z5\nG33 Z-40 K1.5 D-90\nG0 X20\n", m);
  ASSERT_EQ(g33.size(), 6U);
  EXPECT_EQ(g33[3], "N3 DWELL 0.000 s INDEX");
  EXPECT_NE(g33[4].find(" F600.000 SYNC 1.5000 START 90.0000"), std::string::npos) << g33[4];
  EXPECT_EQ(g33[5].find("SYNC"), std::string::npos) << g33[5];
  const auto tap = listing("G17 G21 G90 S300 M3\nG0 X5 Y5 Z2\nG33.1 Z-10 K1.25\nG0 Z20\n", m);
  std::vector<std::string> marks;
  for (const std::string& line : tap) {
    if (line.find("TAP IN") != std::string::npos) marks.emplace_back("in");
    if (line.find("TAP OUT") != std::string::npos) marks.emplace_back("out");
  }
  EXPECT_EQ(marks, (std::vector<std::string>{"in", "out"}));
}

TEST(Threading, RigidTapGoesInReversesAndComesBackFaster) {
  const auto b = blocks("G17 G21 G90 S300 M3\nG0 X5 Y5 Z2\nG33.1 Z-10 K1.25 I2\nG0 Z20\n");
  std::vector<Block> sync;
  std::vector<double> m;
  for (const Block& x : b) {
    if (x.kind == BlockKind::kLine && x.sync_mm_rev > 0) sync.push_back(x);
    if (x.kind == BlockKind::kAux && x.aux_letter == 'M') m.push_back(x.aux_value);
  }
  ASSERT_EQ(sync.size(), 2U);
  EXPECT_DOUBLE_EQ(sync[0].end[2], -10);
  EXPECT_DOUBLE_EQ(sync[1].end[2], 2);
  EXPECT_DOUBLE_EQ(sync[0].feed_mm_min, 1.25 * 300);
  EXPECT_DOUBLE_EQ(sync[1].feed_mm_min, 1.25 * 600);
  EXPECT_EQ(sync[0].path_mode, PathMode::kExactStop);
  EXPECT_EQ(m, (std::vector<double>{3, 4, 3}));
}

// G76 P2 Z-30 I-1 J0.1 K1.2 R2 H2: depths 0.1·√n while below 1.2 (n = 1 … 143), then 1.2 three
// times; every pass cuts along Z at X = peaks − depth.
TEST(Threading, G76PassesCutTheDegressionDepthsThenTheSpringPasses) {
  const auto b = blocks("G18 G21 G90 S500 M3\nG0 X20 Z5\nG76 P2 Z-30 I-1 J0.1 K1.2 R2 H2\n");
  std::vector<double> cut_x;
  for (const Block& x : b) {
    if (x.kind == BlockKind::kLine && x.sync_mm_rev > 0 && x.start[0] == x.end[0]) {
      cut_x.push_back(x.end[0]);
    }
  }
  std::vector<double> want;
  for (int n = 1; 0.1 * std::sqrt(n) < 1.2; ++n) want.push_back(19 - 0.1 * std::sqrt(n));
  for (int k = 0; k < 3; ++k) want.push_back(19 - 1.2);
  ASSERT_EQ(cut_x.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(cut_x[i], want[i], 1e-9) << i;
  EXPECT_DOUBLE_EQ(b.back().end[0], 20);
  EXPECT_DOUBLE_EQ(b.back().end[2], -30);
}

// D on G33 and G76 is the thread's start angle (LinuxCNC): accepted, and with a spindle that
// has no angle it leaves the motion as it is.
TEST(Threading, StartAngleDLeavesTheMotion) {
  for (const std::string code : {"G33 Z-40 K1.5", "G76 P2 Z-30 I-1 J0.1 K1.2 R2 H2"}) {
    const std::string head = "G18 G21 G90 S500 M3\nG0 X20 Z5\n";
    const auto plain = blocks(head + code + "\n");
    const auto angled = blocks(head + code + " D-90\n");
    ASSERT_EQ(plain.size(), angled.size()) << code;
    for (std::size_t i = 0; i < plain.size(); ++i) {
      for (std::size_t a = 0; a < 3; ++a) EXPECT_EQ(plain[i].end[a], angled[i].end[a]) << code;
    }
  }
}

TEST(Threading, ConstantSurfaceSpeedFollowsTheRadiusUpToD) {
  // 150 m/min: 150000 / (2π·r) rpm, capped at D2000 below r = 11.94 mm.
  const auto b = blocks("G18 G21 G90 G0 X40 Z0\nG96 S150 D2000 M3\nG95 G1 X0 F0.1\n");
  double last_rpm = 0;
  bool checked = false;
  for (const Block& x : b) {
    if (x.kind == BlockKind::kAux && x.aux_letter == 'S') last_rpm = x.aux_value;
    if (x.kind != BlockKind::kLine) continue;
    const double r_mid = std::fabs(x.start[0] + x.end[0]) / 2;
    const double want = std::min(2000.0, 150000 / (2 * std::numbers::pi * r_mid));
    EXPECT_NEAR(last_rpm, want, want * 0.021) << "at r " << r_mid;
    EXPECT_NEAR(x.feed_mm_min, 0.1 * last_rpm, 1e-9);
    const double r0 = std::fabs(x.start[0]), r1 = std::fabs(x.end[0]);
    if (r1 > 11.94) {
      EXPECT_LE(r0 / r1, 1.0 + 0.0205) << "a piece spans at most 2 % of speed";
    }
    checked = true;
  }
  EXPECT_TRUE(checked);
  EXPECT_DOUBLE_EQ(last_rpm, 2000);
}

TEST(Threading, ErrorsAreAtTheLine) {
  EXPECT_NE(error_of("G21 S400 M3\nG33 Z-10\n").find("thread.ngc:2:1: error: G33 without K"),
            std::string::npos);
  EXPECT_NE(error_of("G21 S400\nG33 Z-10 K1\n").find("2:1: error: G33 needs the spindle turning"),
            std::string::npos);
  EXPECT_NE(error_of("G17 G21 S400 M3\nG76 P1 Z-10 I-1 J0.1 K0.6\n")
                .find("2:1: error: G76 needs the ZX plane"),
            std::string::npos);
  EXPECT_NE(error_of("G18 G21 S400 M3\nG76 P1 Z-10 I-1 J0.1\n").find("G76 without K"),
            std::string::npos);
  EXPECT_NE(error_of("G18 G21 G0 X10\nG96 S100 M3\nG1 X0 F100\n").find("G96 at X0 without D"),
            std::string::npos);
  // 10 mm per revolution at 5000 rpm is 50 m/min along Z: beyond the test machine's axis.
  EXPECT_NE(error_of("G18 G21 S5000 M3\nG33 Z-10 K10\n").find("beyond its limit"),
            std::string::npos);
  EXPECT_NE(error_of("G21 G0 E5\n").find("1:8: error: unknown word 'E'"), std::string::npos);
}

}  // namespace
}  // namespace cncore::interp::test
