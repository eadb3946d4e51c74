// Motion kernel, end to end: the produced trajectory is measured by the independent checker
// (tests/support: finite differences of the output positions against the programmed blocks) —
// P1–P5 of spec 01 on the seed's example and on the shapes that stress a look-ahead.
#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "limits.hpp"
#include "motion_test_rc.hpp"
#include "motion_test_util.hpp"
#include "trajectory_checker.hpp"

namespace cncore::motion::test {
namespace {

constexpr double kPi = std::numbers::pi;

testing::CheckReport check(const MachineConfig& m, const std::vector<Block>& blocks,
                           const RunResult& r) {
  return testing::check_trajectory(r.traj, blocks, testing::limits_from_config(m));
}

// The moving-average type (the seed's), whatever the default acc/dec type: these tests measure
// its behaviour (test_motion_accel runs the same programs with the acceleration type).
RunOpts opts(Mode mode) {
  RunOpts o;
  o.kernel.mode = mode;
  o.kernel.accdec = AccDecType::kMovingAverage;
  return o;
}

std::string mode_name(Mode m) {
  return m == Mode::kLookahead ? "Lookahead" : "Stop";
}

// The last sample is the programmed end, at rest; the first is the start at t = 0.
void expect_ends(const RunResult& r, const AxisVec& start, const AxisVec& end) {
  ASSERT_GE(r.samples.size(), 1u);
  EXPECT_EQ(r.samples.front().t_s, 0.0);
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    EXPECT_NEAR(r.samples.front().position[i], start[i], 1e-12) << "axis " << i;
    EXPECT_NEAR(r.samples.back().position[i], end[i], 1e-9) << "axis " << i;
  }
  EXPECT_EQ(r.samples.back().feed_mm_min, 0.0);
}

class BothModes : public ::testing::TestWithParam<Mode> {};
INSTANTIATE_TEST_SUITE_P(Kernel, BothModes, ::testing::Values(Mode::kLookahead, Mode::kStop),
                         [](const auto& param_info) { return mode_name(param_info.param); });

TEST_P(BothModes, SeedExampleKeepsEveryLimit) {
  const MachineConfig m = test_machine();
  const Prog p = seed_example();
  RunOpts o = opts(GetParam());
  o.kernel.check_reference_walk = true;
  const RunResult r = run(m, p.blocks, o);
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_EQ(r.mismatches, 0u);
  expect_ends(r, AxisVec{}, p.pos);
  // Both joints are tangent: look-ahead passes them at the arc's shape speed √(R·Amax) =
  // 100 mm/s (the checker's Vg), never stopping; stop mode stops at each.
  std::size_t joints = 0;
  for (const auto& j : rep.joints) {
    if (j.stop) continue;
    ++joints;
    EXPECT_NEAR(j.vg_mm_s, 100.0, 1e-9);
    EXPECT_LE(j.speed_mm_s, j.vg_mm_s * 1.005);
    if (GetParam() == Mode::kLookahead) {
      EXPECT_GE(j.speed_mm_s, j.vg_mm_s * 0.98) << "joint passed slower than needed";
    } else {
      EXPECT_LE(j.speed_mm_s, m.max_accel_mm_s2 * m.period_s);
    }
  }
  EXPECT_EQ(joints, 2u);
}

TEST_P(BothModes, CornerExampleKeepsEveryLimit) {
  const MachineConfig m = test_machine();
  const Prog p = corner_example();
  RunOpts o = opts(GetParam());
  o.kernel.check_reference_walk = true;
  const RunResult r = run(m, p.blocks, o);
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_EQ(r.mismatches, 0u);
  expect_ends(r, AxisVec{}, p.pos);
  if (GetParam() == Mode::kLookahead) {
    // Its 45° corners have Vg = 2.35 mm/s, below a third of the feed: crawling through them
    // would cost 1.5·T·(1 − Vg/F) cycles against T for a stop, so look-ahead stops there.
    for (const auto& j : rep.joints) {
      if (!j.stop) {
        EXPECT_LE(j.speed_mm_s, m.max_accel_mm_s2 * m.period_s * 1.005) << "corner not stopped";
      }
    }
  }
}

TEST_P(BothModes, StraightLinesOfEveryLength) {
  const MachineConfig m = test_machine();
  // Down to far less than one cycle's travel (10000 mm/min = 0.167 mm per cycle).
  for (double len : {1e-5, 1e-3, 0.05, 0.1667, 0.5, 1.0, 7.3, 50.0, 400.0}) {
    Prog p;
    p.line_to(Vec3{len * 0.6, len * 0.8, 0}, 10000);
    const RunResult r = run(m, p.blocks, opts(GetParam()));
    const auto rep = check(m, p.blocks, r);
    EXPECT_TRUE(rep.ok()) << "length " << len << ": " << rep.summary();
    expect_ends(r, AxisVec{}, p.pos);
  }
}

TEST_P(BothModes, FullCirclesInEveryPlane) {
  const MachineConfig m = test_machine();
  const Vec3 normals[] = {{0, 0, 1}, {0, 0, -1}, {0, 1, 0}, {1, 0, 0}};
  for (double r_mm : {0.1, 0.5, 2.0, 10.0, 100.0}) {
    for (const Vec3& n : normals) {
      // A full turn from a point on the circle back to it (the machine starts there).
      const Vec3 radial = n.x != 0 ? Vec3{0, r_mm, 0} : Vec3{r_mm, 0, 0};
      MachineConfig mc = m;
      mc.start_position = {radial.x, radial.y, radial.z, 0, 0, 0};
      Prog p;
      p.pos.set_xyz(radial);
      p.arc_to(radial, Vec3{0, 0, 0}, 10000, n);
      const RunResult r = run(mc, p.blocks, opts(GetParam()));
      const auto rep = check(mc, p.blocks, r);
      EXPECT_TRUE(rep.ok()) << "R " << r_mm << ": " << rep.summary();
      EXPECT_LE(rep.max_normal_accel_mm_s2, m.max_accel_mm_s2 * 1.005);
      AxisVec start;
      start.set_xyz(radial);
      expect_ends(r, start, p.pos);
      // Arc speed reaches its limit min(Vmax, √(R·Amax)) (look-ahead makes no needless stops).
      const double vb = std::min(m.max_feed_mm_min / 60, std::sqrt(r_mm * m.max_accel_mm_s2));
      if (GetParam() == Mode::kLookahead && r_mm >= 2) {
        EXPECT_GE(rep.max_speed_mm_s, 0.99 * vb) << "R " << r_mm;
      }
    }
  }
}

TEST_P(BothModes, SharpCorners) {
  const MachineConfig m = test_machine();
  for (double deg : {90.0, 135.0, 168.0, 179.0}) {
    const double th = deg * kPi / 180;
    Prog p;
    p.line_to(Vec3{40, 0, 0}, 10000);
    p.line_to(Vec3{40 + 40 * std::cos(th), 40 * std::sin(th), 0}, 10000);
    const RunResult r = run(m, p.blocks, opts(GetParam()));
    const auto rep = check(m, p.blocks, r);
    EXPECT_TRUE(rep.ok()) << deg << "°: " << rep.summary();
    expect_ends(r, AxisVec{}, p.pos);
  }
}

// Fails if the look-ahead releases a corner's cap when the commanded (pre-filter) position
// passes the corner instead of the filtered one: a long fast line, a 168° corner, a long fast
// line. With the wrong release the window holds the fast steps of the next line while the tool
// is still before the corner (spec 01 measured 8× the passing speed).
TEST(Kernel, CornerCapHoldsUntilTheToolHasPassed) {
  const MachineConfig m = test_machine();
  const double th = 168 * kPi / 180;
  Prog p;
  p.line_to(Vec3{100, 0, 0}, 10000);
  p.line_to(Vec3{100 + 100 * std::cos(th), 100 * std::sin(th), 0}, 10000);
  const RunResult r = run(m, p.blocks, opts(Mode::kLookahead));
  const auto rep = check(m, p.blocks, r);
  ASSERT_GE(rep.joints.size(), 1u);
  const auto& j = rep.joints[0];
  ASSERT_FALSE(j.stop);
  // Vg = Amax·τ / (2 sin 84°) = 2000·0.001 / 1.989 = 1.0055 mm/s.
  EXPECT_NEAR(j.vg_mm_s, 2.0 / (2 * std::sin(84 * kPi / 180)), 1e-6);
  EXPECT_LE(j.speed_mm_s, j.vg_mm_s * 1.005) << rep.summary();
  // And the direction change at the corner stays within Amax·τ.
  EXPECT_LE(rep.max_normal_accel_mm_s2, m.max_accel_mm_s2 * 1.005);
}

TEST_P(BothModes, ZigZag) {
  const MachineConfig m = test_machine();
  Prog p;
  for (int i = 0; i < 40; ++i) {
    p.line_to(Vec3{i % 2 == 0 ? 5.0 : 0.0, i * 0.5, 0}, 10000);
    p.line_to(Vec3{i % 2 == 0 ? 5.0 : 0.0, (i + 1) * 0.5, 0}, 10000);
  }
  const RunResult r = run(m, p.blocks, opts(GetParam()));
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  expect_ends(r, AxisVec{}, p.pos);
}

TEST_P(BothModes, HelicesAndTurns) {
  const MachineConfig m = test_machine();
  Prog p;
  p.line_to(Vec3{5, 0, 0}, 8000);
  p.arc_to(Vec3{-5, 0, -3}, Vec3{0, 0, 0}, 8000);                  // half-turn helix, rises −3
  p.arc_to(Vec3{-5, 0, -13}, Vec3{0, 0, -3}, 8000, {0, 0, 1}, 2);  // two extra full turns
  p.arc_to(Vec3{-5, 5, -18}, Vec3{-5, 0, -18}, 6000, {0, 0, -1});  // G2-like, 3/4 turn... (cw)
  p.line_to(Vec3{0, 0, 0}, 10000);
  const RunResult r = run(m, p.blocks, opts(GetParam()));
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  expect_ends(r, AxisVec{}, p.pos);
}

TEST_P(BothModes, RapidsDwellAndAuxEvents) {
  const MachineConfig m = test_machine();
  const Prog p = events_example();
  const RunResult r = run(m, p.blocks, opts(GetParam()));
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  expect_ends(r, AxisVec{}, p.pos);
  // Every event exactly once, in program order, each where the program puts it.
  std::string order;
  for (const auto& s : r.samples) {
    if (s.aux_letter == 0) continue;
    order += s.aux_letter + std::to_string(static_cast<int>(s.aux_value)) + " ";
    if (s.aux_value == 3) {  // M3 waits: the tool stands at the end of the rapid
      EXPECT_NEAR(s.position[kZ], 10, 1e-12);
      EXPECT_EQ(s.feed_mm_min, 0.0);
    }
    if (s.aux_value == 8) {
      EXPECT_GE(s.position[kX], 150 - 1e-6);  // after the line's end
    }
  }
  EXPECT_EQ(order, "S12000 M3 M8 M5 ");
  // The dwell: the tool stands at (100, 50, 0) for ≥ 0.25 s.
  std::size_t still = 0, best = 0;
  for (const auto& s : r.samples) {
    const bool at = std::abs(s.position[kX] - 100) < 1e-12 && std::abs(s.position[kZ]) < 1e-12;
    still = at ? still + 1 : 0;
    best = std::max(best, still);
  }
  EXPECT_GE(static_cast<double>(best) * m.period_s, 0.25);
  // The rapid ran faster than the feed moves (rapid rate, bounded by the filter's ramp).
  EXPECT_GT(rep.max_speed_mm_s, 160.0);
}

// P5: the override steps up and down at arbitrary cycles, also mid-corner.
TEST_P(BothModes, OverrideStepsKeepTheLimits) {
  const MachineConfig m = test_machine();
  const Prog p = corner_example(6000);
  RunOpts o = opts(GetParam());
  o.override_steps = p5_override_steps();
  const RunResult r = run(m, p.blocks, o);
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  expect_ends(r, AxisVec{}, p.pos);
}

TEST(Kernel, FeedHoldStopsOnThePathAndResumes) {
  const MachineConfig m = test_machine();
  const Prog p = seed_example(10000);
  RunOpts o = opts(Mode::kLookahead);
  o.hold_steps = {{0.2, true}, {0.6, false}};
  const RunResult r = run(m, p.blocks, o);
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  expect_ends(r, AxisVec{}, p.pos);
  // Stopped within the filter time T·τ (+1 cycle) after the hold, and stays until resume.
  const double t_filter =
      std::ceil(m.max_feed_mm_min / 60 / (m.max_accel_mm_s2 * m.period_s)) * m.period_s;
  for (const auto& s : r.samples) {
    if (s.t_s >= 0.2 + t_filter + 2 * m.period_s && s.t_s < 0.6) {
      ASSERT_EQ(s.feed_mm_min, 0.0) << "t " << s.t_s;
    }
  }
  // It moves again after the resume.
  bool moved = false;
  for (const auto& s : r.samples) moved = moved || (s.t_s > 0.6 && s.feed_mm_min > 0);
  EXPECT_TRUE(moved);
}

TEST(Kernel, LateBlocksAreTreatedAsStopsAndStillKeepTheLimits) {
  const MachineConfig m = test_machine();
  Prog p;
  for (int i = 0; i < 200; ++i) {
    const double a = i * 0.1;
    p.line_to(Vec3{20 * std::cos(a), 20 * std::sin(a), 0}, 10000);
  }
  for (std::size_t every : {1u, 3u}) {
    RunOpts o = opts(Mode::kLookahead);
    o.feed_every = every;  // one block per cycle: the tail stop is live most of the time
    o.kernel.check_reference_walk = true;
    const RunResult r = run(m, p.blocks, o);
    const auto rep = check(m, p.blocks, r);
    EXPECT_TRUE(rep.ok()) << rep.summary();
    EXPECT_EQ(r.mismatches, 0u);
    expect_ends(r, AxisVec{}, p.pos);
  }
}

TEST(Kernel, SmallBufferStillReachesTheEnd) {
  MachineConfig m = test_machine();
  m.lookahead_blocks = 3;
  const Prog p = seed_example();
  const RunResult r = run(m, p.blocks, opts(Mode::kLookahead));
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  expect_ends(r, AxisVec{}, p.pos);
}

TEST_P(BothModes, PerAxisLimitsDecide) {
  MachineConfig m = test_machine();
  m.axes[kY].max_speed_mm_min = 3000;
  m.axes[kY].max_accel_mm_s2 = 500;
  m.axes[kZ].max_accel_mm_s2 = 300;
  Prog p;
  p.line_to(Vec3{30, 30, 0}, 10000);
  p.line_to(Vec3{60, 0, -5}, 10000);
  p.arc_to(Vec3{60, 20, -5}, Vec3{60, 10, -5}, 10000);
  p.line_to(Vec3{0, 0, 0}, 10000);
  const RunResult r = run(m, p.blocks, opts(GetParam()));
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_LE(rep.max_axis_speed_mm_s[kY], 50 * 1.005);
  EXPECT_LE(rep.max_axis_accel_mm_s2[kY], 500 * 1.005);
  expect_ends(r, AxisVec{}, p.pos);
}

TEST_P(BothModes, JerkStageBoundsTheJerk) {
  MachineConfig m = test_machine();
  m.max_jerk_mm_s3 = 100000;  // T2 = ⌈2·Amax/(Jmax·τ)⌉ = 40 cycles
  const Prog p = seed_example();
  const RunResult r = run(m, p.blocks, opts(GetParam()));
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_LE(rep.max_tangential_jerk_mm_s3, m.max_jerk_mm_s3 * 1.005);
  expect_ends(r, AxisVec{}, p.pos);
}

TEST_P(BothModes, RotaryAxesMoveLinearly) {
  MachineConfig m = test_machine();
  m.axes[kA].enabled = true;
  m.axes[kA].rotary = true;
  m.axes[kA].max_speed_mm_min = 3600;  // 60 °/s
  m.axes[kA].max_accel_mm_s2 = 720;
  Prog p;
  AxisVec a;
  a.set_xyz(Vec3{20, 0, 0});
  a[kA] = 90;
  p.line_to(a, 10000);  // X and A together
  a[kA] = 0;
  p.line_to(a, 3000);  // rotary only: path length in degrees
  const RunResult r = run(m, p.blocks, opts(GetParam()));
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_LE(rep.max_axis_speed_mm_s[kA], 60 * 1.005);
  expect_ends(r, AxisVec{}, p.pos);
}

// KernelOptions::bound_resultant_accel: on arcs √(a_t² + a_n²) ≤ Amax instead of each ≤ Amax.
TEST(Kernel, ResultantAccelerationBoundOnArcs) {
  const MachineConfig m = test_machine();
  Prog p;
  p.line_to(Vec3{20, 0, 0}, 10000);
  p.arc_to(Vec3{20, 20, 0}, Vec3{20, 10, 0}, 10000);              // R 10, tangent entry
  p.arc_to(Vec3{20, 22, 0}, Vec3{20, 21, 0}, 10000, {0, 0, -1});  // R 1, reversing curvature
  p.line_to(Vec3{0, 22, 0}, 10000);
  RunOpts o = opts(Mode::kLookahead);
  const RunResult seed_way = run(m, p.blocks, o);
  o.kernel.bound_resultant_accel = true;
  const RunResult bounded = run(m, p.blocks, o);
  auto lim = testing::limits_from_config(m);
  const auto rep_seed = testing::check_trajectory(seed_way.traj, p.blocks, lim);
  lim.max_resultant_accel_mm_s2 = m.max_accel_mm_s2;
  const auto rep = testing::check_trajectory(bounded.traj, p.blocks, lim);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_LE(rep.max_resultant_accel_mm_s2, m.max_accel_mm_s2 * 1.005);
  std::printf("resultant acceleration: %.0f mm/s² (each bounded), %.0f mm/s² (resultant bounded)\n",
              rep_seed.max_resultant_accel_mm_s2, rep.max_resultant_accel_mm_s2);
}

// Post-interpolation filter: the corners are rounded, and the measured distance to the
// programmed path stays within the contour tolerance (the checker uses it as P1's tolerance).
TEST(Kernel, PostFilterKeepsTheContourTolerance) {
  for (double tol : {0.002, 0.01, 0.05}) {
    MachineConfig m = test_machine();
    m.post_filter_s = 0.016;
    m.contour_tolerance_mm = tol;
    const Prog p = contour_example();
    const RunResult r = run(m, p.blocks, opts(Mode::kLookahead));
    const auto rep = check(m, p.blocks, r);
    EXPECT_TRUE(rep.ok()) << "tol " << tol << ": " << rep.summary();
    EXPECT_LE(rep.max_path_error_mm, tol);
    EXPECT_GT(rep.max_path_error_mm, 0.1 * tol) << "the corner speed is needlessly low";
    std::printf("post filter 16 ms, tolerance %.3f mm: measured contour error %.4f mm, %.3f s\n",
                tol, rep.max_path_error_mm, r.time_s());
    expect_ends(r, AxisVec{}, p.pos);
  }
}

TEST(Kernel, PostFilterExactPathStopsAtCorners) {
  MachineConfig m = test_machine();
  m.post_filter_s = 0.016;
  Prog p;
  p.line_to(Vec3{20, 0, 0}, 10000, PathMode::kExactPath);
  p.line_to(Vec3{20, 20, 0}, 10000, PathMode::kExactPath);
  const RunResult r = run(m, p.blocks, opts(Mode::kLookahead));
  auto lim = testing::limits_from_config(m);
  lim.path_tolerance_mm = 1e-6;
  const auto rep = testing::check_trajectory(r.traj, p.blocks, lim);
  EXPECT_TRUE(rep.ok()) << rep.summary();
}

// P6: look-ahead is much faster than stopping at every block end.
TEST(Kernel, LookaheadIsMuchFasterThanStopMode) {
  const MachineConfig m = test_machine();
  Prog tiny;  // a CAM-like arc of 2000 chords of 0.05 mm
  for (int i = 1; i <= 2000; ++i) {
    const double a = i * 0.001;
    tiny.line_to(Vec3{50 * std::sin(a), 50 - 50 * std::cos(a), 0}, 6000);
  }
  struct Case {
    const char* name;
    std::vector<Block> blocks;
    double min_ratio;
  };
  const Case cases[] = {{"seed example", seed_example().blocks, 1.2},
                        {"2000 tiny segments", tiny.blocks, 20}};
  for (const auto& c : cases) {
    const RunResult la = run(m, c.blocks, opts(Mode::kLookahead));
    const RunResult st = run(m, c.blocks, opts(Mode::kStop));
    EXPECT_TRUE(check(m, c.blocks, la).ok());
    EXPECT_TRUE(check(m, c.blocks, st).ok());
    std::printf("P6 %s: look-ahead %.3f s, stop mode %.3f s (×%.1f)\n", c.name, la.time_s(),
                st.time_s(), st.time_s() / la.time_s());
    EXPECT_GT(st.time_s(), c.min_ratio * la.time_s()) << c.name;
  }
}

// Random programs (lines, arcs and helices in any plane, rapids, segment lengths from 1 µm to
// 30 mm, random feeds, exact stops) with random override steps, in both modes: every
// property of the checker holds, the end is exact, and the O(log n) look-ahead gives the same
// limit as the plain walk in every cycle.
RC_GTEST_PROP(Kernel, RandomProgramsWithOverrideSteps, ()) {
  MachineConfig m = test_machine();
  m.lookahead_blocks = *rc::gen::inRange(4, 40);
  const Mode mode = *rc::gen::element(Mode::kLookahead, Mode::kStop);
  const Prog p = random_moves();
  RunOpts o = opts(mode);
  o.kernel.check_reference_walk = mode == Mode::kLookahead;
  add_random_override_steps(o);
  const RunResult r = run(m, p.blocks, o);
  const auto rep = check(m, p.blocks, r);
  if (!rep.ok()) {
    RC_LOG() << rep.summary() << " mode " << static_cast<int>(mode) << " buffer "
             << m.lookahead_blocks << "\n";
    log_case(p.blocks, o);
  }
  RC_ASSERT(rep.ok());
  RC_ASSERT(r.mismatches == 0u);
  for (std::size_t i = 0; i < 3; ++i)
    RC_ASSERT(std::abs(r.samples.back().position[i] - p.pos[i]) <= 1e-9);
  RC_ASSERT(r.samples.back().feed_mm_min == 0.0);
}

}  // namespace
}  // namespace cncore::motion::test
