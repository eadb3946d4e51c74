// Spindle-synchronised motion through the simulated machine (sim::run_program, the driver of
// `cncore run`), measured on the trajectory: the speed of a G33 move (finite differences of the
// set-points) is K·S and the feed override does not change it while it changes a G1; each
// series starts from rest; G76's deepest pass reaches the thread's depth and ends at Z; G96
// turns the spindle at the surface speed over the radius where the tool is.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include "config/machine_config.hpp"
#include "files.hpp"
#include "limits.hpp"
#include "simulation/run.hpp"
#include "trajectory.hpp"
#include "trajectory_checker.hpp"

namespace cncore::interp::test {
namespace {

namespace fs = std::filesystem;

struct Recorder : sim::SampleObserver {
  std::vector<Block> blocks;
  testing::Trajectory tr;
  std::vector<char> aux;
  std::vector<double> aux_value;
  void on_block(const Block& b) override {
    if (!b.piece) blocks.push_back(b);
  }
  void on_sample(const motion::Sample& s) override {
    tr.add_sample(s);
    aux.push_back(s.aux_letter);
    aux_value.push_back(s.aux_value);
  }
};

struct Measured {
  Recorder rec;
  testing::CheckReport checker;
  double period_s = 0;
  // Path speed (mm/min) between samples i−1 and i, from the set-points.
  double speed(std::size_t i) const {
    const Vec3 d = rec.tr.pos[i].xyz() - rec.tr.pos[i - 1].xyz();
    return norm(d) / period_s * 60;
  }
};

Measured run(const std::string& name, const std::string& text, double override_pct = 100) {
  const MachineConfig m = default_machine_config();
  const fs::path p = fs::path(CNCORE_TEST_TMP_DIR) / name;
  testing::write_file(p, text);
  Measured r;
  r.period_s = m.period_s;
  sim::RunOptions o;
  if (override_pct != 100) o.override_steps = {{0.0, override_pct}};
  sim::run_program(p.string(), m, o, {&r.rec});
  r.checker = testing::check_trajectory(r.rec.tr, r.rec.blocks, testing::limits_from_config(m));
  return r;
}

// The highest speed measured on source line `line`, and the speed where the line starts.
struct LineSpeeds {
  double top = 0, at_start = -1;
};
LineSpeeds speeds_on(const Measured& r, std::uint32_t line) {
  LineSpeeds s;
  for (std::size_t i = 1; i < r.rec.tr.size(); ++i) {
    if (r.rec.tr.line[i] != line) continue;
    if (s.at_start < 0) s.at_start = r.speed(i);
    s.top = std::max(s.top, r.speed(i));
  }
  return s;
}

TEST(ThreadingRun, G33RunsAtKTimesSAndTheOverrideLeavesItAlone) {
  const std::string prog =
      "G18 G21 G90 S600 M3\nG0 X10 Z5\nG33 Z-60 K1.5\nG0 X20\nG1 Z5 F900\nM30\n";
  const Measured base = run("g33.ngc", prog);
  const Measured fast = run("g33_ov.ngc", prog, 150);
  EXPECT_TRUE(base.checker.ok()) << base.checker.summary();
  EXPECT_TRUE(fast.checker.ok()) << fast.checker.summary();
  // 1.5 mm/rev · 600 rpm = 900 mm/min, whatever the override.
  EXPECT_NEAR(speeds_on(base, 3).top, 900, 900 * 1e-6);
  EXPECT_NEAR(speeds_on(fast, 3).top, 900, 900 * 1e-6);
  EXPECT_LT(speeds_on(base, 3).at_start, 900 * 0.1) << "the thread starts from rest";
  // The G1 at the same F follows the override.
  EXPECT_NEAR(speeds_on(base, 5).top, 900, 900 * 1e-6);
  EXPECT_NEAR(speeds_on(fast, 5).top, 1350, 1350 * 1e-6);
}

// An outside thread: P1.5, 0.92 mm deep, first cut 0.2, constant area (R2), 29.5° compound,
// two spring passes, a 3 mm taper at the end.
TEST(ThreadingRun, G76CutsToTheThreadDepthAtThePitch) {
  const Measured r = run("g76.ngc",
                         "G18 G21 G90 G0 X12 Z3\nS800 M3\n"
                         "G76 P1.5 Z-25 I-2 J0.2 K0.92 R2 Q29.5 H2 E3 L2\nG0 X30\nM30\n");
  EXPECT_TRUE(r.checker.ok()) << r.checker.summary();
  double min_x = 1e9;
  std::size_t passes = 0;
  bool moving = false;
  for (std::size_t i = 1; i < r.rec.tr.size(); ++i) {
    if (r.rec.tr.line[i] != 3) continue;
    const AxisVec& p = r.rec.tr.pos[i];
    min_x = std::min(min_x, p[0]);
    // Along Z at cutting depth (X below the peaks at 10): a pass; counted where it starts.
    const bool cutting = p[0] < 10 - 1e-9 && std::fabs(p[2] - r.rec.tr.pos[i - 1][2]) > 0;
    if (cutting && !moving) ++passes;
    moving = cutting;
  }
  EXPECT_NEAR(min_x, 10 - 0.92, 1e-9);
  int want = 0;
  for (int n = 1; 0.2 * std::sqrt(n) < 0.92; ++n) ++want;
  EXPECT_EQ(passes, static_cast<std::size_t>(want + 3));
  // Along the straight part of each pass (X still) Z advances 1.5 mm per revolution of 800 rpm.
  double top = 0;
  for (std::size_t i = 1; i < r.rec.tr.size(); ++i) {
    const AxisVec& p = r.rec.tr.pos[i];
    if (r.rec.tr.line[i] == 3 && p[0] < 10 && p[0] == r.rec.tr.pos[i - 1][0]) {
      top = std::max(top, r.speed(i));
    }
  }
  EXPECT_NEAR(top, 1.5 * 800, 1.5 * 800 * 1e-6);
  const AxisVec& end = r.rec.tr.pos.back();
  EXPECT_NEAR(end[0], 30, 1e-9);
  EXPECT_NEAR(end[2], -25, 1e-9);
}

TEST(ThreadingRun, ConstantSurfaceSpeedTurnsTheSpindleFasterTowardTheCentre) {
  const Measured r =
      run("g96.ngc", "G18 G21 G90 G0 X40 Z0\nG96 S150 D2500 M3\nG95 G1 X2 F0.15\nM30\n");
  EXPECT_TRUE(r.checker.ok()) << r.checker.summary();
  // Each S event reached on the facing move against the speed the radius asks (2 % pieces).
  double rpm = 0;
  std::size_t events = 0;
  for (std::size_t i = 1; i < r.rec.tr.size(); ++i) {
    if (r.rec.aux[i] == 'S') {
      rpm = r.rec.aux_value[i];
      ++events;
    }
    if (r.rec.tr.line[i] != 3 || rpm == 0) continue;
    const double radius = std::fabs(r.rec.tr.pos[i][0]);
    const double want = std::min(2500.0, 150000 / (2 * std::numbers::pi * radius));
    EXPECT_NEAR(rpm, want, want * 0.021) << "at X " << radius;
    // The feed per revolution: the speed never exceeds F·rpm.
    EXPECT_LE(r.speed(i), 0.15 * rpm * (1 + 1e-6)) << "at X " << radius;
  }
  EXPECT_GT(events, 50U);
  EXPECT_DOUBLE_EQ(rpm, 2500);
}

}  // namespace
}  // namespace cncore::interp::test
