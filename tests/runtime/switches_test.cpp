// The operator switches of `cncore serve` measured on the set-points: single block switched on
// while a program runs stops the tool at the end of a programmed block; block delete decides
// whether "/" lines run, and a program is checked again at cycle start with the switch in force.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "served.hpp"

namespace cncore::runtime {
namespace {

using testing::Served;

std::string write_program(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

bool stopped(const Status& s) {
  return s.state == MachineState::kHold && s.hold_complete;
}

TEST(Switches, SingleBlockOnWhileRunningStopsAtTheEndOfAProgrammedBlock) {
  // A zigzag of 2 mm blocks (no two collinear, so none is merged), 120 of them.
  std::string text = "G21 G90 G64\nG1 X0 Y0 F3000\n";
  for (int i = 1; i <= 120; ++i) text += fmt::format("G1 X{} Y{}\n", 2 * i, (i % 2) * 2);
  text += "M30\n";
  // A short look-ahead buffer: most of the program reaches the kernel after the switch, with
  // the single-block pauses after its blocks (the test below: with the whole buffer ahead).
  MachineConfig m = default_machine_config();
  m.lookahead_blocks = 16;
  Served sv(m);
  ASSERT_TRUE(sv.c().load_program(write_program("zigzag.ngc", text)).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  sv.wait_cycles(100);
  ASSERT_EQ(sv.c().status().state, MachineState::kRun);
  const double x_at_switch = sv.c().status().commanded[kX];
  ASSERT_TRUE(sv.c().set_switches(Switches{false, true}).ok);
  ASSERT_TRUE(sv.wait_for(stopped));
  // Stopped on a vertex of the zigzag, the end of a block: X a multiple of 2 and Y its parity.
  const AxisVec p = sv.c().status().commanded;
  const double i = std::round(p[kX] / 2);
  EXPECT_NEAR(p[kX], 2 * i, 1e-9);
  EXPECT_NEAR(p[kY], std::fmod(i, 2) * 2, 1e-9);
  EXPECT_GT(p[kX], x_at_switch);
  EXPECT_LE(p[kX], x_at_switch + 2 * (m.lookahead_blocks + 1));
  // Cycle start runs one more block and stops at its end.
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_for([](const Status& s) { return s.state == MachineState::kRun; }));
  ASSERT_TRUE(sv.wait_for(stopped));
  EXPECT_NEAR(sv.c().status().commanded[kX], 2 * i + 2, 1e-9);
  // Off again: the program runs to its end without another stop.
  ASSERT_TRUE(sv.c().set_switches(Switches{false, false}).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_EQ(sv.c().status().commanded[kX], 240);
  // The path never left the zigzag, and the tool came to rest at the stops (speed by
  // differences of the set-points: zero over consecutive cycles at the vertex).
  const auto s = sv.samples();
  bool rested = false;
  for (std::size_t n = 1; n < s.size(); ++n) {
    if (s[n].position == s[n - 1].position && std::abs(s[n].position[kX] - 2 * i) < 1e-9) {
      rested = true;
    }
  }
  EXPECT_TRUE(rested);
}

TEST(Switches, SingleBlockOnWithTheWholeBufferAheadStopsWithinTheBlocksBrakingNeeds) {
  // 12 000 blocks of a zigzag (vertex i at X = 2·i), more than the default 10 000-block
  // look-ahead buffer, which is full when the switch goes on: every block it holds came without
  // a program stop after it, so the kernel itself stops at the first block end it can reach.
  // At F6000 the tool slows to the 90° corners at every vertex, so braking takes at most the
  // rest of one block: it stops at the end of the block under it or of the next one.
  std::string text = "G21 G90 G64\nG1 X0 Y0 F6000\n";
  for (int i = 1; i <= 12000; ++i) text += fmt::format("G1 X{} Y{}\n", 2 * i, (i % 2) * 2);
  text += "M30\n";
  MachineConfig m = default_machine_config();
  ASSERT_EQ(m.lookahead_blocks, 10000U);
  m.axes[kX].max_mm = 25000;  // the zigzag's 24 m
  Served sv(m);
  ASSERT_TRUE(sv.c().load_program(write_program("zigzag-12k.ngc", text)).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  sv.wait_cycles(300);
  ASSERT_EQ(sv.c().status().state, MachineState::kRun);
  ASSERT_TRUE(sv.c().set_switches(Switches{false, true}).ok);
  ASSERT_TRUE(sv.wait_for(stopped, 10));
  const AxisVec p = sv.c().status().commanded;
  const double k = std::round(p[kX] / 2);
  EXPECT_NEAR(p[kX], 2 * k, 1e-9);
  EXPECT_NEAR(p[kY], std::fmod(k, 2) * 2, 1e-9);
  // Where the tool was in the first cycle with the switch on (the samples are by cycle).
  std::uint64_t on_cycle = 0;
  for (const AppliedCommand& a : sv.applied()) {
    if (a.command == Command::kSwitches) on_cycle = a.cycle;
  }
  const auto s = sv.samples();
  ASSERT_GT(on_cycle, 0U);
  ASSERT_LT(on_cycle, s.size());
  const double block_at_switch = std::floor(s[on_cycle].position[kX] / 2) + 1;  // its end vertex
  EXPECT_GE(k, block_at_switch);
  EXPECT_LE(k, block_at_switch + 1) << "switched on at X " << s[on_cycle].position[kX];
  // Cycle start runs one more block (its blocks had no program stop either).
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_for([](const Status& st) { return st.state == MachineState::kRun; }));
  ASSERT_TRUE(sv.wait_for(stopped, 10));
  EXPECT_NEAR(sv.c().status().commanded[kX], 2 * k + 2, 1e-9);
  // Off again: the tool runs on past the next vertex without stopping there.
  ASSERT_TRUE(sv.c().set_switches(Switches{false, false}).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_for([&](const Status& st) { return st.commanded[kX] > 2 * k + 10; }, 10));
  EXPECT_EQ(sv.c().status().state, MachineState::kRun);
}

TEST(Switches, BlockDeleteOffRunsSlashLinesAndTheProgramIsCheckedAgainAtCycleStart) {
  Served sv(default_machine_config());
  const std::string program =
      write_program("slash.ngc", "G21 G90\nG1 X10 F3000\n/G1 Y10\nG1 X20\nM30\n");
  ASSERT_TRUE(sv.c().load_program(program).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_EQ(sv.c().status().commanded[kY], 0);  // skipped: the switch is on by default

  Switches off;
  off.block_delete = false;
  ASSERT_TRUE(sv.c().set_switches(off).ok);
  ASSERT_TRUE(sv.c().mdi("G0 X0 Y0").ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_EQ(sv.c().status().commanded[kY], 10);
  EXPECT_EQ(sv.c().status().commanded[kX], 20);

  // A "/" line beyond the travel: loaded with the switch on (fine), refused at cycle start once
  // the switch is off, at its line, before anything moves.
  ASSERT_TRUE(sv.c().set_switches(Switches{}).ok);
  const std::string far =
      write_program("slash-far.ngc", "G21 G90\nG1 X10 F3000\n/G1 Y5000\nG1 X20\nM30\n");
  ASSERT_TRUE(sv.c().load_program(far).ok);
  ASSERT_TRUE(sv.c().set_switches(off).ok);
  const AxisVec before = sv.c().status().commanded;
  const Result r = sv.c().cycle_start();
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.error.find("slash-far.ngc:3:"), std::string::npos) << r.error;
  sv.wait_cycles(50);
  EXPECT_EQ(sv.c().status().commanded, before);
  EXPECT_EQ(sv.c().status().state, MachineState::kIdle);
}

}  // namespace
}  // namespace cncore::runtime
