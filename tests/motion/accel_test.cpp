// The acceleration-limited acc/dec type, end to end: the same programs as the
// moving-average tests (kernel_test.cpp) through the kernel with AccDecType::kAcceleration, the
// trajectory measured by the independent checker (tests/support) — P1–P5 of spec 01 — plus what
// is specific to this type: time against the closed-form optimum, rapids at the rapid rate,
// exact passing speeds, the bound equal to a plain walk over the caps, random programs with
// random override steps (RapidCheck).
#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <iomanip>
#include <numbers>
#include <string>
#include <utility>

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

RunOpts accel_opts() {
  RunOpts o;
  o.kernel.accdec = AccDecType::kAcceleration;
  o.kernel.check_reference_walk = true;
  return o;
}

void expect_ends(const RunResult& r, const AxisVec& start, const AxisVec& end) {
  ASSERT_GE(r.samples.size(), 1u);
  EXPECT_EQ(r.samples.front().t_s, 0.0);
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    EXPECT_NEAR(r.samples.front().position[i], start[i], 1e-12) << "axis " << i;
    EXPECT_NEAR(r.samples.back().position[i], end[i], 1e-9) << "axis " << i;
  }
  EXPECT_EQ(r.samples.back().feed_mm_min, 0.0);
}

// Runs, checks P1–P4 and that the trees gave the same bound as the walk in every cycle.
RunResult run_checked(const MachineConfig& m, const Prog& p, RunOpts o = accel_opts(),
                      AxisVec start = {}) {
  const RunResult r = run(m, p.blocks, o);
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_EQ(r.mismatches, 0u);
  expect_ends(r, start, p.pos);
  return r;
}

// A trapezoid on one line, computed by hand: 100 mm at F 6000 (100 mm/s), A 2000 mm/s², τ 1 ms.
// Ramp 0 → 100 mm/s takes 50 ms and 2.5 mm; cruise 95 mm takes 0.95 s; total 1.05 s (continuous
// time). The discrete profile may need a few cycles more, never fewer.
TEST(AccelLimited, SingleLineIsATrapezoid) {
  const MachineConfig m = test_machine();
  Prog p;
  p.line_to(Vec3{60, 80, 0}, 6000);
  const RunResult r = run_checked(m, p);
  EXPECT_GE(r.time_s(), 1.05 - 1e-9);
  EXPECT_LE(r.time_s(), 1.05 + 0.004);
  const auto rep = check(m, p.blocks, r);
  EXPECT_NEAR(rep.max_speed_mm_s, 100, 1e-6);
  EXPECT_LE(rep.max_tangential_accel_mm_s2, 2000 * 1.000001);
}

TEST(AccelLimited, SeedAndCornerExamples) {
  const MachineConfig m = test_machine();
  const RunResult seed = run_checked(m, seed_example());
  const RunResult corner = run_checked(m, corner_example());
  // The moving average needs T = 84 cycles for every speed change; this type |ΔV|/Amax.
  RunOpts ma;
  ma.kernel.accdec = AccDecType::kMovingAverage;  // whatever the default
  const RunResult seed_ma = run(m, seed_example().blocks, ma);
  EXPECT_LT(seed.time_s(), seed_ma.time_s());
  std::printf("seed example: acceleration %.3f s, moving average %.3f s; corner example %.3f s\n",
              seed.time_s(), seed_ma.time_s(), corner.time_s());
}

TEST(AccelLimited, StraightLinesOfEveryLength) {
  const MachineConfig m = test_machine();
  for (double len : {1e-5, 1e-3, 0.05, 0.1667, 0.5, 1.0, 7.3, 50.0, 400.0}) {
    SCOPED_TRACE(len);
    Prog p;
    p.line_to(Vec3{len * 0.6, len * 0.8, 0}, 10000);
    run_checked(m, p);
  }
}

TEST(AccelLimited, FullCirclesInEveryPlane) {
  const Vec3 normals[] = {{0, 0, 1}, {0, 0, -1}, {0, 1, 0}, {1, 0, 0}};
  for (double r_mm : {0.1, 0.5, 2.0, 10.0, 100.0}) {
    for (const Vec3& n : normals) {
      SCOPED_TRACE(r_mm);
      const Vec3 radial = n.x != 0 ? Vec3{0, r_mm, 0} : Vec3{r_mm, 0, 0};
      MachineConfig mc = test_machine();
      mc.start_position = {radial.x, radial.y, radial.z, 0, 0, 0};
      Prog p;
      p.pos.set_xyz(radial);
      p.arc_to(radial, Vec3{0, 0, 0}, 10000, n);
      AxisVec start;
      start.set_xyz(radial);
      const RunResult r = run_checked(mc, p, accel_opts(), start);
      const auto rep = check(mc, p.blocks, r);
      const double vb = std::min(mc.max_feed_mm_min / 60, std::sqrt(r_mm * mc.max_accel_mm_s2));
      if (r_mm >= 2) {
        EXPECT_GE(rep.max_speed_mm_s, 0.99 * vb);
      }
    }
  }
}

// Corners are passed at their passing speed, not stopped at (no slow-corner rule here), and the
// cycle that turns the corner has the corner's speed on both sides.
TEST(AccelLimited, SharpCornersAtTheirPassingSpeed) {
  const MachineConfig m = test_machine();
  for (double deg : {90.0, 135.0, 168.0, 179.0}) {
    SCOPED_TRACE(deg);
    const double th = deg * kPi / 180;
    Prog p;
    p.line_to(Vec3{40, 0, 0}, 10000);
    p.line_to(Vec3{40 + 40 * std::cos(th), 40 * std::sin(th), 0}, 10000);
    const RunResult r = run_checked(m, p);
    const auto rep = check(m, p.blocks, r);
    ASSERT_GE(rep.joints.size(), 1u);
    const auto& j = rep.joints[0];  // the corner (the end of the program may be listed too)
    // Vg = Amax·τ / (2 sin(θ/2)) with θ the turn (180° − the corner's interior angle... here
    // the direction turns by `deg`).
    EXPECT_NEAR(j.vg_mm_s, 2.0 / (2 * std::sin(deg * kPi / 360)), 1e-6);
    EXPECT_LE(j.speed_mm_s, j.vg_mm_s * 1.005);
    EXPECT_GE(j.speed_mm_s, j.vg_mm_s * 0.5);  // passed, not stopped
    EXPECT_LE(rep.max_normal_accel_mm_s2, m.max_accel_mm_s2 * 1.005);
  }
}

// Largest |P[k+1] − 2P[k] + P[k−1]|_i / τ² over the samples, per axis (mm/s²): the per-axis
// acceleration by finite differences of the produced positions, independent of the checker.
std::array<double, kMaxAxes> axis_accel_by_differences(const RunResult& r, double period_s) {
  std::array<double, kMaxAxes> out{};
  for (std::size_t k = 1; k + 1 < r.samples.size(); ++k) {
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      const double d2 = r.samples[k + 1].position[i] - 2 * r.samples[k].position[i] +
                        r.samples[k - 1].position[i];
      out[i] = std::max(out[i], std::abs(d2) / (period_s * period_s));
    }
  }
  return out;
}

// A gentle corner (below ~0.7° on the built-in machine the corner formula allows more than Vmax,
// so no corner cap applies) passed while the speed changes: the turn and the speed change share
// the cycle. Per axis the second difference there is u1·(S_i − E_i) + Δu·S_i; with the axis
// limits equal to Amax and a diagonal path both terms land on the same axis. By hand (0.6°, 45°):
// 0.14 mm/cycle · 0.0074 + 0.002 · 0.70 ≈ 0.0025 mm/cycle² = 1.23 × the axis limit (2000 mm/s²)
// without a reserve for the speed change at the joint.
TEST(AccelLimited, GentleCornerWithSpeedChangeKeepsAxisLimits) {
  MachineConfig m = test_machine();
  for (std::size_t i = 0; i < 3; ++i) m.axes[i].max_accel_mm_s2 = m.max_accel_mm_s2;
  for (double deg : {0.15, 0.3, 0.6, 1.0, 3.0}) {
    for (double dir : {1.0, -1.0}) {
      for (int variant = 0; variant < 3; ++variant) {
        SCOPED_TRACE(::testing::Message()
                     << deg << " deg, turn " << dir << ", variant " << variant);
        const double a0 = kPi / 4;
        const double a1 = a0 + dir * deg * kPi / 180;
        Prog p;
        // 0: brake through the joint towards the end 5 mm later; 1: accelerate through it (feed
        // rises at the joint); 2: accelerate from rest through it (short first segment).
        const double len1 = variant == 2 ? 2.0 : 50.0;
        const double len2 = variant == 0 ? 5.0 : 50.0;
        const Vec3 j{len1 * std::cos(a0), len1 * std::sin(a0), 0};
        p.line_to(j, variant == 1 ? 6000 : 10000);
        p.line_to(j + Vec3{len2 * std::cos(a1), len2 * std::sin(a1), 0}, 10000);
        const RunResult r = run_checked(m, p);
        const auto acc = axis_accel_by_differences(r, m.period_s);
        for (std::size_t i = 0; i < 3; ++i) {
          EXPECT_LE(acc[i], m.axes[i].max_accel_mm_s2 * 1.005) << "axis " << i;
        }
      }
    }
  }
}

// A curve of 0.5 mm lines turning 0.8° each (a CAM contour) on a diagonal, axis limits = Amax,
// at F 3 000 with the override stepping up to 200 % and down while the tool is in the curve.
// The joint zones there are sized for F (50 mm/s) instead of the machine's 333 mm/s, with a
// joint cap of F that holds above 100 % (accel_limited.cpp 7.): every axis stays within its
// limit at every override. Without that cap (zones sized for F, corners passed at 200 % of it)
// Y measured 2 152 mm/s² on a 2 000 axis.
TEST(AccelLimited, GentleCornersAtTheFeedKeepAxisLimitsAtEveryOverride) {
  MachineConfig m = test_machine();
  for (std::size_t i = 0; i < 3; ++i) m.axes[i].max_accel_mm_s2 = m.max_accel_mm_s2;
  for (const double turn_deg : {0.8, -0.8, 2.0}) {
    SCOPED_TRACE(::testing::Message() << turn_deg << " deg per corner");
    Prog p;
    Vec3 at{0, 0, 0};
    double ang = kPi / 4;
    for (int i = 0; i < 400; ++i) {
      at = at + Vec3{0.5 * std::cos(ang), 0.5 * std::sin(ang), 0};
      p.line_to(at, 3000);
      ang += turn_deg * kPi / 180;
    }
    RunOpts o = accel_opts();
    o.override_steps = {{0.3, 200.0}, {0.9, 50.0}, {1.3, 200.0}, {1.9, 120.0}, {2.6, 200.0}};
    const RunResult r = run(m, p.blocks, o);
    auto lim = testing::limits_from_config(m);
    const auto rep = testing::check_trajectory(r.traj, p.blocks, lim);
    EXPECT_TRUE(rep.ok()) << rep.summary();
    EXPECT_EQ(r.mismatches, 0u);
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_LE(rep.max_axis_accel_mm_s2[i], m.axes[i].max_accel_mm_s2 * 1.005) << "axis " << i;
    }
    expect_ends(r, {}, p.pos);
  }
}

TEST(AccelLimited, ZigZagHelicesAndLateBlocks) {
  const MachineConfig m = test_machine();
  Prog z;
  for (int i = 0; i < 40; ++i) {
    z.line_to(Vec3{i % 2 == 0 ? 5.0 : 0.0, i * 0.5, 0}, 10000);
    z.line_to(Vec3{i % 2 == 0 ? 5.0 : 0.0, (i + 1) * 0.5, 0}, 10000);
  }
  run_checked(m, z);
  Prog h;
  h.line_to(Vec3{5, 0, 0}, 8000);
  h.arc_to(Vec3{-5, 0, -3}, Vec3{0, 0, 0}, 8000);
  h.arc_to(Vec3{-5, 0, -13}, Vec3{0, 0, -3}, 8000, {0, 0, 1}, 2);
  h.arc_to(Vec3{-5, 5, -18}, Vec3{-5, 0, -18}, 6000, {0, 0, -1});
  h.line_to(Vec3{0, 0, 0}, 10000);
  run_checked(m, h);
  Prog c;
  for (int i = 0; i < 200; ++i) {
    const double a = i * 0.1;
    c.line_to(Vec3{20 * std::cos(a), 20 * std::sin(a), 0}, 10000);
  }
  for (std::size_t every : {1u, 3u}) {
    RunOpts o = accel_opts();
    o.feed_every = every;
    run_checked(m, c, o);
  }
  MachineConfig small = m;
  small.lookahead_blocks = 3;
  run_checked(small, seed_example());
}

// Segments shorter than a corner's passing speed: a joint cap [j − Vg, j + Vg) reaches over
// several segments, so the oldest segment in the buffer is still needed after the tool has
// passed it. With a small buffer and blocks arriving late the buffer is full of such segments
// and the tool waits at the window's end for the next block: the kernel must still accept it
// (found by RandomProgramsWithOverrideSteps, seed 16775138560219754814: the tool waited 2000 s
// 0.9 µm before the end).
TEST(AccelLimited, FullSmallBufferOfSegmentsShorterThanTheirCornerCapsDoesNotWait) {
  MachineConfig m = test_machine();
  m.lookahead_blocks = 5;
  Prog p;
  for (int i = 0; i < 60; ++i) {
    const double a = (i % 2 == 0 ? 40.0 : -40.0) * std::numbers::pi / 180;
    const double len = 0.0002 + 0.0001 * (i % 3);
    p.line_to(p.pos.xyz() + Vec3{len * std::cos(a), len * std::sin(a), 0}, 8000);
  }
  for (std::size_t every : {1u, 2u}) {
    RunOpts o = accel_opts();
    o.feed_every = every;
    o.max_cycles = 100000;  // the path is 21 µm long: it takes a few hundred cycles
    const RunResult r = run_checked(m, p, o);
    EXPECT_LT(r.samples.size(), 2000u) << "feed_every " << every;
  }
}

TEST(AccelLimited, RapidsReachTheRapidRateAndEventsHappenInOrder) {
  const MachineConfig m = test_machine();
  const Prog p = events_example();
  const RunResult r = run_checked(m, p);
  std::string order;
  for (const auto& s : r.samples) {
    if (s.aux_letter != 0)
      order += s.aux_letter + std::to_string(static_cast<int>(s.aux_value)) + " ";
  }
  EXPECT_EQ(order, "S12000 M3 M8 M5 ");
  const auto rep = check(m, p.blocks, r);
  // 15 000 mm/min = 250 mm/s (the moving average holds rapids to Amax·T·τ = 168 mm/s).
  EXPECT_NEAR(rep.max_speed_mm_s, 250, 1e-6);
}

TEST(AccelLimited, OverrideStepsAndFeedHold) {
  const MachineConfig m = test_machine();
  RunOpts o = accel_opts();
  o.override_steps = p5_override_steps();
  run_checked(m, corner_example(6000), o);
  RunOpts h = accel_opts();
  h.hold_steps = {{0.2, true}, {0.6, false}};
  const RunResult r = run_checked(m, seed_example(10000), h);
  // Stopped within Vmax/Amax (+2 cycles) of the hold, until the resume.
  for (const auto& s : r.samples) {
    if (s.t_s >= 0.2 + 10000.0 / 60 / 2000 + 0.002 && s.t_s < 0.6) {
      ASSERT_EQ(s.feed_mm_min, 0.0) << "t " << s.t_s;
    }
  }
}

TEST(AccelLimited, PerAxisLimitsAndRotaryAxes) {
  MachineConfig m = test_machine();
  m.axes[kY].max_speed_mm_min = 3000;
  m.axes[kY].max_accel_mm_s2 = 500;
  m.axes[kZ].max_accel_mm_s2 = 300;
  Prog p;
  p.line_to(Vec3{30, 30, 0}, 10000);
  p.line_to(Vec3{60, 0, -5}, 10000);
  p.arc_to(Vec3{60, 20, -5}, Vec3{60, 10, -5}, 10000);
  p.line_to(Vec3{0, 0, 0}, 10000);
  const RunResult r = run_checked(m, p);
  const auto rep = check(m, p.blocks, r);
  EXPECT_LE(rep.max_axis_accel_mm_s2[kY], 500 * 1.005);

  MachineConfig ma = test_machine();
  ma.axes[kA].enabled = true;
  ma.axes[kA].rotary = true;
  ma.axes[kA].max_speed_mm_min = 3600;
  ma.axes[kA].max_accel_mm_s2 = 720;
  Prog q;
  AxisVec a;
  a.set_xyz(Vec3{20, 0, 0});
  a[kA] = 90;
  q.line_to(a, 10000);
  a[kA] = 0;
  q.line_to(a, 3000);
  run_checked(ma, q);
}

// Axis limits equal to Amax (the built-in machine): on arcs the normal and tangential
// accelerations share the axes; with the resultant option the path resultant is bounded.
TEST(AccelLimited, ArcsWithCoupledAxisLimitsAndResultant) {
  MachineConfig m = test_machine();
  for (std::size_t i = 0; i < 3; ++i) m.axes[i].max_accel_mm_s2 = m.max_accel_mm_s2;
  Prog p;
  p.line_to(Vec3{20, 0, 0}, 10000);
  p.arc_to(Vec3{20, 20, 0}, Vec3{20, 10, 0}, 10000);
  p.arc_to(Vec3{20, 22, 0}, Vec3{20, 21, 0}, 10000, {0, 0, -1});
  p.line_to(Vec3{0, 22, 0}, 10000);
  run_checked(m, p);
  RunOpts o = accel_opts();
  o.kernel.bound_resultant_accel = true;
  const RunResult r = run(m, p.blocks, o);
  testing::Limits lim = testing::limits_from_config(m);
  lim.max_resultant_accel_mm_s2 = m.max_accel_mm_s2;
  const auto rep = testing::check_trajectory(r.traj, p.blocks, lim);
  EXPECT_TRUE(rep.ok()) << rep.summary();
}

// P6: much faster than stop mode on tiny segments, and not slower than the moving average.
TEST(AccelLimited, FasterThanStopModeAndMovingAverage) {
  const MachineConfig m = test_machine();
  Prog p;
  for (int i = 1; i <= 2000; ++i) {
    const double a = i * 0.05 / 20;
    p.line_to(Vec3{20 * std::sin(a), 20 - 20 * std::cos(a), 0}, 10000);
  }
  RunOpts ma;
  RunOpts stop;
  stop.kernel.mode = Mode::kStop;
  const RunResult acc = run_checked(m, p);
  const RunResult r_ma = run(m, p.blocks, ma);
  const RunResult r_stop = run(m, p.blocks, stop);
  // One long ramp up and down: both types are time-optimal there (a few cycles apart).
  EXPECT_LE(acc.time_s(), r_ma.time_s() * 1.01);
  EXPECT_LT(acc.time_s() * 50, r_stop.time_s());
  std::printf("2000 chords of 0.05 mm: acceleration %.3f s, moving average %.3f s, stop %.3f s\n",
              acc.time_s(), r_ma.time_s(), r_stop.time_s());
}

// P5 on random programs with random override steps: the generator of kernel_test.cpp, this type.
// An override decrease on an arc run at its top speed, where the normal acceleration takes
// 0.95 of the slow Y axis's budget g = 800 mm/s²: the tangent has √(g² − a_n²) = 250 mm/s² at
// first, and slowing down it may use √((0.98·g)² − (v²/ρ)²) once that is more. Integrating
// dv/dt = −max(250, √(784² − (v²/ρ)²)) from 123 mm/s (R 20: a_n = 760) down to the new limit
// 16.7 mm/s takes 0.168 s; at a fixed 250 mm/s² it would take 0.43 s. Measured from the
// positions: below the new limit within 0.168 s + 3 cycles.
TEST(AccelLimited, OverrideDecreaseOnAFastArcDeceleratesWithWhatTheSpeedLeaves) {
  MachineConfig m = test_machine();
  m.axes[kY].max_accel_mm_s2 = 800;
  Prog p;
  p.arc_to(Vec3{40, 0, 0}, Vec3{20, 0, 0}, 10000);  // half circle R 20 in XY
  RunOpts o = accel_opts();
  o.override_steps = {{0.5, 10}};
  const RunResult r = run(m, p.blocks, o);
  auto lim = testing::limits_from_config(m);
  lim.override_ramp_s = 0.168 + 0.003;
  const auto rep = testing::check_trajectory(r.traj, p.blocks, lim);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  double top = 0, below_at = -1;
  for (std::size_t k = 1; k < r.samples.size(); ++k) {
    const double v =
        norm(r.samples[k].position.xyz() - r.samples[k - 1].position.xyz()) / m.period_s;
    if (r.samples[k].t_s < 0.5) top = std::max(top, v);
    if (r.samples[k].t_s >= 0.5 && below_at < 0 && v <= 10000.0 / 60 * 0.1 * 1.005) {
      below_at = r.samples[k].t_s;
    }
  }
  EXPECT_NEAR(top, std::sqrt(0.95 * 800 * 20), 0.5);  // the arc's top speed, a_n = 0.95·g
  EXPECT_GT(below_at, 0.5);
  EXPECT_LE(below_at - 0.5, 0.168 + 0.003);
}

// The same arc from rest: r is fixed for the top speed (√(1 − 0.95²)·800 = 250 mm/s²), but
// while the speed is low the normal acceleration leaves most of g for the tangent. Inside the
// arc the type rises by min(A0, √((0.98·g)² − (u⁺²/ρ)²)) (accel_limited.cpp, step()): 784
// mm/s² at the start, measured here from the positions; the limits still hold.
TEST(AccelLimited, ArcRampsWithWhatTheSpeedLeaves) {
  MachineConfig m = test_machine();
  m.axes[kY].max_accel_mm_s2 = 800;
  Prog p;
  p.arc_to(Vec3{40, 0, 0}, Vec3{20, 0, 0}, 10000);
  const RunResult r = run(m, p.blocks, accel_opts());
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  auto speed = [&](std::size_t k) {
    return norm(r.samples[k].position.xyz() - r.samples[k - 1].position.xyz()) / m.period_s;
  };
  // Cycles 5–15: v ≤ 13 mm/s, a_n = v²/ρ ≤ 8.5 mm/s², so √(784² − a_n²) ≈ 784.
  for (std::size_t k = 6; k <= 15; ++k) {
    const double a_t = (speed(k) - speed(k - 1)) / m.period_s;
    EXPECT_GT(a_t, 0.95 * 0.98 * 800) << "cycle " << k;
    EXPECT_LE(a_t, 0.98 * 800 * 1.005) << "cycle " << k;
  }
  // And the top speed is still the arc's (a_n = 0.95·g).
  double top = 0;
  for (std::size_t k = 1; k < r.samples.size(); ++k) top = std::max(top, speed(k));
  EXPECT_NEAR(top, std::sqrt(0.95 * 800 * 20), 0.5);
}

// A zig-zag of 5 mm strokes turning 53° at every corner: Vg = Amax·τ/(2 sin 26.6°) = 2.24 mm/s.
// The cycle after the one that crosses a corner no longer keeps the corner's cap: its limit is
// the exact second difference around the crossing (accel_limited.cpp, 9.), so where the crossing
// sample lies close to the corner the speed rises by up to Amax·τ at once. Measured from the
// positions: the first chord after each corner's crossing chord.
TEST(AccelLimited, SpeedRisesRightAfterTheCycleThatCrossesACappedCorner) {
  const MachineConfig m = test_machine();
  Prog p;
  for (int i = 1; i <= 20; ++i) p.line_to(Vec3{5.0 * i, i % 2 ? 2.5 : 0.0, 0}, 10000);
  const RunResult r = run_checked(m, p);
  const double vg = m.max_accel_mm_s2 * m.period_s / (2 * std::sin(std::atan(0.5)));
  auto chord = [&](std::size_t k) {
    return norm(r.samples[k].position.xyz() - r.samples[k - 1].position.xyz()) / m.period_s;
  };
  int corners = 0, risen = 0;
  for (int i = 1; i < 20; ++i) {
    const double x = 5.0 * i;
    std::size_t k = 1;
    while (k < r.samples.size() && r.samples[k].position[kX] < x) ++k;
    ASSERT_LT(k + 1, r.samples.size());
    ++corners;
    EXPECT_LE(chord(k), vg * 1.005) << "corner " << i;  // the crossing chord (≤ its path speed)
    if (chord(k + 1) >= vg + 0.5 * m.max_accel_mm_s2 * m.period_s) ++risen;
  }
  EXPECT_EQ(corners, 19);
  EXPECT_GE(risen, 15) << "of " << corners;
}

// The machine of a shrunk case of the coupled-axes properties below: X, Y, Z limits (mm/s²)
// and the look-ahead window they drew.
MachineConfig coupled_machine(double x_mm_s2, double y_mm_s2, double z_mm_s2,
                              std::uint32_t window) {
  MachineConfig m = test_machine();
  m.axes[kX].max_accel_mm_s2 = x_mm_s2;
  m.axes[kY].max_accel_mm_s2 = y_mm_s2;
  m.axes[kZ].max_accel_mm_s2 = z_mm_s2;
  m.lookahead_blocks = window;
  return m;
}

// A capped corner 0.05 mm before an exact stop (seed 57 of RandomProgramsWithCoupledAxesAndLines,
// Y and Z at Amax, X faster): the tool brakes for the stop through the corner's zone, and the
// stop's bounds in real distance took the segments' plain r, so the pair across the corner
// slowed by 1.64 µm/cycle² where the zone allows 1.27: Y 2 018.7 on a 2 000 axis. Stops now
// brake with the zones' r (accel_limited.cpp 3.).
TEST(AccelLimited, CappedCornerJustBeforeAnExactStopKeepsTheAxisLimit) {
  const MachineConfig m = coupled_machine(2600, 2000, 2000, 4);
  Prog p;
  p.line_to(Vec3{-15.75, -24.18, -4.92}, 3000);
  p.line_to(Vec3{-18.62, -28.17, -5.7}, 3000, PathMode::kExactPath);
  p.line_to(Vec3{-18.65585, -28.2081, -5.70515}, 10000, PathMode::kExactStop);
  for (const std::size_t feed_every : {0, 1}) {
    RunOpts o = accel_opts();
    o.feed_every = feed_every;
    const RunResult r = run(m, p.blocks, o);
    const auto rep = testing::check_trajectory(r.traj, p.blocks, testing::limits_from_config(m));
    EXPECT_TRUE(rep.ok()) << "feed_every " << feed_every << ": " << rep.summary();
    EXPECT_LE(rep.max_axis_accel_mm_s2[kY], 2000 * 1.005) << feed_every;
  }
}

// The same before the program's end, the window's last stop (seeds 74 and 78 of
// RandomProgramsWithCoupledAxesAndLines): the stop's landing step in real distance took the plain
// r, so the pair across a gentle corner 0.03 mm before the end slowed by 1.40 µm/cycle² where the
// zone leaves 1.18 (X 1 475.6 on a 1 400 axis), and a 0.02 mm line after a long one at 150 %
// override gave X 2 033.7 on a 2 000 axis. Every stop now brakes with the zones' r, and a block
// whose zone would lower those bounds at once is held (accel_limited.cpp 3., 6.).
TEST(AccelLimited, CappedCornerJustBeforeTheProgramEndKeepsTheAxisLimit) {
  struct Case {
    MachineConfig m;
    Prog p;
    std::vector<std::pair<double, double>> override_steps;
  };
  std::vector<Case> cases;
  {
    Case c{coupled_machine(1400, 2600, 2600, 4), {}, {}};
    c.p.line_to(Vec3{-5, -5, -1.5}, 3000, PathMode::kExactStop);
    c.p.line_to(Vec3{-5.4425, -5.262, -1.586}, 8000, PathMode::kExactPath);  // 0.52 mm
    c.p.line_to(Vec3{-5.4684, -5.27735, -1.59725}, 3000);                    // 0.03 mm
    cases.push_back(c);
  }
  {
    Case c{coupled_machine(2000, 2000, 1400, 4), {}, {{0.0, 150.0}, {2.5, 100.0}}};
    c.p.line_to(Vec3{-27.99, -12.18, -8.94}, 3000);
    c.p.line_to(Vec3{-28.0046, -12.1906, -8.94795}, 10000);  // 0.02 mm
    cases.push_back(c);
  }
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const Case& c = cases[k];
    for (const std::size_t feed_every : {0, 1}) {
      RunOpts o = accel_opts();
      o.feed_every = feed_every;
      o.override_steps = c.override_steps;
      const RunResult r = run(c.m, c.p.blocks, o);
      const auto rep = check(c.m, c.p.blocks, r);
      EXPECT_TRUE(rep.ok()) << rep.summary();
      EXPECT_EQ(r.mismatches, 0u);
      expect_ends(r, {}, c.p.pos);
      EXPECT_LE(rep.max_axis_accel_mm_s2[kX], c.m.axes[kX].max_accel_mm_s2 * 1.005)
          << "case " << k << ", feed_every " << feed_every;
    }
  }
}

// Two corners within one cycle's travel (a segment shorter than the step between them): the
// cycle that turns both at once also changes speed, so the zone of the chain must leave each
// axis room for both (accel_limited.cpp 7., chains). With the combined turn alone using the
// whole X budget (its corner speed 7.31 mm/s = 1 400 mm/s² · 1 ms / |S_x − E_x|, 0.1915), the
// crossing pair also sped up by 0.49 mm/s (489 mm/s²) and X measured 1 407 mm/s² (seed 2 of
// RandomProgramsWithCoupledAxesAndLines, a 1.34 µm line), and Y 603 mm/s² on a 600 axis (seed
// 7: a 0.82 µm line at F 500 after an exact-path corner, override 150 %). Measured by the
// checker from the samples.
TEST(AccelLimited, TwoCornersWithinOneCycleShareTheAxisBudgetWithTheSpeedChange) {
  {
    const MachineConfig m = coupled_machine(1400, 1400, 2600, 4);
    Prog p;
    p.line_to(Vec3{-0.02915, -0.04645, -0.015}, 3000);
    p.line_to(Vec3{-0.029991, -0.04745, -0.0153}, 3000);  // 1.34 µm
    p.line_to(Vec3{-5.01499, -4.92245, -1.2403}, 8000);
    run_checked(m, p);
  }
  {
    const MachineConfig m = coupled_machine(1400, 600, 2600, 4);
    Prog p;
    p.line_to(Vec3{-30, -30, -9}, 10000, PathMode::kExactPath);
    p.line_to(Vec3{-30.00053, -30.000576, -9.000259}, 500);  // 0.82 µm
    p.line_to(Vec3{-33.77053, -33.790576, -10.025259}, 8000);
    RunOpts o = accel_opts();
    o.override_steps = {{0.377, 150.0}};
    run_checked(m, p, o);
  }
}

// A random program of lines, rapids, arcs and helices with random override steps on machine m
// (random buffer size, sometimes late blocks): P1–P5 by the checker, the bound equal to the walk,
// the end point reached at rest.
void random_program_with_override_steps(MachineConfig m, double override_ramp_s = -1,
                                        bool arcs_only = false) {
  m.lookahead_blocks = *rc::gen::inRange(4, 40);
  const Prog p = random_moves(arcs_only);
  RunOpts o = accel_opts();
  // The slowest case (14 × 42 mm at 500 mm/min × 10 %) needs < 1 M cycles: a run that creeps
  // fails quickly (end point not reached) instead of running 50 M cycles per shrink step.
  o.max_cycles = 2'000'000;
  o.feed_every = *rc::gen::element<std::size_t>(0, 0, 1);  // sometimes late blocks
  add_random_override_steps(o);
  const RunResult r = run(m, p.blocks, o);
  auto lim = testing::limits_from_config(m);
  lim.override_ramp_s = override_ramp_s;
  const auto rep = testing::check_trajectory(r.traj, p.blocks, lim);
  if (!rep.ok()) {
    RC_LOG() << rep.summary() << " feed_every " << o.feed_every << " buffer " << m.lookahead_blocks
             << " axes " << m.axes[0].max_accel_mm_s2 << " " << m.axes[1].max_accel_mm_s2 << " "
             << m.axes[2].max_accel_mm_s2 << "\n";
    log_case(p.blocks, o);
  }
  RC_ASSERT(rep.ok());
  RC_ASSERT(r.mismatches == 0u);
  for (std::size_t i = 0; i < 3; ++i)
    RC_ASSERT(std::abs(r.samples.back().position[i] - p.pos[i]) <= 1e-9);
  RC_ASSERT(r.samples.back().feed_mm_min == 0.0);
}

RC_GTEST_PROP(AccelLimited, RandomProgramsWithOverrideSteps, ()) {
  random_program_with_override_steps(test_machine());
}

// Braking on the same arc for a reversal at its end (a joint cap of V_t): the braking bounds take
// r·A0 = 250 mm/s² for the arc (r fixed for its top speed), but while braking the tangent may
// use a(v) = √((0.98·g)² − (v²/ρ)²) (accel_limited.cpp, 10.): at 10–60 mm/s, a_n ≤ 180 mm/s² and
// a(v) ≥ 763 mm/s². Measured from the positions: those cycles slow down by more than 0.9 × 763
// mm/s² (not 250) and never by more than 784; the limits hold.
TEST(AccelLimited, ArcBrakesWithWhatTheSpeedLeaves) {
  MachineConfig m = test_machine();
  m.axes[kY].max_accel_mm_s2 = 800;
  Prog p;
  p.arc_to(Vec3{40, 0, 0}, Vec3{20, 0, 0}, 10000);  // half circle R 20 in XY, ends along ±Y
  const Vec3 end_dir = p.blocks.back().normal.z > 0 ? Vec3{0, 1, 0} : Vec3{0, -1, 0};
  p.line_to(Vec3{40, 0, 0} - 10.0 * end_dir, 10000);  // back the way it came
  const RunResult r = run(m, p.blocks, accel_opts());
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  auto speed = [&](std::size_t k) {
    return norm(r.samples[k].position.xyz() - r.samples[k - 1].position.xyz()) / m.period_s;
  };
  std::size_t fast = 0, slow = 0;
  for (std::size_t k = 2; k < r.samples.size(); ++k) {
    if (r.samples[k].line != p.blocks.front().line) continue;
    const double v0 = speed(k - 1), v1 = speed(k);
    if (v1 >= v0 || v1 < 10 || v0 > 60) continue;
    const double dec = (v0 - v1) / m.period_s;
    EXPECT_LE(dec, 0.98 * 800 * 1.005) << "cycle " << k;
    (dec > 0.9 * 763 ? fast : slow) += 1;
  }
  EXPECT_GE(fast, 30u);  // 50 mm/s at ~770 mm/s²: ~65 cycles
  EXPECT_LE(slow, 3u);
}

// The same with axis limits near Amax (2 000 mm/s²), where an arc's normal and tangential
// acceleration share the axes of its plane (accel_limited.cpp 2., 5., 9.: the arc's top speed,
// its rise and its braking with what the speed leaves); test_machine()'s 10 000 mm/s² axes never
// couple. Arcs and helices only here; with lines, rapids and path modes too below. Before the
// stop's bounds took the lowest r up to the stop (4.), this failed at 16 of 36 seeds × 300 cases
// (seed 13: 3 698 mm/s² on a 2 000 axis); 60 × 300 pass.
void random_program_with_coupled_axes(bool arcs_only) {
  MachineConfig m = test_machine();
  for (std::size_t i = 0; i < 3; ++i) {
    m.axes[i].max_accel_mm_s2 = *rc::gen::element(600.0, 1400.0, 2000.0, 2000.0, 2600.0);
  }
  // After an override decrease the speed falls at the segment's rate, down to 600 mm/s² on a
  // line along the slowest axis and √(1 − 0.95²) = 0.31 of it on an arc at its top speed (2.):
  // the checker's default ramp assumes Amax. The fastest limit is 20 000 mm/min × 150 %.
  random_program_with_override_steps(m, 20000 * 1.5 / 60 / (0.31 * 600) + 0.002, arcs_only);
}

RC_GTEST_PROP(AccelLimited, RandomProgramsWithCoupledArcAxes, ()) {
  random_program_with_coupled_axes(true);
}

// The same with lines, rapids and the three path modes as well. Before the zone of a chain of
// corners left the speed change its share of the combined turn (TwoCornersWithinOneCycle...
// above) it failed at seeds 1, 2, 7 and 13 of 60 × 300 cases, and at seeds 57, 74 and 78 until
// every stop braked with the zones' r (CappedCornerJustBefore...); 120 × 300 pass.
RC_GTEST_PROP(AccelLimited, RandomProgramsWithCoupledAxesAndLines, ()) {
  random_program_with_coupled_axes(false);
}

// Centred corners (accel_limited.cpp 11.): the zig-zag of zigzag_0.002_0.0005.ngc (53° corners
// every 0.0568 mm, Vg = 2.24 µm per cycle, A0 = 2 µm per cycle², every axis at Amax). The step
// before the crossing and the one before it may exceed the cap's braking bound; the next cycle
// then must take a centred step whatever it is told. So a feed hold and an override drop to
// 30 % start at each cycle of one corner's approach; every run keeps P1–P4.
Prog centred_zigzag(int corners) {
  Prog p;
  for (int i = 1; i <= corners + 1; ++i) {
    p.line_to(Vec3{0.0508 * i, i % 2 ? -0.0127 : 0.0127, 0}, 9999 * 25.4);
  }
  return p;
}

MachineConfig centred_machine() {
  MachineConfig m = test_machine();
  for (std::size_t i = 0; i < 3; ++i) m.axes[i].max_accel_mm_s2 = m.max_accel_mm_s2;
  return m;
}

TEST(AccelLimited, CentredCornersPassAZigZagFaster) {
  const MachineConfig m = centred_machine();
  const RunResult r = run_checked(m, centred_zigzag(40));
  // 41 segments: 0.412 s with the cap held before the crossing (before 11.), 0.373 s centred
  // (the bound's pattern … V + A0, V, V + A0 … at each corner).
  EXPECT_LE(r.time_s(), 0.380);
}

// A feed hold (released after hold_s), an override drop to 30 % and a rise from 50 % to 100 %,
// each started at every cycle k0 … k1 (ms): every run keeps P1–P4 and ends at the program's end.
void hold_drop_rise_at_every_cycle(const MachineConfig& m, const Prog& p, int k0, int k1,
                                   double hold_s) {
  for (int k = k0; k <= k1; ++k) {
    const double t = 0.001 * k;
    RunOpts h = accel_opts();
    h.hold_steps = {{t, true}, {t + hold_s, false}};
    run_checked(m, p, h);
    RunOpts o = accel_opts();
    o.override_steps = {{t, 30}};
    run_checked(m, p, o);
    RunOpts up = accel_opts();
    up.override_steps = {{0.0, 50}, {t, 100}};
    run_checked(m, p, up);
  }
}

TEST(AccelLimited, CentredCornersUnderAHoldOrAnOverrideDropAtEveryCycle) {
  const MachineConfig m = centred_machine();
  const Prog p = centred_zigzag(6);
  // The third corner is crossed near 0.03 s: start the hold or the drop at each cycle of
  // [0.020, 0.036] s (its approach, the committing and the centred step among them).
  hold_drop_rise_at_every_cycle(m, p, 20, 36, 0.02);
}

// Centred corners inside joint zones (accel_limited.cpp 11., 9.): line-contouring-xz's gentle
// polyline in XZ (1.33 mm chords turning 4.8°, every axis at Amax, F 10 000). Each corner is
// capped (Vg ≈ 23 mm/s) and its zone at the floor (r = 0.25 over [j − 2V, j + V]). The slowest
// step after the committing, the centred and the crossing step is that step less ρ·A0, ρ the
// mean r over the step (or the r where it lands, for a hold): with r_hi = 1 (a's r) instead,
// the committing step and 9.'s step after the crossing were never feasible there.
Prog contour_polyline(int segments, double turn_deg, double chord_mm) {
  Prog p;
  Vec3 at{0, 0, 0};
  double phi = 0;
  for (int i = 0; i < segments; ++i) {
    at = at + chord_mm * Vec3{std::sin(phi), 0, std::cos(phi)};
    p.line_to(at, 10000);
    phi += turn_deg * kPi / 180;
  }
  return p;
}

TEST(AccelLimited, CentredCornersInsideJointZonesPassAPolylineFaster) {
  const MachineConfig m = centred_machine();
  const RunResult r = run_checked(m, contour_polyline(12, 4.8, 1.33));
  std::printf("polyline of 12 chords turning 4.8°: %.3f s\n", r.time_s());
  // 0.437 s with r_hi = 1 (438 cycles), 0.431 s with ρ (432 cycles).
  EXPECT_LE(r.time_s(), 0.433);
}

TEST(AccelLimited, CentredCornersInsideJointZonesUnderAHoldOrAnOverrideDropAtEveryCycle) {
  const MachineConfig m = centred_machine();
  const Prog p = contour_polyline(5, 4.8, 1.33);
  // The second corner (2.66 mm) is crossed near 0.073 s: start the hold or the drop at each
  // cycle of its approach and of the cycles after it.
  hold_drop_rise_at_every_cycle(m, p, 55, 80, 0.03);
}

// cam-short-segments' rosette r = 30 + 6·sin(6φ) mm, two lobes in 400 chords of 0.13–0.2 mm at
// F 6 000 after a 30 mm line (every axis at Amax): the tool brakes and speeds up through the
// joint zones of its 0.5–4° corners: 1.441 s with the zones' r for decreases and increases alike;
// 1.430 s with σ running the zones' decreases at their own r (7.); 1.418 s with the line's own
// r for the rise where the pair at the tool lies on one line (4.).
TEST(AccelLimited, RosetteOfShortChordsBrakesAndRisesAtTheZonesOwnLimits) {
  const MachineConfig m = centred_machine();
  Prog p;
  for (int k = 0; k <= 400; ++k) {
    const double phi = 2 * kPi * k / 1200, r = 30 + 6 * std::sin(6 * phi);
    p.line_to(Vec3{r * std::cos(phi), r * std::sin(phi), 0}, 6000);
  }
  const RunResult r = run_checked(m, p);
  std::printf("rosette of 400 chords: %.3f s\n", r.time_s());
  EXPECT_LE(r.time_s(), 1.421);
}

// A circle of 16 µm chords with its coordinates rounded to 0.0001 inch (circle_small_segments of
// the LinuxCNC tests, here `chords` of them from the top): the rounding makes corners of 4–12°
// every few chords, whose zones (7.) cover the whole path, sized for each corner's cap.
Prog rounded_circle(int chords) {
  Prog p;
  const double r = 25.4, q = 0.00254;
  p.rapid_to(Vec3{0, r, 0});
  for (int i = 1; i <= chords; ++i) {
    const double a = 2 * kPi * i / 10000;
    p.line_to(Vec3{std::round(r * std::sin(a) / q) * q, std::round(r * std::cos(a) / q) * q, 0},
              9999 * 25.4);
  }
  return p;
}

// 12.: a pair of steps across one joint between lines rises by its exact limit, not by the
// zones' r. 2 500 chords: 3.462 s with the zones' r (before 12.), 3.414 s.
TEST(AccelLimited, PairsAcrossOneJointRiseByTheirExactLimit) {
  const MachineConfig m = centred_machine();
  const RunResult r = run_checked(m, rounded_circle(2500));
  std::printf("rounded circle of 2 500 chords: %.3f s\n", r.time_s());
  EXPECT_LE(r.time_s(), 3.44);
}

// 13. forward: on the rounded circle the sharper micro-corners' caps (9 µm/cycle at 12.5°) keep
// the speed at the gentler joints after them below those joints' own caps; sized for what
// accelerating at A0 leaves there, their zones let the speed fall faster towards the next
// sharp one. 2 500 chords: 3.336 s with the zones sized for their own caps, 3.312 s.
TEST(AccelLimited, JointsAfterALowCapAreZonedForWhatAcceleratingLeaves) {
  const MachineConfig m = centred_machine();
  const RunResult r = run_checked(m, rounded_circle(2500));
  EXPECT_LE(r.time_s(), 3.324);
}

TEST(AccelLimited, PairsAcrossOneJointUnderAHoldOrAnOverrideDropAtEveryCycle) {
  hold_drop_rise_at_every_cycle(centred_machine(), rounded_circle(150), 20, 60, 0.01);
}

// A polyline from the origin: (length mm, direction in degrees in the XY plane) per line.
Prog xy_polyline(std::initializer_list<std::pair<double, double>> len_deg, double feed) {
  Prog p;
  Vec3 at{0, 0, 0};
  for (auto [len, deg] : len_deg) {
    at = at + Vec3{len * std::cos(deg * kPi / 180), len * std::sin(deg * kPi / 180), 0};
    p.line_to(at, feed);
  }
  return p;
}

// The first sample (after the start) whose X reaches x_mm: the end of the cycle that crosses a
// joint there.
std::size_t crossing_sample(const RunResult& r, double x_mm) {
  std::size_t k = 1;
  while (k < r.samples.size() && r.samples[k].position[kX] < x_mm) ++k;
  return k;
}

// How many of the cycles [from, to) slowed down by at least 0.95·Amax·τ², measured from the
// samples' chords.
int full_braking_cycles(const RunResult& r, const MachineConfig& m, std::size_t from,
                        std::size_t to) {
  const double a0_mm = m.max_accel_mm_s2 * m.period_s * m.period_s;
  auto step = [&](std::size_t i) {
    return norm(r.samples[i].position.xyz() - r.samples[i - 1].position.xyz());
  };
  int full = 0;
  for (std::size_t i = from; i < to; ++i) {
    if (step(i) - step(i + 1) >= 0.95 * a0_mm) ++full;
  }
  return full;
}

// A gentle joint (0.5°, no cap of its own at the top speed) 0.2 mm after a 30° corner: its zone
// was sized for the top speed and reached 2·V = 0.33 mm back, over the braking for the 30°
// corner, which then ran at the zone's r (1.45 instead of 2 µm/cycle² on line-contouring-xz's
// pattern). Sized for what the tool can reach from the 30° corner's cap (7.), the braking before
// that corner runs at the full Amax.
TEST(AccelLimited, GentleJointAfterACornerIsZonedForTheSpeedItCanReach) {
  const MachineConfig m = centred_machine();
  const RunResult r = run_checked(m, xy_polyline({{20.0, 0.0}, {0.2, 30.0}, {20.0, 30.5}}, 10000));
  const std::size_t k = crossing_sample(r, 20.0);
  ASSERT_GT(k, 20u);
  // The braking cycles before the crossing's last few (where the corner's own zone and cap act).
  EXPECT_EQ(full_braking_cycles(r, m, k - 16, k - 4), 12);
}

// 13.: a gentle joint (1.5° on a diagonal, its zone at the floor for its own cap of ~60
// µm/cycle) 0.08 mm before a 40° corner: the 40° corner's braking bound keeps the speed there
// far lower, and the zone sized again for it lets the braking before the gentle joint run at the
// full Amax (0.8 instead of 2 µm/cycle² with the zone sized for the gentle joint's cap: 0.422 →
// 0.409 s).
TEST(AccelLimited, GentleJointBeforeASharpCornerIsZonedForTheSpeedItsBrakingLeaves) {
  const MachineConfig m = centred_machine();
  const RunResult r =
      run_checked(m, xy_polyline({{20.0, 45.0}, {0.08, 46.5}, {20.0, 86.5}}, 10000));
  const std::size_t k = crossing_sample(r, 20 * std::cos(kPi / 4));  // the gentle joint's
  ASSERT_GT(k, 20u);
  EXPECT_EQ(full_braking_cycles(r, m, k - 12, k), 12);
}

// A corner cap below A0 at the end of a line of low r (X at 600 mm/s², r = 0.3; the corner's
// per-axis cap 0.6 mm/s): the cap's key bound (3.) is √(A0² + V²) − A0 = 0.09 V at c, and
// followed up to c the tool crawled towards the corner below its cap. The cap takes over where
// its key's bound has come down to V (σ(c) − σ(e) = V), so the last cycles before the corner run
// at the cap.
TEST(AccelLimited, SmallCornerCapIsRunAtNotCrawledTowards) {
  MachineConfig m = test_machine();
  m.axes[kX].max_accel_mm_s2 = 600;
  m.axes[kY].max_accel_mm_s2 = 2000;
  const RunResult r = run_checked(m, xy_polyline({{2.0, 0.0}, {2.0, 90.0}}, 10000));
  const double vg_mm_s = 600 * m.period_s;  // a_x·τ / |S_x − E_x|
  std::size_t k = 1;
  while (k < r.samples.size() && r.samples[k].position[kY] <= 0) ++k;  // the crossing
  ASSERT_GT(k, 40u);
  int slow = 0;
  for (std::size_t i = k - 30; i < k; ++i) {
    const double v =
        norm(r.samples[i].position.xyz() - r.samples[i - 1].position.xyz()) / m.period_s;
    if (v < 0.9 * vg_mm_s) ++slow;
  }
  EXPECT_EQ(slow, 0);  // (3 before: 0.47, 0.35, 0.26 mm/s)
}

// 13. where the gentle joint's zone reaches back over a short segment before it (its tail over
// two segments: a 0.05 mm piece of the line before it): sized again for the 40° corner's
// braking bound, it lets the braking before the gentle joint run at the full Amax (2 of 12
// cycles at the full rate before, 0.422 → 0.410 s).
TEST(AccelLimited, GentleZoneOverTwoSegmentsIsSizedAgainForTheSharpCornerAfter) {
  const MachineConfig m = centred_machine();
  const RunResult r =
      run_checked(m, xy_polyline({{20.0, 45.0}, {0.05, 45.0}, {0.08, 46.5}, {20.0, 86.5}}, 10000));
  const std::size_t k = crossing_sample(r, 20.05 * std::cos(kPi / 4));  // the gentle joint's
  ASSERT_GT(k, 20u);
  EXPECT_EQ(full_braking_cycles(r, m, k - 12, k), 12);
}

// 13. below the braking bound: a 13.6° joint 10.4 µm before a 55° corner (line-contouring-xz,
// line 509, turned into the XY plane). The 55° corner's braking bound at the gentle joint, with
// the lattice's and 11.'s slack, is above the joint's own cap, so the zone stayed sized for the
// cap at the floor's share (5.2 → 4.2 → 3.7 → 3.2 → 2.7 µm/cycle). Sized for what braking at
// A0 leaves there, less A0/2, the last cycles before the joint brake at the full Amax.
TEST(AccelLimited, GentleJointJustBeforeASharpCornerIsZonedForWhatBrakingLeaves) {
  const MachineConfig m = centred_machine();
  const RunResult r =
      run_checked(m, xy_polyline({{1.0, 59.3}, {0.0104, 73.2}, {1.0, 18.6}}, 10000));
  const std::size_t k = crossing_sample(r, 1.0 * std::cos(59.3 * kPi / 180));
  ASSERT_GT(k, 20u);
  // The six cycles before the crossing: 5 at the full rate (one holds at the gentle joint's cap),
  // where the zone at the floor braked 5.2 → 4.2 → 3.7 → 3.2 → 2.7 → 2.3 (0 of 6).
  EXPECT_GE(full_braking_cycles(r, m, k - 6, k), 5);
  EXPECT_LE(r.time_s(), 0.094);  // 0.097 s before
}

// An override drop while the tool brakes through a gentle corner's zone for a slower feed after
// it (seed 23 of RandomProgramsWithCoupledAxesAndLines once σ ran a zone's decreases at their own
// r, 7.): the feed recovery decelerated at the zone's r for increases and fell behind the feed
// keys of the level before, 50.26 mm/s on a 50 mm/s line. It now decelerates at least at σ's mean
// r over the step just taken.
TEST(AccelLimited, OverrideDropInsideAJointZoneKeepsTheFeedOfTheLevelBefore) {
  const MachineConfig m = coupled_machine(2600, 2000, 2600, 4);
  Prog p;
  p.line_to(Vec3{-4.865, -4.28, -1.255}, 8000, PathMode::kExactPath);
  p.line_to(Vec3{-9.63, -8.77, -2.59}, 3000, PathMode::kExactStop);
  RunOpts o = accel_opts();
  o.override_steps = {{0.068, 50.0}, {2.5, 100.0}};
  const RunResult r = run(m, p.blocks, o);
  auto lim = testing::limits_from_config(m);
  lim.override_ramp_s = 20000 * 1.5 / 60 / (0.31 * 600) + 0.002;
  const auto rep = testing::check_trajectory(r.traj, p.blocks, lim);
  EXPECT_TRUE(rep.ok()) << rep.summary();
}

// Random polylines of lines only (turns 0.5–120°, chords 0.02–3 mm, in random planes) on coupled
// axes, with random override steps and feed holds: many capped corners with zones, where 11.
// (committing and centred steps) and 9. (the step after the crossing) apply. P1–P5 by the
// checker.
RC_GTEST_PROP(AccelLimited, RandomPolylinesWithCentredCorners, ()) {
  MachineConfig m = test_machine();
  for (std::size_t i = 0; i < 3; ++i) {
    m.axes[i].max_accel_mm_s2 = *rc::gen::element(600.0, 1400.0, 2000.0, 2000.0, 2600.0);
  }
  m.lookahead_blocks = *rc::gen::inRange(4, 40);
  auto unit = [](Vec3 v) { return (1.0 / norm(v)) * v; };
  auto rnd = [] { return (*rc::gen::inRange(-1000, 1001)) / 1000.0; };
  Vec3 d = unit(Vec3{rnd(), rnd(), rnd()} + Vec3{1e-3, 0, 0});
  Prog p;
  const int n = *rc::gen::inRange(2, 16);
  const double feed = *rc::gen::element(3000.0, 8000.0, 10000.0, 20000.0);
  for (int i = 0; i < n; ++i) {
    const double len = *rc::gen::element(0.02, 0.05, 0.1, 0.3, 1.0, 3.0) *
                       (0.5 + (*rc::gen::inRange(0, 1001)) / 1000.0);
    p.line_to(p.pos.xyz() + len * d, feed);
    // The next direction: d turned by θ towards a random perpendicular.
    const double theta = (*rc::gen::element(0.5, 2.0, 5.0, 15.0, 45.0, 90.0, 120.0)) * kPi / 180;
    Vec3 w{rnd(), rnd(), rnd()};
    w = w - dot(w, d) * d;
    if (norm(w) < 1e-3) w = std::abs(d.x) < 0.9 ? Vec3{1, 0, 0} - d.x * d : Vec3{0, 1, 0} - d.y * d;
    d = unit(std::cos(theta) * d + std::sin(theta) * unit(w));
  }
  RunOpts o = accel_opts();
  o.max_cycles = 2'000'000;
  const int steps = *rc::gen::inRange(0, 4);
  for (int i = 0; i < steps; ++i) {
    o.override_steps.emplace_back((*rc::gen::inRange(0, 300)) / 1000.0,
                                  *rc::gen::element(10.0, 30.0, 50.0, 100.0, 150.0));
  }
  std::sort(o.override_steps.begin(), o.override_steps.end());
  if (!o.override_steps.empty()) o.override_steps.emplace_back(0.5, 100.0);
  if (*rc::gen::element(false, false, true)) {
    const double t = (*rc::gen::inRange(0, 300)) / 1000.0;
    o.hold_steps = {{t, true}, {t + 0.05, false}};
  }
  const RunResult r = run(m, p.blocks, o);
  auto lim = testing::limits_from_config(m);
  // After an override decrease the speed falls at the segment's rate, down to 600 mm/s² (as
  // random_program_with_coupled_axes()).
  lim.override_ramp_s = 20000 * 1.5 / 60 / 600 + 0.002;
  const auto rep = testing::check_trajectory(r.traj, p.blocks, lim);
  if (!rep.ok()) {
    RC_LOG() << rep.summary() << " buffer " << m.lookahead_blocks << " axes "
             << m.axes[0].max_accel_mm_s2 << " " << m.axes[1].max_accel_mm_s2 << " "
             << m.axes[2].max_accel_mm_s2 << "\n";
    for (const Block& b : p.blocks) {
      RC_LOG() << std::setprecision(17) << "(" << b.end[0] << "," << b.end[1] << "," << b.end[2]
               << ") F " << b.feed_mm_min << "\n";
    }
  }
  RC_ASSERT(rep.ok());
  RC_ASSERT(r.mismatches == 0u);
  for (std::size_t i = 0; i < 3; ++i)
    RC_ASSERT(std::abs(r.samples.back().position[i] - p.pos[i]) <= 1e-9);
}

}  // namespace
}  // namespace cncore::motion::test
