// Tests of the checker itself: synthetic trajectories whose speed, acceleration and path error are
// known in closed form; the checker must find exactly what is there.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <ranges>
#include <string>

#include "trajectory_checker.hpp"

namespace cncore::testing {
namespace {

constexpr double kTau = 0.001;

Block line(AxisVec a, AxisVec b, double feed, std::uint32_t ln = 1) {
  Block bl;
  bl.kind = BlockKind::kLine;
  bl.start = a;
  bl.end = b;
  bl.feed_mm_min = feed;
  bl.line = ln;
  return bl;
}
AxisVec P(double x, double y, double z = 0) {
  AxisVec p;
  p[kX] = x;
  p[kY] = y;
  p[kZ] = z;
  return p;
}

// Path position of a continuous trapezoid (accel a up to v, cruise, decel a to rest at L),
// sampled every τ; the last sample is exactly L.
std::vector<double> trapezoid(double L, double v, double a) {
  double ta = v / a;
  double la = 0.5 * a * ta * ta;
  if (2 * la > L) {  // triangle
    ta = std::sqrt(L / a);
    v = a * ta;
    la = L / 2;
  }
  const double tc = (L - 2 * la) / v;
  const double total = 2 * ta + tc;
  std::vector<double> s;
  for (int k = 0;; ++k) {
    const double t = k * kTau;
    if (t >= total) {
      s.push_back(L);
      break;
    }
    double x = 0;
    if (t < ta) {
      x = 0.5 * a * t * t;
    } else if (t < ta + tc) {
      x = la + v * (t - ta);
    } else {
      const double r = total - t;
      x = L - 0.5 * a * r * r;
    }
    s.push_back(x);
  }
  return s;
}

// Samples at path positions s along the path (the geometry's own point_at).
Trajectory follow(const Path& path, const std::vector<double>& s, double override_pct = 100) {
  Trajectory tr;
  std::size_t j = 0;
  for (std::size_t k = 0; k < s.size(); ++k) {
    while (j + 1 < path.segments.size() &&
           s[k] > path.segments[j].s0_mm + path.segments[j].length_mm)
      ++j;
    const auto& sg = path.segments[j];
    const double u = std::clamp((s[k] - sg.s0_mm) / sg.length_mm, 0.0, 1.0);
    tr.add(static_cast<double>(k) * kTau, sg.line, sg.point_at(u), sg.feed_mm_min, override_pct);
  }
  return tr;
}

TEST(TrajectoryChecker, TrapezoidOnALineHasKnownSpeedAndAcceleration) {
  const std::vector<Block> blocks = {line(P(0, 0), P(100, 0), 6000)};
  const auto s = trapezoid(100, 100, 1000);  // 100 mm/s, 1000 mm/s²
  const auto tr = follow(build_path(blocks), s);
  Limits lim;
  const auto rep = check_trajectory(tr, blocks, lim);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_NEAR(rep.max_speed_mm_s, 100, 1e-6);
  EXPECT_NEAR(rep.max_tangential_accel_mm_s2, 1000, 1e-3);
  EXPECT_LT(rep.max_normal_accel_mm_s2, 1e-3);
  EXPECT_LT(rep.max_path_error_mm, 1e-12);
  EXPECT_EQ(rep.end_error_mm, 0);
  EXPECT_NEAR(rep.max_axis_accel_mm_s2[kX], 1000, 1e-3);
  EXPECT_NEAR(rep.duration_s, 1.1, 0.0011);  // 0.1 + 0.9 + 0.1

  // The same trajectory on a machine with Amax = 900: every cycle of both full ramps is a
  // tangential violation (2·100 samples with a second difference of exactly 1000, plus at most
  // the partial ones at the ends of the ramps, which are below 1000 but may exceed 900·1.005).
  lim.max_accel_mm_s2 = 900;
  const auto bad = check_trajectory(tr, blocks, lim);
  EXPECT_GE(bad.count(Property::kTangentialAccel), 198u);
  EXPECT_LE(bad.count(Property::kTangentialAccel), 204u);
  for (const auto& v : bad.violations) {
    if (v.property == Property::kTangentialAccel) {
      EXPECT_LE(v.value, 1000 + 1e-6);
    }
  }
  EXPECT_EQ(bad.count(Property::kSpeed), 0u);
  EXPECT_EQ(bad.count(Property::kPath), 0u);
}

TEST(TrajectoryChecker, SpeedOvershootIsFoundExactlyWhereItIs) {
  // Programmed F3000 = 50 mm/s; the trajectory cruises at 52 mm/s (4 % over, beyond the 0.5 %).
  const std::vector<Block> blocks = {line(P(0, 0), P(50, 0), 3000)};
  const auto s = trapezoid(50, 52, 1000);
  const auto tr = follow(build_path(blocks), s);
  const auto rep = check_trajectory(tr, blocks, Limits{});
  std::size_t expected = 0;
  for (std::size_t k = 1; k < s.size(); ++k)
    if ((s[k] - s[k - 1]) / kTau > 50 * 1.005) ++expected;
  EXPECT_GT(expected, 800u);
  EXPECT_EQ(rep.count(Property::kSpeed), expected) << rep.summary();
  EXPECT_NEAR(rep.max_speed_ratio, 52.0 / 50.0, 1e-9);
  EXPECT_EQ(rep.count(Property::kTangentialAccel), 0u);
}

TEST(TrajectoryChecker, CircleHasNormalAccelerationVSquaredOverR) {
  // Full circle R = 10 about the origin (G3 in G17) at 50 mm/s: a_n = v²/R = 250 mm/s².
  Block arc;
  arc.kind = BlockKind::kArc;
  arc.start = P(10, 0);
  arc.end = P(10, 0);
  arc.center = {0, 0, 0};
  arc.normal = {0, 0, 1};
  arc.feed_mm_min = 3000;
  const std::vector<Block> blocks = {arc};
  const Path path = build_path(blocks);
  ASSERT_EQ(path.segments.size(), 1u);
  EXPECT_NEAR(path.length_mm, 2 * std::numbers::pi * 10, 1e-12);
  const auto tr = follow(path, trapezoid(path.length_mm, 50, 1000));
  const auto rep = check_trajectory(tr, blocks, Limits{});
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_NEAR(rep.max_normal_accel_mm_s2, 250, 0.25);
  // At 50 mm/s the chord turns by v·τ/R = 0.005 rad = 0.2865° per cycle.
  EXPECT_NEAR(rep.max_direction_change_deg, 0.005 * 180 / std::numbers::pi, 1e-4);
  EXPECT_LT(rep.max_path_error_mm, 1e-9);
  // Resultant: on the ramps tangential 1000 and normal up to 250 add up to ≤ √(1000² + 250²).
  EXPECT_LE(rep.max_resultant_accel_mm_s2, std::hypot(1000.0, 250.0) + 1);

  // Amax = 200: the arc limit √(R·Amax) = 44.7 mm/s is exceeded, and so is the normal limit;
  // the ramps (1000 mm/s²) also break the tangential limit.
  Limits low;
  low.max_accel_mm_s2 = 200;
  const auto bad = check_trajectory(tr, blocks, low);
  EXPECT_GT(bad.count(Property::kSpeed), 0u);
  EXPECT_GT(bad.count(Property::kNormalAccel), 0u);
  for (const auto& v : bad.violations) {
    if (v.property == Property::kSpeed) {
      EXPECT_NEAR(v.limit, std::sqrt(2000.0), 1e-9);
    }
  }
  EXPECT_EQ(bad.count(Property::kPath), 0u);
}

TEST(TrajectoryChecker, CornerCutIsAPathViolationOfTheRightSize) {
  // X0→X10 then Y0→Y10. The trajectory leaves the path at (9.9, 0) and rejoins it at (10, 0.1):
  // the chord's largest distance to the path (to both lines, at its middle) is 0.05 mm.
  const std::vector<Block> blocks = {line(P(0, 0), P(10, 0), 600, 1),
                                     line(P(10, 0), P(10, 10), 600, 2)};
  Trajectory tr;
  const double v = 1.0;  // mm/s, slow enough for every other limit
  double t = 0;
  auto go = [&](AxisVec a, AxisVec b, std::uint32_t ln) {
    const double len = std::sqrt(std::pow(b[kX] - a[kX], 2) + std::pow(b[kY] - a[kY], 2));
    const int n = static_cast<int>(std::round(len / (v * kTau)));
    for (int k = 1; k <= n; ++k) {
      t += kTau;
      tr.add(t, ln, a + (static_cast<double>(k) / n) * (b - a), 600);
    }
  };
  tr.add(0, 1, P(0, 0), 600);
  go(P(0, 0), P(9.9, 0), 1);
  go(P(9.9, 0), P(10, 0.1), 2);
  go(P(10, 0.1), P(10, 10), 2);
  const auto rep = check_trajectory(tr, blocks, Limits{});
  EXPECT_NEAR(rep.max_path_error_mm, 0.05, 1e-3);
  // Samples farther than 1 µm (+0.5 %) from the path: on the chord, distance grows linearly
  // from both ends: min(x, 0.1 − x)·√2/2 ... counted by brute force over the two lines.
  std::size_t expected = 0;
  for (std::size_t k = 0; k < tr.size(); ++k) {
    const double x = tr.pos[k][kX], y = tr.pos[k][kY];
    const double d1 = (x <= 10) ? std::abs(y) : std::hypot(x - 10, y);
    const double d2 = (y >= 0) ? std::abs(x - 10) : std::hypot(x - 10, y);
    if (std::min(d1, d2) > 0.001 * 1.005 + 1e-9) ++expected;
  }
  EXPECT_GT(expected, 100u);
  EXPECT_EQ(rep.count(Property::kPath), expected) << rep.summary();
  EXPECT_EQ(rep.count(Property::kSpeed), 0u);
  EXPECT_EQ(rep.count(Property::kTangentialAccel), 0u) << rep.summary();
}

TEST(TrajectoryChecker, CornerPassedTooFastBreaksJointSpeedAndNormalAcceleration) {
  // 90° corner: Vg = Amax·τ/(2 sin 45°) = 1.414 mm/s. Passing it at 10 mm/s changes the
  // velocity by 10·√2 mm/s within a cycle or two.
  const std::vector<Block> blocks = {line(P(0, 0), P(1, 0), 600, 1),
                                     line(P(1, 0), P(1, 1), 600, 2)};
  const Path path = build_path(blocks);
  // Constant-speed ramps at 1000 mm/s², top speed 10 mm/s, through the corner without slowing.
  const auto tr = follow(path, trapezoid(2, 10, 1000));
  const auto rep = check_trajectory(tr, blocks, Limits{});
  ASSERT_EQ(rep.joints.size(), 2u);
  EXPECT_NEAR(rep.joints[0].angle_deg, 90, 1e-9);
  EXPECT_NEAR(rep.joints[0].vg_mm_s, 2.0 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(rep.joints[0].speed_mm_s, 10, 1e-6);
  EXPECT_EQ(rep.count(Property::kJointSpeed), 1u);
  EXPECT_GE(rep.count(Property::kNormalAccel), 1u);
  EXPECT_EQ(rep.count(Property::kTangentialAccel), 0u) << rep.summary();
  EXPECT_EQ(rep.count(Property::kPath), 0u);
  EXPECT_LT(rep.max_path_error_mm, 1e-12);

  // The same at 1.4 mm/s passes.
  const auto slow = follow(path, trapezoid(2, 1.4, 1000));
  const auto ok = check_trajectory(slow, blocks, Limits{});
  EXPECT_TRUE(ok.ok()) << ok.summary();
  EXPECT_LE(ok.max_normal_accel_mm_s2, 2000 * 1.005);
}

TEST(TrajectoryChecker, OverrideDecreaseGetsOneRampOfAllowanceAndNoMore) {
  // F6000 (100 mm/s) line; override 100 % then 50 % from t = 0.5 s.
  const std::vector<Block> blocks = {line(P(0, 0), P(200, 0), 6000)};
  Limits lim;  // ramp = 250/2000 + 0.002 = 0.127 s
  ASSERT_NEAR(lim.ramp_s(), 0.127, 1e-12);
  auto run = [&](double slow_down_at) {
    // accelerate at 1000 to 100 mm/s, cruise, at slow_down_at decelerate at 1000 to 50 mm/s,
    // cruise, decelerate to rest at the end (position clamped to the end point).
    std::vector<double> s{0};
    std::vector<double> ov{100};
    double v = 0, x = 0, t = 0;
    while (x < 200) {
      t += kTau;
      const double target = t > slow_down_at ? 50 : 100;
      const double stop_v = std::sqrt(2 * 1000 * std::max(0.0, 200 - x));
      const double want = std::min(target, stop_v);
      v = want > v ? std::min(want, v + 1000 * kTau) : std::max(want, v - 1000 * kTau);
      if (v < 1e-9 && 200 - x < 1e-6) break;
      x = std::min(200.0, x + std::max(v, 1e-3) * kTau);
      s.push_back(x);
      ov.push_back(s.size() > 500 ? 50 : 100);  // sample 500 (t = 0.5 s) is the first at 50 %
    }
    Trajectory tr;
    for (std::size_t k = 0; k < s.size(); ++k) {
      AxisVec p = P(s[k], 0);
      tr.add(static_cast<double>(k) * kTau, 1, p, 6000, ov[k]);
    }
    return tr;
  };
  const auto good = check_trajectory(run(0.5), blocks, lim);
  EXPECT_EQ(good.count(Property::kSpeed), 0u) << good.summary();
  // Staying at 100 mm/s for 0.2 s after the step: the samples from 0.5 + 0.127 s on (their
  // window holds only 50 % samples) that are still faster than 50·1.005 are violations.
  const auto late_tr = run(0.7);
  const auto late = check_trajectory(late_tr, blocks, lim);
  std::size_t expected = 0;
  for (std::size_t k = 1; k < late_tr.size(); ++k) {
    const double vk = (late_tr.pos[k][kX] - late_tr.pos[k - 1][kX]) / kTau;
    if (k >= 627 && vk > 50 * 1.005 + 1e-6) ++expected;
  }
  EXPECT_GT(expected, 70u);
  EXPECT_EQ(late.count(Property::kSpeed), expected) << late.summary();
}

TEST(TrajectoryChecker, FeedDropBetweenBlocksGetsNoAllowance) {
  // F6000 then F3000 on the same line: entering block 2 at 100 mm/s is a violation right away.
  const std::vector<Block> blocks = {line(P(0, 0), P(50, 0), 6000, 1),
                                     line(P(50, 0), P(100, 0), 3000, 2)};
  const auto tr = follow(build_path(blocks), trapezoid(100, 100, 1000));
  const auto rep = check_trajectory(tr, blocks, Limits{});
  ASSERT_GT(rep.count(Property::kSpeed), 0u);
  // The first violation is the first sample inside block 2.
  const auto& v0 = rep.violations.front();
  EXPECT_EQ(v0.property, Property::kSpeed);
  EXPECT_EQ(v0.line, 2u);
  EXPECT_NEAR(tr.pos[v0.index][kX], 50, 0.1 + 1e-9);
  EXPECT_NEAR(v0.limit, 50, 1e-12);
}

TEST(TrajectoryChecker, ExactStopMustBeReachedAtRest) {
  std::vector<Block> blocks = {line(P(0, 0), P(10, 0), 6000, 1), line(P(10, 0), P(20, 0), 6000, 2)};
  blocks[0].path_mode = PathMode::kExactStop;
  const Path path = build_path(blocks);
  ASSERT_TRUE(path.segments[0].stop_after);
  // Passing the stop at speed: a stop-point violation (no sample lands on it) or a speed one.
  const auto fly = follow(path, trapezoid(20, 50, 1000));
  const auto rep = check_trajectory(fly, blocks, Limits{});
  EXPECT_EQ(rep.count(Property::kStopPoint) + rep.count(Property::kEndSpeed), 1u) << rep.summary();
  // Two trapezoids, one per block: fine.
  auto s = trapezoid(10, 50, 1000);
  for (double x : trapezoid(10, 50, 1000)) s.push_back(10 + x);
  const auto stop = follow(path, s);
  const auto ok = check_trajectory(stop, blocks, Limits{});
  EXPECT_TRUE(ok.ok()) << ok.summary();
  // A dwell of 0.1 s after block 1 that the trajectory does not wait for.
  Block dw;
  dw.kind = BlockKind::kDwell;
  dw.dwell_s = 0.1;
  dw.line = 3;
  blocks[0].path_mode = PathMode::kBlend;
  blocks.insert(blocks.begin() + 1, dw);
  const auto no_wait = check_trajectory(stop, blocks, Limits{});
  EXPECT_EQ(no_wait.count(Property::kStopPoint), 1u) << no_wait.summary();
  std::vector<double> s2 = trapezoid(10, 50, 1000);
  for (int k = 0; k < 100; ++k) s2.push_back(10);
  for (double x : trapezoid(10, 50, 1000)) s2.push_back(10 + x);
  const auto waited = check_trajectory(follow(path, s2), blocks, Limits{});
  EXPECT_TRUE(waited.ok()) << waited.summary();
}

// An arc with two extra turns (G2 … P3) and an exact stop passes its end point twice before
// it stops there: those passes at speed are not the stop.
TEST(TrajectoryChecker, MultiTurnArcPassesItsStopPointBeforeStoppingThere) {
  // R such that a sample of the trapezoid below (50 mm/s, 1000 mm/s²: cruise samples at
  // 1.25 + 0.05·m mm) lands on the end point as the tool passes it after 1.25 turns.
  const double r = (1.25 + 0.05 * 1546) / (2.5 * std::numbers::pi);
  Block arc;
  arc.kind = BlockKind::kArc;
  arc.start = P(r, 0);
  arc.end = P(0, r);
  arc.center = {0, 0, 0};
  arc.normal = {0, 0, 1};
  arc.turns = 2;
  arc.feed_mm_min = 3000;
  arc.line = 1;
  arc.path_mode = PathMode::kExactStop;
  const std::vector<Block> blocks = {arc, line(P(0, r), P(0, r + 10), 3000, 2)};
  const Path path = build_path(blocks);
  const double l0 = path.segments[0].length_mm;
  ASSERT_NEAR(l0, 2.25 * 2 * std::numbers::pi * r, 1e-9);
  auto s = trapezoid(l0, 50, 1000);
  ASSERT_GT(s.size(), 1600u);
  const AxisVec at = path.segments[0].point_at(s[1596] / l0);
  EXPECT_LT(std::hypot(at[kX] - arc.end[kX], at[kY] - arc.end[kY]), 1e-9);
  for (double x : trapezoid(10, 50, 1000)) s.push_back(l0 + x);
  const auto rep = check_trajectory(follow(path, s), blocks, Limits{});
  EXPECT_TRUE(rep.ok()) << rep.summary();
  ASSERT_FALSE(rep.joints.empty());
  EXPECT_LE(rep.joints.front().speed_mm_s, 1000 * kTau + 1e-9);
}

TEST(TrajectoryChecker, EndPointAndEndSpeed) {
  const std::vector<Block> blocks = {line(P(0, 0), P(10, 0), 6000)};
  auto s = trapezoid(10, 50, 1000);
  s.back() = 10 - 1e-6;  // stops 1 µm short
  const auto rep = check_trajectory(follow(build_path(blocks), s), blocks, Limits{});
  EXPECT_EQ(rep.count(Property::kEndPoint), 1u) << rep.summary();
  EXPECT_NEAR(rep.end_error_mm, 1e-6, 1e-12);
  // Ends at full speed: the arriving speed is far above Amax·τ = 2 mm/s.
  std::vector<double> abrupt;
  for (int k = 0; k <= 200; ++k) abrupt.push_back(k * 0.05);
  const auto rep2 = check_trajectory(follow(build_path(blocks), abrupt), blocks, Limits{});
  EXPECT_EQ(rep2.count(Property::kEndSpeed), 1u) << rep2.summary();
  EXPECT_EQ(rep2.count(Property::kEndPoint), 0u);
}

TEST(TrajectoryChecker, JerkIsMeasuredOnTheTangentialProfile) {
  // s(t) = j·t³/6 → third difference of s is exactly j·τ³.
  const std::vector<Block> blocks = {line(P(0, 0), P(1000, 0), 10000)};
  Trajectory tr;
  const double j = 50000;
  for (int k = 0; k <= 50; ++k) {
    const double t = k * kTau;
    tr.add(t, 1, P(j * t * t * t / 6, 0), 10000);
  }
  Limits lim;
  lim.max_jerk_mm_s3 = 40000;
  const auto rep = check_trajectory(tr, blocks, lim);
  EXPECT_NEAR(rep.max_tangential_jerk_mm_s3, j, 1e-3 * j);
  // Jerk needs four samples: k−1 … k+2, so samples 1..48 of a 51-sample run.
  EXPECT_EQ(rep.count(Property::kJerk), 48u);
}

// A corner rounded by a filter at constant speed: the samples on the fillet are off the path,
// where the speed is the chord's and the projection no longer follows the tool, so the
// tangential acceleration computed across the fillet jumps although the speed does not change.
// Windows that turn a corner are not charged jerk; the same jerk on a straight stretch is.
TEST(TrajectoryChecker, JerkIsNotChargedForTheTurnAtACorner) {
  const std::vector<Block> blocks = {line(P(0, 0), P(10, 0), 6000),
                                     line(P(10, 0), P(10, 10), 6000)};
  auto rounded = [](double bump_at_mm) {
    // 0.1 mm per cycle: along X to 9.5, a quarter circle of R 0.5 about (9.5, 0.5), along Y.
    Trajectory tr;
    std::vector<AxisVec> pts;
    for (int k = 0; k <= 95; ++k) pts.push_back(P(0.1 * k, 0));
    const double step = 0.1 / 0.5;  // rad per cycle
    for (double a = step; a < std::numbers::pi / 2; a += step) {
      pts.push_back(P(9.5 + 0.5 * std::sin(a), 0.5 - 0.5 * std::cos(a)));
    }
    for (int k = 0; k <= 95; ++k) pts.push_back(P(10, 0.5 + 0.1 * k));
    double extra = 0;
    for (std::size_t k = 0; k < pts.size(); ++k) {
      AxisVec p = pts[k];
      if (p[1] > bump_at_mm) {
        extra += 0.0001;  // a speed step of 0.1 mm/s per cycle from there on
        p[1] += extra;
      }
      tr.add(static_cast<double>(k) * kTau, 1, p, 6000);
    }
    return tr;
  };
  Limits lim;
  lim.max_jerk_mm_s3 = 1000;
  lim.max_accel_mm_s2 = 1e6;  // the start, the end and the turn are not what this test checks
  lim.max_feed_mm_min = 1e5;
  lim.path_tolerance_mm = 0.3;
  const auto corner = check_trajectory(rounded(100), blocks, lim);
  // Only the start and the end change the speed along the path.
  for (const auto& v : corner.violations) {
    if (v.property == Property::kJerk) {
      EXPECT_TRUE(v.index < 3u || v.index + 4 > corner.speed_mm_s.size()) << corner.summary();
    }
  }
  // A speed ramp starting on the straight part along Y (at 5 mm) is charged.
  const auto straight = check_trajectory(rounded(5), blocks, lim);
  EXPECT_GT(straight.count(Property::kJerk), corner.count(Property::kJerk)) << straight.summary();
}

TEST(TrajectoryChecker, PerAxisLimits) {
  // A 45° line at 100 mm/s: each axis moves at 70.7 mm/s; the ramp at 1000 mm/s² gives 707
  // per axis. Y limited to 60 mm/s and 600 mm/s².
  const std::vector<Block> blocks = {line(P(0, 0), P(50, 50), 6000)};
  const auto tr = follow(build_path(blocks), trapezoid(std::sqrt(5000.0), 100, 1000));
  Limits lim;
  lim.axis_speed_mm_min[kY] = 3600;
  lim.axis_accel_mm_s2[kY] = 600;
  const auto rep = check_trajectory(tr, blocks, lim);
  EXPECT_NEAR(rep.max_axis_speed_mm_s[kY], 100 / std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(rep.max_axis_accel_mm_s2[kY], 1000 / std::sqrt(2.0), 1e-3);
  EXPECT_GT(rep.count(Property::kAxisSpeed), 0u);
  EXPECT_GT(rep.count(Property::kAxisAccel), 0u);
  for (const auto& v : rep.violations) {
    if (v.property == Property::kAxisSpeed || v.property == Property::kAxisAccel) {
      EXPECT_EQ(v.axis, static_cast<int>(kY));
    }
  }
  EXPECT_EQ(rep.count(Property::kSpeed), 0u);
}

TEST(TrajectoryChecker, RetracedPathKeepsProgressMonotone) {
  // Out and back along the same line, with a stop at the reversal: on the way back the samples
  // are on both segments; the checker must follow the second one (no negative speed, no fake
  // acceleration).
  std::vector<Block> blocks = {line(P(0, 0), P(10, 0), 6000, 1), line(P(10, 0), P(0, 0), 6000, 2)};
  const Path path = build_path(blocks);
  ASSERT_TRUE(path.segments[0].stop_after == false);
  blocks[0].path_mode = PathMode::kExactStop;
  auto s = trapezoid(10, 50, 1000);
  s.push_back(10);  // one cycle at rest at the reversal
  for (double x : trapezoid(10, 50, 1000)) s.push_back(10 + x);
  const auto tr = follow(build_path(blocks), s);
  const auto rep = check_trajectory(tr, blocks, Limits{});
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_NEAR(rep.max_tangential_accel_mm_s2, 1000, 1e-3);
}

TEST(TrajectoryChecker, ReversalPassedAtVIsMeasuredAtVNotTwice) {
  // Up Z and straight back down, passed at Vg = 1 mm/s (Amax·τ/2 for a 180° turn, 1 µm per
  // cycle): the cycle through the fold goes 0.5 µm up and 0.5 µm down, so its end sample is at
  // the same height as the sample before it and lies on both segments. Read on the first one,
  // the next cycle would seem to cover 2 µm (the fake 2·Vg once reported on stress_test.gcode
  // and genes-encoder.ngc).
  const std::vector<Block> blocks = {line(P(0, 0, 0), P(0, 0, 1), 60, 1),
                                     line(P(0, 0, 1), P(0, 0, 0), 60, 2)};
  const Path path = build_path(blocks);
  std::vector<double> s;
  for (int k = 0; k <= 2000; ++k) s.push_back(0.0005 + 0.001 * k);  // 1 µm/cycle, fold mid-cycle
  s.back() = 2;
  Trajectory tr = follow(path, s);
  const auto rep = check_trajectory(tr, blocks, Limits{});
  EXPECT_EQ(rep.count(Property::kJointSpeed), 0u) << rep.summary();
  EXPECT_EQ(rep.count(Property::kSpeed), 0u) << rep.summary();
  EXPECT_NEAR(rep.max_speed_mm_s, 1.0, 1e-6) << rep.summary();

  // The same reversal passed at 4 mm/s is still a violation, whichever reading is taken.
  std::vector<double> fast;
  for (int k = 0; k <= 500; ++k) fast.push_back(0.002 + 0.004 * k);
  fast.back() = 2;
  const auto rep_fast = check_trajectory(follow(path, fast), blocks, Limits{});
  EXPECT_GT(rep_fast.count(Property::kJointSpeed), 0u) << rep_fast.summary();
}

// Up Z to 1 and back to 0 in steps of v, the set-points turning `short_mm` before the fold; with
// `ramp` they slow by v/4 per cycle to the turn and rise again the same way, else they reverse
// at once.
Trajectory turned_short(double v_mm, double short_mm, bool ramp) {
  const std::vector<double> fractions =
      ramp ? std::vector<double>{0.75, 0.5, 0.25} : std::vector<double>{};
  double ramp_mm = 0;
  for (const double f : fractions) ramp_mm += f * v_mm;
  std::vector<double> z{0};
  while (z.back() + v_mm <= 1 - short_mm - ramp_mm + 1e-12) z.push_back(z.back() + v_mm);
  for (const double f : fractions) z.push_back(z.back() + f * v_mm);
  for (const double f : std::views::reverse(fractions)) z.push_back(z.back() - f * v_mm);
  while (z.back() - v_mm > 1e-12) z.push_back(z.back() - v_mm);
  z.push_back(0);
  Trajectory tr;
  for (std::size_t k = 0; k < z.size(); ++k)
    tr.add(static_cast<double>(k) * kTau, 1, P(0, 0, z[k]));
  return tr;
}

TEST(TrajectoryChecker, FilteredReversalTurnedShortOfItsTipIsMeasuredByItsChords) {
  // The post filter averages the set-points, so at a reversal they turn before the tip (stress_test
  // lines 203-204: at X 0.998 of a fold at 1.000), on the path but past none of it. Their progress
  // along the path jumps over the tip (2·2 µm in one cycle, once reported as 4 mm/s on a 1 mm/s
  // joint and 3 750 mm/s² tangential); what the servos follow is the chord.
  const std::vector<Block> blocks = {line(P(0, 0, 0), P(0, 0, 1), 60, 1),
                                     line(P(0, 0, 1), P(0, 0, 0), 60, 2)};
  Limits filtered;
  filtered.post_filter_s = 0.008;
  filtered.path_tolerance_mm = 0.01;  // the contour tolerance
  const auto rep = check_trajectory(turned_short(0.001, 0.0025, true), blocks, filtered);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_NEAR(rep.max_speed_mm_s, 1.0, 1e-6) << rep.summary();

  // Unfiltered, the same set-points skip 2.5 µm of the path at the fold: charged.
  EXPECT_FALSE(check_trajectory(turned_short(0.001, 0.0025, true), blocks, Limits{}).ok());
  // Filtered, reversing at once at 4 mm/s on the 1 mm/s fold is still charged: the crossing
  // step's chord and the turn's 8 µm per cycle².
  const auto fast = check_trajectory(turned_short(0.004, 0.0025, false), blocks, filtered);
  EXPECT_GT(fast.count(Property::kJointSpeed), 0u) << fast.summary();
  EXPECT_GT(fast.count(Property::kNormalAccel), 0u) << fast.summary();
}

TEST(TrajectoryChecker, ArrivalAtASlowBlockIsChargedToTheBlockItCameBy) {
  // G0 to an exact stop at X10, then G1 F5: the last cycle of the G0 lands on the G1's start at
  // 0.5 mm/s (Amax·τ/2 with 1000 mm/s²). That cycle moved on the G0; once on the G1 the speed
  // must be ≤ 5 mm/min. (slant_test.nc in stop mode was once charged F5 for that cycle.)
  std::vector<Block> blocks = {line(P(0, 0), P(10, 0), 0, 1), line(P(10, 0), P(11, 0), 5, 2)};
  blocks[0].kind = BlockKind::kRapid;
  blocks[0].path_mode = PathMode::kExactStop;
  const Path path = build_path(blocks);
  // The landing sample is 0.1 nm past the joint (rounding): nearer to the G1 than to the G0.
  std::vector<double> s = trapezoid(10, 50, 1000);
  s.back() = 10 + 1e-10;
  s.push_back(10 + 1e-10);
  for (int k = 1; k <= 100; ++k) s.push_back(10 + 1e-10 + k * 5.0 / 60 * kTau);
  const auto rep = check_trajectory(follow(path, s), path, Limits{});
  EXPECT_EQ(rep.count(Property::kSpeed), 0u) << rep.summary();
  // One step too fast on the G1 is still found.
  s.push_back(s.back() + 2 * 5.0 / 60 * kTau);
  const auto rep_fast = check_trajectory(follow(path, s), path, Limits{});
  EXPECT_EQ(rep_fast.count(Property::kSpeed), 1u) << rep_fast.summary();
}

TEST(TrajectoryChecker, HairpinLegWithinTheRoundingIsNotTakenForTheCurrentSegment) {
  // A → B is a hairpin (B goes back 0.4 µm along A, 10 µm to the side), C carries on backwards. One
  // cycle goes from A (x = 0.99962) over A's end and all of B onto C, landing 41 µm from A's part
  // ahead of the previous sample. With CSV rounding (q = 5e-7) the projection once accepted A there
  // (distance 4.1e-5 ≤ its old snap of 100q) and made up a path error and a joint-speed violation
  // (seen on camotics/vcarve.ngc).
  const std::vector<Block> blocks = {line(P(0, 0), P(1, 0), 600, 1),
                                     line(P(1, 0), P(0.9996, 1e-5), 600, 2),
                                     line(P(0.9996, 1e-5), P(0.5, 2e-5), 600, 3)};
  const Path path = build_path(blocks);
  std::vector<double> s;
  for (double x = 0.00042; x < path.length_mm; x += 0.0008) s.push_back(x);
  s.push_back(path.length_mm);
  Trajectory tr = follow(path, s);
  tr.position_resolution_mm = 5e-7;
  const auto rep = check_trajectory(tr, path, Limits{});
  EXPECT_LT(rep.max_path_error_mm, 1e-9) << rep.summary();
  // 0.8 mm/s is below the hairpin's Vg = Amax·τ/(2 sin(θ/2)) ≈ 1.0 mm/s: nothing to report.
  EXPECT_EQ(rep.count(Property::kJointSpeed), 0u) << rep.summary();
  EXPECT_EQ(rep.count(Property::kTangentialAccel), 0u) << rep.summary();
}

TEST(TrajectoryCsv, ReadsColumnsByNameInAnyOrder) {
  const std::string file = ::testing::TempDir() + "traj_test.csv";
  {
    std::ofstream o(file);
    o << "line,feed,z,t,extra,x,y,override\n";
    o << "0,0,1.5,0,abc,0,0,100\n";
    o << "7,6000,1.5,0.001,,0.1,-0.2,80\n";
    o << "7,6000,1.5,0.002,q,0.2,-0.4,\n";
  }
  const auto tr = load_trajectory_csv(file);
  ASSERT_EQ(tr.size(), 3u);
  EXPECT_NEAR(tr.period_s, 0.001, 1e-15);
  EXPECT_EQ(tr.line[1], 7u);
  EXPECT_EQ(tr.pos[2][kX], 0.2);
  EXPECT_EQ(tr.pos[2][kY], -0.4);
  EXPECT_EQ(tr.pos[2][kZ], 1.5);
  EXPECT_EQ(tr.feed_mm_min[1], 6000);
  EXPECT_EQ(tr.override_pct[1], 80);
  EXPECT_EQ(tr.override_pct[2], 100);  // empty → default
  std::remove(file.c_str());
}

TEST(TrajectoryCsv, MissingColumnOrBadNumberIsAnError) {
  const std::string file = ::testing::TempDir() + "traj_bad.csv";
  {
    std::ofstream o(file);
    o << "t,x,y\n0,0,0\n";
  }
  EXPECT_THROW(load_trajectory_csv(file), std::runtime_error);
  {
    std::ofstream o(file);
    o << "t,line,x\n0,0,0\n0.001,1,zz\n";
  }
  try {
    load_trajectory_csv(file);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":3:"), std::string::npos) << e.what();
  }
  std::remove(file.c_str());
  EXPECT_THROW(load_trajectory_csv(file), std::runtime_error);
}

}  // namespace
}  // namespace cncore::testing

// ---- Property: no false alarms on random geometry ----
#include <rapidcheck/gtest.h>

#include "program_gen_rc.hpp"

namespace cncore::testing {
namespace {

// A trajectory that stops at every block end with a trapezoid at Amax/2 and a speed below every
// limit, dwelling where the program dwells: it breaks no property, whatever the geometry
// (helices, reversals, segments far shorter than a cycle's travel).
RC_GTEST_PROP(TrajectoryCheckerProperty, StopEveryBlockProfileIsClean, ()) {
  gen::BlockGenOptions opt;
  opt.min_feed_mm_min = 600;
  const auto bl = *gen::blocks(opt);
  const Path path = build_path(bl);
  RC_PRE(!path.empty());
  const Limits lim;
  Trajectory tr;
  double t = 0;
  tr.add(0, path.segments[0].line, path.segments[0].start, 0);
  for (const auto& sg : path.segments) {
    double v = sg.rapid ? lim.rapid_mm_s() : std::min(sg.feed_mm_min / 60, lim.feed_mm_s());
    if (sg.arc) v = std::min(v, 0.99 * std::sqrt(sg.radius_mm() * lim.max_accel_mm_s2));
    const auto s = trapezoid(sg.length_mm, v, lim.max_accel_mm_s2 / 2);
    for (std::size_t k = 1; k < s.size(); ++k) {
      t += kTau;
      tr.add(t, sg.line, sg.point_at(s[k] / sg.length_mm), sg.feed_mm_min);
    }
    for (double w = 0; w < sg.dwell_after_s; w += kTau) {
      t += kTau;
      tr.add(t, sg.line, sg.end, 0);
    }
  }
  const auto rep = check_trajectory(tr, path, lim);
  if (!rep.ok()) RC_FAIL(rep.summary());
}

}  // namespace
}  // namespace cncore::testing
