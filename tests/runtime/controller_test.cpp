// `cncore serve`'s controller driven through its control interface, measured on the set-points
// it produced (every cycle's sample), against `cncore run`'s kernel and the trajectory checker.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "interpreter/interpreter.hpp"
#include "served.hpp"
#include "simulation/stepper.hpp"
#include "support/limits.hpp"
#include "support/program_blocks.hpp"
#include "support/trajectory_checker.hpp"

namespace cncore::runtime {
namespace {

using testing::Served;

std::string example(const std::string& name) {
  return std::string(CNCORE_SOURCE_DIR) + "/examples/" + name;
}

std::string write_program(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

std::uint64_t applied_cycle(const std::vector<AppliedCommand>& ap, Command c) {
  for (const AppliedCommand& a : ap) {
    if (a.command == c) return a.cycle;
  }
  ADD_FAILURE() << "command " << command_name(c) << " was never applied";
  return 0;
}

// Replays the served run's commands, at the cycles they took effect, on the kernel `cncore run`
// uses (sim::ProgramStepper), and compares every set-point bit for bit.
void expect_same_as_run(Served& sv, const std::string& program) {
  const std::vector<motion::Sample> served = sv.samples();
  const std::vector<AppliedCommand> ap = sv.applied();
  const std::uint64_t s0 = applied_cycle(ap, Command::kStart);
  sim::ProgramStepper ref(program, sv.machine(), motion::kernel_options_for(sv.machine()));
  motion::Sample r;
  std::uint64_t k = 0;
  cncore::testing::Trajectory traj;
  for (;; ++k) {
    const std::uint64_t n = s0 + k;
    for (const AppliedCommand& a : ap) {
      if (a.cycle != n || a.cycle <= s0) continue;
      if (a.command == Command::kFeedOverride) ref.kernel().set_override(a.value);
      if (a.command == Command::kHold) ref.kernel().set_feed_hold(true);
      if (a.command == Command::kResume) ref.kernel().set_feed_hold(false);
    }
    if (!ref.next(r)) break;
    ASSERT_LT(n, served.size());
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      ASSERT_EQ(served[n].position[i], r.position[i]) << "cycle " << k << " axis " << i;
    }
    traj.add_sample(served[n]);
  }
  ASSERT_GT(k, 100U);
  // The served trajectory holds every limit of the program (independent checker).
  const auto blocks = cncore::testing::read_blocks(program, sv.machine());
  const auto rep = cncore::testing::check_trajectory(
      traj, blocks, cncore::testing::limits_from_config(sv.machine()));
  EXPECT_TRUE(rep.ok()) << rep.summary();
}

TEST(Controller, ServedProgramGivesTheSetPointsOfRun) {
  Served sv(default_machine_config());
  const std::string program = example("seed-line-arc-line.ngc");
  ASSERT_TRUE(sv.c().load_program(program).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  expect_same_as_run(sv, program);
  EXPECT_EQ(sv.c().status().starved_cycles, 0U);
}

TEST(Controller, HoldResumeAndOverrideStepsKeepTheSetPointsOfRun) {
  Served sv(default_machine_config());
  const std::string program = example("pocket-with-arcs.ngc");
  ASSERT_TRUE(sv.c().load_program(program).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  sv.wait_cycles(150);
  ASSERT_TRUE(sv.c().set_feed_override(40).ok);
  sv.wait_cycles(250);
  ASSERT_TRUE(sv.c().set_feed_override(160).ok);
  sv.wait_cycles(200);
  ASSERT_TRUE(sv.c().feed_hold().ok);
  ASSERT_TRUE(sv.wait_for([](const Status& s) { return s.hold_complete; }));
  const AxisVec held = sv.c().status().commanded;
  sv.wait_cycles(50);
  EXPECT_EQ(sv.c().status().commanded, held);  // stays where it stopped
  ASSERT_TRUE(sv.c().cycle_start().ok);        // resume
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  expect_same_as_run(sv, program);
}

TEST(Controller, EStopDuringARapidFreezesTheSetPointsInTheNextCycle) {
  Served sv(default_machine_config());
  ASSERT_TRUE(sv.c().mdi("G0 X250 Y150").ok);
  ASSERT_TRUE(sv.wait_for([](const Status& s) { return s.feed_mm_min > 8000; }));
  ASSERT_TRUE(sv.c().estop().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kAlarm));
  sv.wait_cycles(20);
  EXPECT_EQ(sv.c().status().alarm, AlarmCode::kEStop);
  const auto samples = sv.samples();
  const std::uint64_t e = applied_cycle(sv.applied(), Command::kEStop);
  ASSERT_GT(e, 0U);
  ASSERT_LT(e + 10, samples.size());
  EXPECT_NE(samples[e - 1].position, samples[e - 2].position);  // it was moving
  for (std::uint64_t n = e; n < samples.size(); ++n) {
    ASSERT_EQ(samples[n].position, samples[e - 1].position) << "cycle " << n;
  }
  // Latched: a reset does not clear it, nothing starts, unlock does.
  EXPECT_TRUE(sv.c().reset().ok);
  sv.wait_cycles(5);
  EXPECT_EQ(sv.c().status().state, MachineState::kAlarm);
  EXPECT_FALSE(sv.c().mdi("G0 X0").ok);
  EXPECT_TRUE(sv.c().clear_alarm().ok);
  EXPECT_TRUE(sv.wait_state(MachineState::kIdle));
}

TEST(Controller, AProgramLeavingTheTravelIsRefusedAtItsLineBeforeAnyMotion) {
  Served sv(default_machine_config());
  const std::string program =
      write_program("soft-limit.ngc", "G21 G90\nG0 X10 Y10\nG1 X100 F2000\nG1 Y320\nM30\n");
  const Result r = sv.c().load_program(program);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("soft-limit.ngc:4:"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("travel"), std::string::npos) << r.error;
  EXPECT_FALSE(sv.c().cycle_start().ok);  // nothing loaded
  const Result m = sv.c().mdi("G0 Y500");
  EXPECT_FALSE(m.ok);
  sv.wait_cycles(20);
  for (const motion::Sample& s : sv.samples()) ASSERT_EQ(s.position, AxisVec{});
}

TEST(Controller, AWeakPositionLoopRaisesTheFollowingErrorAlarm) {
  MachineConfig m = default_machine_config();
  m.servo.kp_per_s = 5;
  m.servo.feedforward = 0;
  m.servo.following_error_limit_mm = 1;
  Served sv(m);
  ASSERT_TRUE(sv.c().mdi("G0 X100").ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kAlarm));
  const Status s = sv.c().status();
  EXPECT_EQ(s.alarm, AlarmCode::kFollowingError);
  EXPECT_GT(s.commanded[kX], 0);
  EXPECT_LT(s.commanded[kX], 100);  // stopped on the way
}

TEST(Controller, AJogStopsAtTheTravelLimitAndACancelBrakesWithinTheAcceleration) {
  Served sv(default_machine_config());
  JogRequest j;
  j.axes = 1U << kX;
  j.target[kX] = 1;
  j.continuous = true;
  j.feed_mm_min = 12000;  // capped by the machine's feed limit (10 000)
  ASSERT_TRUE(sv.c().jog(j).ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_EQ(sv.c().status().commanded[kX], 300);  // the built-in X travel maximum
  j.target[kX] = -1;
  ASSERT_TRUE(sv.c().jog(j).ok);
  ASSERT_TRUE(sv.wait_for([](const Status& s) { return s.feed_mm_min >= 9999; }, 10));
  ASSERT_TRUE(sv.c().jog_cancel().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_GT(sv.c().status().commanded[kX], -300);
  // Speeds and accelerations by differences of the set-points.
  const auto s = sv.samples();
  const double tau = sv.machine().period_s;
  double worst = 0;
  for (std::size_t n = 2; n < s.size(); ++n) {
    const double v1 = (s[n - 1].position[kX] - s[n - 2].position[kX]) / tau;
    const double v2 = (s[n].position[kX] - s[n - 1].position[kX]) / tau;
    worst = std::max(worst, std::abs(v2 - v1) / tau);
    ASSERT_LE(s[n].position[kX], 300);
  }
  EXPECT_LE(worst, sv.machine().max_accel_mm_s2 * 1.001);
}

// Limits changed while idle: the next jog and program run with them (speed and travel measured
// from the set-points), bad values and changes while moving are refused.
TEST(Controller, LimitsChangedWhileIdleRuleTheNextJogAndProgram) {
  Served sv(default_machine_config());
  MachineLimits l = sv.c().limits();
  EXPECT_EQ(l.max_mm[kX], 300);
  l.max_speed_mm_min[kX] = 1200;
  l.max_mm[kX] = 40;
  ASSERT_TRUE(sv.c().set_limits(l).ok);
  EXPECT_EQ(sv.c().limits(), l);
  EXPECT_EQ(sv.c().machine().axes[kX].max_mm, 300);  // the configuration as started
  JogRequest j;
  j.axes = 1U << kX;
  j.target[kX] = 1;
  j.continuous = true;
  j.feed_mm_min = 9000;
  ASSERT_TRUE(sv.c().jog(j).ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_NEAR(sv.c().status().commanded[kX], 40, 1e-9);  // the new travel's end
  const double tau = sv.machine().period_s;
  const auto speed_max = [&](const std::vector<motion::Sample>& s) {
    double v = 0;
    for (std::size_t n = 1; n < s.size(); ++n) {
      v = std::max(v, std::abs(s[n].position[kX] - s[n - 1].position[kX]) / tau * 60);
    }
    return v;
  };
  EXPECT_LE(speed_max(sv.samples()), 1200 * 1.001);
  EXPECT_GT(speed_max(sv.samples()), 1100);
  // A program beyond the new travel is refused at its line; within it, it keeps the new speed.
  EXPECT_FALSE(sv.c().mdi("G0 X50").ok);
  ASSERT_TRUE(sv.c().mdi("G1 X0 F6000").ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kRun, 5));  // 40 mm at 1200 mm/min: 2 s
  EXPECT_FALSE(sv.c().set_limits(l).ok);
  MachineLimits bad = l;
  bad.min_mm[kX] = 50;
  EXPECT_FALSE(sv.c().set_limits(bad).ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_NEAR(sv.c().status().commanded[kX], 0, 1e-9);
  EXPECT_LE(speed_max(sv.samples()), 1200 * 1.001);
}

TEST(Controller, HomingFindsTheSwitchesWhereverTheAxesReallyAre) {
  ControllerOptions o = Served::default_options();
  o.sim_position_error[kX] = 7;
  o.sim_position_error[kY] = -4;
  o.sim_position_error[kZ] = 3;
  MachineConfig m = default_machine_config();
  m.servo.home_search_mm_min = 6000;
  m.servo.home_latch_mm_min = 600;
  Served sv(m, o);
  EXPECT_FALSE(sv.c().status().homed);
  ASSERT_TRUE(sv.c().home().ok);
  EXPECT_FALSE(sv.c().jog(JogRequest{}).ok);  // homing: nothing else moves
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle, 120));
  const Status s = sv.c().status();
  EXPECT_TRUE(s.homed);
  for (std::size_t a : {kX, kY, kZ}) {
    EXPECT_NEAR(s.commanded[a], m.axes[a].max_mm - m.servo.home_pulloff_mm, 1e-9) << a;
    // Where the controller believes the axis is and where it is now agree: the switch trips
    // exactly at the travel maximum in the controller's coordinates.
  }
  JogRequest up;
  up.axes = 1U << kX;
  up.target[kX] = 1;
  up.continuous = true;
  ASSERT_TRUE(sv.c().jog(up).ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_EQ(sv.c().status().commanded[kX], m.axes[kX].max_mm);
}

TEST(Controller, M0PausesTheProgramUntilCycleStartAndSingleBlockAfterEveryBlock) {
  Served sv(default_machine_config());
  const std::string program =
      write_program("m0.ngc", "G21 G90\nG1 X10 F3000\nM0\nG1 X20\nM1\nG1 X30\nM30\n");
  ASSERT_TRUE(sv.c().load_program(program).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_for(
      [](const Status& s) { return s.state == MachineState::kHold && s.hold_complete; }));
  EXPECT_EQ(sv.c().status().commanded[kX], 10);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));  // M1 without the optional stop: no pause
  EXPECT_EQ(sv.c().status().commanded[kX], 30);

  ASSERT_TRUE(sv.c().set_switches(Switches{false, true}).ok);
  const std::string two = write_program("two.ngc", "G21 G90\nG1 X40 F3000\nG1 X50\nM30\n");
  ASSERT_TRUE(sv.c().load_program(two).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_for(
      [](const Status& s) { return s.state == MachineState::kHold && s.hold_complete; }));
  EXPECT_EQ(sv.c().status().commanded[kX], 40);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_for(
      [](const Status& s) { return s.state == MachineState::kHold && s.hold_complete; }));
  EXPECT_EQ(sv.c().status().commanded[kX], 50);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
}

TEST(Controller, ResetEndsARunningProgramWithAStopOnThePath) {
  Served sv(default_machine_config());
  ASSERT_TRUE(sv.c().load_program(example("pocket-with-arcs.ngc")).ok);
  ASSERT_TRUE(sv.c().cycle_start().ok);
  sv.wait_cycles(300);
  EXPECT_FALSE(sv.c().mdi("G0 X0").ok);  // running: refused
  EXPECT_FALSE(sv.c().home().ok);
  ASSERT_TRUE(sv.c().reset().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  const auto s = sv.samples();
  const double tau = sv.machine().period_s;
  for (std::size_t n = 2; n < s.size(); ++n) {
    const AxisVec a = (s[n].position - s[n - 1].position) - (s[n - 1].position - s[n - 2].position);
    double a2 = 0;
    for (double v : a.v) a2 += v * v;
    // The stop keeps the acceleration (resultant ≤ √2·Amax on arcs, the seed's bound).
    ASSERT_LE(std::sqrt(a2) / (tau * tau), sv.machine().max_accel_mm_s2 * 1.5) << n;
  }
  EXPECT_TRUE(sv.c().mdi("G0 X0 Y0").ok);  // idle again: MDI runs
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_EQ(sv.c().status().commanded[kX], 0);
  EXPECT_EQ(sv.c().status().commanded[kY], 0);
}

TEST(Controller, CheckModeInterpretsWithoutMotion) {
  Served sv(default_machine_config());
  ASSERT_TRUE(sv.c().set_check_mode(true).ok);
  EXPECT_EQ(sv.c().status().state, MachineState::kCheck);
  EXPECT_TRUE(sv.c().mdi("G0 X100").ok);
  EXPECT_FALSE(sv.c().mdi("G0 X1000").ok);  // beyond the travel: reported
  EXPECT_FALSE(sv.c().jog(JogRequest{}).ok);
  sv.wait_cycles(20);
  EXPECT_EQ(sv.c().status().commanded, AxisVec{});
  ASSERT_TRUE(sv.c().set_check_mode(false).ok);
  EXPECT_TRUE(sv.wait_state(MachineState::kIdle));
}

TEST(Controller, OffsetsAndPositionPersistAcrossRestarts) {
  const auto dir = std::filesystem::path(CNCORE_TEST_TMP_DIR) / "controller-state";
  std::filesystem::remove_all(dir);
  ControllerOptions o = Served::default_options();
  o.state_dir = dir.string();
  {
    Served sv(default_machine_config(), o);
    ASSERT_TRUE(sv.c().mdi("G10 L2 P1 X12.5 Y-3").ok);
    ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
    ASSERT_TRUE(sv.c().mdi("G53 G0 X5").ok);
    ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
    EXPECT_EQ(sv.c().status().work_offset[kX], 12.5);
  }
  Served again(default_machine_config(), o);
  const Status s = again.c().status();
  EXPECT_EQ(s.work_offset[kX], 12.5);
  EXPECT_EQ(s.work_offset[kY], -3);
  EXPECT_EQ(s.commanded[kX], 5);
  // The next program runs in that offset.
  ASSERT_TRUE(again.c().mdi("G90 G0 X0").ok);
  ASSERT_TRUE(again.wait_state(MachineState::kIdle));
  EXPECT_EQ(again.c().status().commanded[kX], 12.5);
}

TEST(Controller, ToolTableWritesCarryToTheNextProgramAndAcrossRestarts) {
  const auto dir = std::filesystem::path(CNCORE_TEST_TMP_DIR) / "controller-tools";
  std::filesystem::remove_all(dir);
  ControllerOptions o = Served::default_options();
  o.state_dir = dir.string();
  MachineConfig m = default_machine_config();
  m.start_position = {0, 0, 50, 0, 0, 0};
  {
    Served sv(m, o);
    ASSERT_TRUE(sv.c().mdi("G10 L1 P3 Z20 R4").ok);
    ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
    // The next MDI line (a job of its own) finds tool 3's length: Z0 puts the tip at 0, the
    // controlled point 20 mm above.
    ASSERT_TRUE(sv.c().mdi("T3 M6 G43 H3 G90 G0 Z0").ok);
    ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
    EXPECT_EQ(sv.c().status().commanded[kZ], 20);
    ASSERT_TRUE(sv.c().mdi("G49 G0 Z30").ok);
    ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  }
  Served again(m, o);
  ASSERT_TRUE(again.c().mdi("T3 M6 G43 H3 G90 G0 Z5").ok);
  ASSERT_TRUE(again.wait_state(MachineState::kIdle));
  EXPECT_EQ(again.c().status().commanded[kZ], 25);
}

}  // namespace
}  // namespace cncore::runtime
