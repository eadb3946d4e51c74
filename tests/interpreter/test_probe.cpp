// G38.2–G38.5 against the simulated probe's solids ([probe] boxes and the [stock] box): where the
// move ends, and #5061…#5070 as a program reads them, measured on the blocks and the messages.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

struct Probed {
  std::vector<Block> moves;
  std::vector<std::string> messages;
};

// A plate X −50…50, Y −50…50 with its top at Z −2, and a 10 mm cube standing on it at X 20…30.
MachineConfig probe_machine() {
  MachineConfig m = test_machine();
  m.probe.boxes = {ProbeBox{{-50, -50, -30}, {50, 50, -2}}, ProbeBox{{20, -5, -2}, {30, 5, 8}}};
  return m;
}

Probed run(const std::string& text, const MachineConfig& m = probe_machine()) {
  Probed p;
  Options o;
  o.on_message = [&p](const std::string& s) { p.messages.push_back(s); };
  Interpreter in(Interpreter::FromText{}, text, "probe.ngc", m, o);
  Block b;
  while (in.next(b)) {
    if (is_motion(b)) p.moves.push_back(b);
  }
  return p;
}

std::string error_of(const std::string& text, const MachineConfig& m = probe_machine()) {
  try {
    run(text, m);
  } catch (const InputError& e) {
    return e.formatted();
  }
  return {};
}

TEST(Probe, TowardStopsWhereTheTipMeetsTheSurfaceAndRecordsIt) {
  // G55 shifts X by 5: the result is in the coordinates the probe ran in.
  const Probed p = run(
      "G21 G90 G10 L2 P2 X5\nG55 G0 X0 Y0 Z5\nG38.2 Z-20 F100\n(debug,#5061 #5062 #5063 #5070)\n");
  ASSERT_EQ(p.moves.size(), 2U);
  EXPECT_NEAR(p.moves[1].end[2], -2, 1e-12);  // machine Z of the plate's top
  EXPECT_DOUBLE_EQ(p.moves[1].feed_mm_min, 100);
  EXPECT_EQ(p.moves[1].path_mode, PathMode::kExactStop);  // the machine stops at the trip
  ASSERT_EQ(p.messages.size(), 1U);
  EXPECT_EQ(p.messages[0], "0.000000 0.000000 -2.000000 1.000000");
}

TEST(Probe, ASideOfTheCubeAlongX) {
  const Probed p = run("G21 G90 G0 X0 Y0 Z3\nG38.2 X40 F200\n(debug,#5061 #5070)\n");
  ASSERT_EQ(p.moves.size(), 2U);
  EXPECT_NEAR(p.moves[1].end[0], 20, 1e-12);
  EXPECT_EQ(p.messages.at(0), "20.000000 1.000000");
}

TEST(Probe, InchesAreReportedInInches) {
  const Probed p = run("G20 G90 G0 X0 Y0 Z1\nG38.2 Z-1 F10\n(debug,#5063)\n");
  EXPECT_EQ(p.messages.at(0), fmt::format("{:.6f}", -2 / 25.4));
}

TEST(Probe, G38_3WithoutContactGoesToTheTargetAndSaysSo) {
  const Probed p = run("G21 G90 G0 X0 Y0 Z20\nG38.3 X10 F200\n(debug,#5061 #5070)\n");
  ASSERT_EQ(p.moves.size(), 2U);
  EXPECT_NEAR(p.moves[1].end[0], 10, 1e-12);
  EXPECT_EQ(p.messages.at(0), "10.000000 0.000000");
}

TEST(Probe, AwayStopsWhereContactIsLost) {
  // From inside the plate up through the cube's top: contact is lost at Z 8, not at Z −2.
  const Probed p = run("G21 G90 G0 X25 Y0 Z-5\nG38.4 Z20 F50\n(debug,#5063 #5070)\n");
  ASSERT_EQ(p.moves.size(), 2U);
  EXPECT_NEAR(p.moves[1].end[2], 8, 1e-12);
  EXPECT_EQ(p.messages.at(0), "8.000000 1.000000");
}

TEST(Probe, TheModeIsModalAndTheToolLengthOffsetIsTakenOff) {
  // Tool 1 is 10 mm long: the controlled point stops 10 mm above the surface.
  MachineConfig m = probe_machine();
  m.cutting.tools.push_back(ToolSpec{});
  m.cutting.tools.back().number = 1;
  m.cutting.tools.back().length_mm = 10;
  // G38.3 stays in force: the line "Z-10" after it probes too (without contact first, then down
  // to the plate).
  const Probed p = run("G21 G90 T1 M6 G43 H1\nG0 X0 Y0 Z20\nG38.3 X-40 F100\nZ-10\n", m);
  ASSERT_EQ(p.moves.size(), 3U);
  EXPECT_NEAR(p.moves[1].end[0], -40, 1e-12);
  EXPECT_NEAR(p.moves[2].end[2], -2 + 10, 1e-12);
  EXPECT_DOUBLE_EQ(p.moves[2].feed_mm_min, 100);
}

TEST(Probe, StockIsTouchedUnlessTurnedOff) {
  MachineConfig m = test_machine();
  m.cutting.stock.enabled = true;
  m.cutting.stock.min_mm = {0, 0, -20};
  m.cutting.stock.size_mm = {50, 50, 20};
  const std::string text = "G21 G90 G0 X10 Y10 Z10\nG38.2 Z-10 F100\n";
  EXPECT_NEAR(run(text, m).moves.back().end[2], 0, 1e-12);
  m.probe.touch_stock = false;
  EXPECT_EQ(error_of(text, m), "probe.ngc:2:1: error: G38.2: the move ended without contact");
}

TEST(Probe, ErrorsAtTheLine) {
  EXPECT_EQ(error_of("G21 G90 G0 X0 Y0 Z5\nG38.2 Z-1 F100\n"),
            "probe.ngc:2:1: error: G38.2: the move ended without contact");
  EXPECT_EQ(error_of("G21 G90 G0 X0 Y0 Z5\nG38.2 Z-10\n"),
            "probe.ngc:2:1: error: no feed rate: program F before the first G1/G2/G3");
  EXPECT_EQ(error_of("G21 G90 G0 X0 Y0 Z5\nG93 G38.2 Z-10 F1\n"),
            "probe.ngc:2:5: error: G38.2 with inverse time feed G93: probe in G94");
  EXPECT_EQ(error_of("G21 G90 G0 X0 Y0 Z-5\nG38.2 Z-10 F100\n"),
            "probe.ngc:2:1: error: G38.2: the probe is already tripped at the start of the move");
  EXPECT_EQ(error_of("G21 G90 G0 X0 Y0 Z5\nG38.4 Z10 F100\n"),
            "probe.ngc:2:1: error: G38.4: the probe is not tripped at the start of a move away "
            "from the part");
  EXPECT_EQ(error_of("G21 G90 F100\nG38.3\n"), "probe.ngc:2:1: error: G38.3 without axis words");
  EXPECT_EQ(error_of("G21 G90 G0 X0 Y0 Z5\nG38.2 Z4.9 F100\n"),
            "probe.ngc:2:1: error: G38.2: the target is within 0.254 mm of the start (LinuxCNC's "
            "minimum probe move)");
}

}  // namespace
}  // namespace cncore::interp::test
