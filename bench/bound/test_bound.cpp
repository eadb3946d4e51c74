// The time-optimal bound on cases with closed-form answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "bound.hpp"
#include "trajectory.hpp"
#include "trajectory_checker.hpp"

namespace cncore::bound {
namespace {

AxisVec P(double x, double y, double z = 0) {
  AxisVec p;
  p[kX] = x;
  p[kY] = y;
  p[kZ] = z;
  return p;
}
Block line(AxisVec a, AxisVec b, double feed) {
  Block bl;
  bl.kind = BlockKind::kLine;
  bl.start = a;
  bl.end = b;
  bl.feed_mm_min = feed;
  return bl;
}

constexpr double kA = 2000;  // default Amax

TEST(Bound, SingleLineTrapezoid) {
  // 100 mm at 100 mm/s: 0.05 s up (2.5 mm), 95 mm cruise (0.95 s), 0.05 s down.
  EXPECT_NEAR(optimal_time_s({line(P(0, 0), P(100, 0), 6000)}, {}), 1.05, 1e-12);
}

TEST(Bound, ShortLineTriangle) {
  // 1 mm: never reaches 100 mm/s; half the way accelerating: t = 2·√(L/A).
  EXPECT_NEAR(optimal_time_s({line(P(0, 0), P(1, 0), 6000)}, {}), 2 * std::sqrt(1.0 / kA), 1e-12);
}

TEST(Bound, FeedAboveTheMachineLimitIsClipped) {
  // F20000 on a 10 000 mm/min machine: 166.67 mm/s. 100 mm: v/A + L/v.
  const double v = 10000.0 / 60;
  EXPECT_NEAR(optimal_time_s({line(P(0, 0), P(100, 0), 20000)}, {}), v / kA + 100 / v, 1e-12);
}

TEST(Bound, CornerSpeed) {
  // Two 100 mm lines at 90°: corner at Vg = A·τ/(2 sin 45°) = 1.41421 mm/s.
  const double v = 100, vg = kA * 0.001 / (2 * std::sin(std::numbers::pi / 4));
  const double one =
      v / kA + (v - vg) / kA + (100 - v * v / (2 * kA) - (v * v - vg * vg) / (2 * kA)) / v;
  const double t =
      optimal_time_s({line(P(0, 0), P(100, 0), 6000), line(P(100, 0), P(100, 100), 6000)}, {});
  EXPECT_NEAR(t, 2 * one, 1e-12);
  // Collinear: one trapezoid over 200 mm.
  EXPECT_NEAR(
      optimal_time_s({line(P(0, 0), P(100, 0), 6000), line(P(100, 0), P(200, 0), 6000)}, {}), 2.05,
      1e-12);
}

TEST(Bound, ExactStopAndDwell) {
  std::vector<Block> b = {line(P(0, 0), P(100, 0), 6000), line(P(100, 0), P(200, 0), 6000)};
  b[0].path_mode = PathMode::kExactStop;
  EXPECT_NEAR(optimal_time_s(b, {}), 2 * 1.05, 1e-12);
  b[0].path_mode = PathMode::kBlend;
  Block dw;
  dw.kind = BlockKind::kDwell;
  dw.dwell_s = 0.5;
  b.insert(b.begin() + 1, dw);
  const auto r = optimal_profile(b, {});
  EXPECT_NEAR(r.time_s, 2 * 1.05 + 0.5, 1e-12);
  EXPECT_EQ(r.stops, 2u);
}

TEST(Bound, CircleAtTheArcLimit) {
  auto circle = [](double r, double feed) {
    Block a;
    a.kind = BlockKind::kArc;
    a.start = P(r, 0);
    a.end = P(r, 0);
    a.center = {0, 0, 0};
    a.normal = {0, 0, 1};
    a.feed_mm_min = feed;
    return a;
  };
  // R = 10: √(R·A) = 141 > 100: the feed decides. Full speed time L/v plus v/A for the ramps.
  const double l10 = 2 * std::numbers::pi * 10;
  EXPECT_NEAR(optimal_time_s({circle(10, 6000)}, {}), l10 / 100 + 100 / kA, 1e-12);
  // R = 1: the arc limit √(1·2000) = 44.72 mm/s decides.
  const double v1 = std::sqrt(kA), l1 = 2 * std::numbers::pi;
  EXPECT_NEAR(optimal_time_s({circle(1, 6000)}, {}), l1 / v1 + v1 / kA, 1e-12);
}

TEST(Bound, PerAxisSpeedByDirectionAndRapids) {
  testing::Limits lim;
  lim.axis_speed_mm_min[kY] = 3600;  // 60 mm/s
  // 45° line: Y moves at v/√2 ≤ 60 → v ≤ 84.85 mm/s. Length 100√2.
  const double v = 60 * std::sqrt(2.0), l = 100 * std::sqrt(2.0);
  EXPECT_NEAR(optimal_time_s({line(P(0, 0), P(100, 100), 6000)}, lim), v / kA + l / v, 1e-12);
  // A rapid at 15 000 mm/min = 250 mm/s, 300 mm.
  Block g0 = line(P(0, 0), P(300, 0), 0);
  g0.kind = BlockKind::kRapid;
  EXPECT_NEAR(optimal_time_s({g0}, {}), 250 / kA + 300 / 250.0, 1e-12);
}

TEST(Bound, BrakingForASlowBlockAhead) {
  // 100 mm at 100 mm/s, then 1 mm at F60 (1 mm/s): the first block brakes to 1 mm/s at its end.
  const double a = kA;
  const double t1 = 100 / a + (100 - 1) / a + (100 - 1e4 / (2 * a) - (1e4 - 1) / (2 * a)) / 100;
  // Second block: 1 mm entered at 1 mm/s, cruise (1 − 1/(2a)) mm, then 1/a s of braking.
  const double t2_exact = (1 - 1 / (2 * a)) / 1 + 1 / a;
  EXPECT_NEAR(optimal_time_s({line(P(0, 0), P(100, 0), 6000), line(P(100, 0), P(101, 0), 60)}, {}),
              t1 + t2_exact, 1e-12);
}

TEST(BoundCoupled, LineAcceleratesAtTheAxisShare) {
  // 45° line, X and Y limited to 1000 mm/s²: each axis gets a_t/√2, so a_t ≤ 1000·√2.
  testing::Limits lim;
  lim.axis_accel_mm_s2[kX] = lim.axis_accel_mm_s2[kY] = 1000;
  Block b;
  b.kind = BlockKind::kLine;
  b.start = P(0, 0);
  b.end = P(100, 100);
  b.feed_mm_min = 6000;
  const double a = 1000 * std::sqrt(2.0), l = 100 * std::sqrt(2.0), v = 100;
  EXPECT_NEAR(optimal_time_s({b}, lim), v / a + l / v, 1e-12);
  // The simple model uses Amax = 2000 along the line.
  EXPECT_NEAR(optimal_time_s({b}, lim, Model::kSimple), v / 2000 + l / v, 1e-12);
}

// The exact optimum on a planar arc with the checker's limits (|a_t| ≤ A, v ≤ √(R·A), per-axis
// |a_t·T_i + v²/R·N_i| ≤ A_i), by forward and backward integration of d(v²)/ds = ±2·a_t,max at
// every point with a fine step (1e-4 rad), then t = ∫ds/v. Independent of the bound's pieces.
double exact_arc_time(double r, double sweep, double vcap, double amax, double ai) {
  const std::size_t n = 200000;
  const double dphi = sweep / n, ds = r * dphi;
  // Start at (r, 0) going counter-clockwise: T = (−sin φ, cos φ), N = (−cos φ, −sin φ).
  auto hi = [&](double phi, double v, bool brake) {
    const double an = v * v / r;
    const double t[2] = {-std::sin(phi), std::cos(phi)}, nn[2] = {-std::cos(phi), -std::sin(phi)};
    double a = amax;
    for (int i = 0; i < 2; ++i) {
      if (std::abs(t[i]) < 1e-15) continue;
      // a_t·t + an·n ∈ [−ai, ai]: accelerating a_t ≤ (ai − an·n·sgn t)/|t| ... (both signs).
      const double s = t[i] > 0 ? 1 : -1;
      const double up = (ai - an * nn[i] * s) / std::abs(t[i]);   // a_t ≤ up
      const double dn = (-ai - an * nn[i] * s) / std::abs(t[i]);  // a_t ≥ dn
      a = std::min(a, brake ? -dn : up);
    }
    return std::max(a, 0.0);
  };
  std::vector<double> f(n + 1), b(n + 1);
  f[0] = 0;
  for (std::size_t k = 0; k < n; ++k) {
    // Midpoint step on w = v² (the exact solution to ~1e-8 relative at this step size).
    const double phi = dphi * (static_cast<double>(k) + 0.5);
    const double w1 = f[k] * f[k] + hi(phi, f[k], false) * ds;
    const double vm = std::min(vcap, std::sqrt(w1));
    f[k + 1] = std::min(vcap, std::sqrt(f[k] * f[k] + 2 * hi(phi, vm, false) * ds));
  }
  b[n] = 0;
  for (std::size_t k = n; k-- > 0;) {
    const double phi = dphi * (static_cast<double>(k) + 0.5);
    const double w1 = b[k + 1] * b[k + 1] + hi(phi, b[k + 1], true) * ds;
    const double vm = std::min(vcap, std::sqrt(w1));
    b[k] = std::min(vcap, std::sqrt(b[k + 1] * b[k + 1] + 2 * hi(phi, vm, true) * ds));
  }
  double t = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double v0 = std::min(f[k], b[k]), v1 = std::min(f[k + 1], b[k + 1]);
    t += 2 * ds / (v0 + v1);  // v² is nearly linear in s over a step: trapezoid on v
  }
  return t;
}

TEST(BoundCoupled, ArcRampsWithTheNormalAccelerationsShare) {
  // A 180° arc R = 5 from rest to rest at F6000 = 100 mm/s = √(R·A): the speed limit makes
  // v²/R reach A, where an axis at 45° to the tangent leaves a_t ≤ (√2 − 1)·A.
  Block a;
  a.kind = BlockKind::kArc;
  a.start = P(5, 0);
  a.end = P(-5, 0);
  a.center = {0, 0, 0};
  a.normal = {0, 0, 1};
  a.feed_mm_min = 6000;
  const double r = 5, sweep = std::numbers::pi, v = 100;
  // The first bound: a trapezoid at A, v/A + L/v.
  const double simple = v / kA + r * sweep / v;
  EXPECT_NEAR(optimal_time_s({a}, {}, Model::kSimple), simple, 1e-12);
  EXPECT_NEAR(optimal_time_s({a}, {}), simple, 1e-12);  // no axis limits: nothing couples
  testing::Limits lim;  // the built-in machine: every axis 2000 mm/s² (= A)
  lim.axis_accel_mm_s2[kX] = lim.axis_accel_mm_s2[kY] = lim.axis_accel_mm_s2[kZ] = kA;
  const double exact = exact_arc_time(r, sweep, v, kA, kA);
  const double coupled = optimal_time_s({a}, lim);
  // Still a lower bound of the exact optimum, tighter than the first bound, and within 0.3 % of
  // the optimum (1° pieces with the Lipschitz slack).
  EXPECT_LE(coupled, exact);
  EXPECT_GT(coupled, simple + 0.5 * (exact - simple));
  EXPECT_GT(coupled, exact * 0.997);
  RecordProperty("exact_s", std::to_string(exact));
  std::printf("arc R5 180deg: simple %.6f coupled %.6f exact %.6f s\n", simple, coupled, exact);
}

// The bound is a lower bound of a sampled trajectory the checker accepts, and close to it on a
// dense zig-zag of capped corners: a trajectory built cycle by cycle (bench/bound/
// discrete_reference.py) passes every corner with ONE cycle centred on it.
TEST(BoundHonesty, ZigzagHasACheckedTrajectoryWithin5PercentOfTheBound) {
  // linuxcnc-tp/zigzag_0.002_0.0005 in mm: strokes of (0.0508, ±0.0254) mm at F > Vmax; corners
  // of θ = 2·atan(1/2) = 53.13°, V_g = A·τ/(2 sin(θ/2)) = 2/(2/√5) = √5 mm/s.
  const int strokes = 200;
  const double dx = 0.0508, dy = 0.0254, tau = 0.001;
  std::vector<Block> blocks;
  for (int i = 0; i < strokes; ++i) {
    const double y0 = i % 2 == 1 ? -dy / 2 : dy / 2;  // every stroke the same length
    const double y1 = i % 2 == 0 ? -dy / 2 : dy / 2;
    Block b;
    b.kind = BlockKind::kLine;
    b.line = static_cast<std::uint32_t>(i + 1);
    b.start = P(dx * i, y0);
    b.end = P(dx * (i + 1), y1);
    b.feed_mm_min = 9999 * 25.4;
    blocks.push_back(b);
  }
  testing::Limits lim;  // the built-in machine
  for (std::size_t i = 0; i < 3; ++i) {
    lim.axis_accel_mm_s2[i] = kA;
    lim.axis_speed_mm_min[i] = 15000;
  }
  const double bound = optimal_time_s(blocks, lim);

  // Cycle lengths (mm). m = 0.99 on every limit. Joint cycle m·√5·τ, centred on the joint; its
  // neighbours may be longer by D = m·A·τ² (hand check of the two samples around a corner: the
  // tangential rule allows A·τ, the Y axis (V + D)/√5 ≤ A·τ, X 2D/√5 ≤ A·τ, the normal rule far
  // more). Between two joint cycles the fewest cycles whose largest profile (rising by m·A·τ²
  // per cycle from V + D at both ends) covers the gap, topped at the level that fits exactly.
  const double m = 0.99, step = m * kA * tau * tau, vg = m * std::sqrt(5.0) * tau;
  // The cycles next to a joint cycle lie in [vg − step, vg + step] (tangential rule); the first
  // and last of the program within [0, step] (from and to rest).
  const double edge = vg + step, edge_min = vg - step;
  auto fill = [&](double dist, double first_max, double last_max, double first_min,
                  double last_min) {
    std::size_t k = 1;
    auto prof = [&](std::size_t kk, double h) {
      std::vector<double> x(kk);
      for (std::size_t i = 0; i < kk; ++i) {
        const double up = std::min(first_max + step * static_cast<double>(i),
                                   last_max + step * static_cast<double>(kk - 1 - i));
        const double low = std::max({0.0, first_min - step * static_cast<double>(i),
                                     last_min - step * static_cast<double>(kk - 1 - i)});
        x[i] = std::min(up, std::max(low, h));
      }
      return x;
    };
    auto sum = [](const std::vector<double>& x) {
      double s = 0;
      for (double v : x) s += v;
      return s;
    };
    while (sum(prof(k, 1e9)) < dist) ++k;
    double lo = 0, hi = 1;  // 1 mm per cycle: above every profile value here
    for (int it = 0; it < 80; ++it)
      (sum(prof(k, 0.5 * (lo + hi))) < dist ? lo : hi) = 0.5 * (lo + hi);
    auto x = prof(k, hi);
    x.back() += dist - sum(x);
    return x;
  };
  const double seg = std::hypot(dx, dy);
  std::vector<double> cycles;  // path length of each cycle
  std::vector<std::size_t> per_segment;
  for (int i = 0; i < strokes; ++i) {
    const double before = i == 0 ? 0 : vg / 2, after = i + 1 == strokes ? 0 : vg / 2;
    const double first_max = i == 0 ? step : edge, last_max = i + 1 == strokes ? step : edge;
    auto x = fill(seg - before - after, first_max, last_max, i == 0 ? 0 : edge_min,
                  i + 1 == strokes ? 0 : edge_min);
    per_segment.push_back(x.size() + (i + 1 == strokes ? 0 : 1));
    cycles.insert(cycles.end(), x.begin(), x.end());
    if (i + 1 < strokes) cycles.push_back(vg);
  }
  // Hand count for an inner stroke: 0.056796 − 0.002214 = 0.054582 mm between joint cycles;
  // 7 cycles reach at most 2·(4.19 + 6.17 + 8.15) + 10.13 = 47.2 µm, 8 cycles 57.3 µm: 8 + the
  // joint cycle = 9.
  EXPECT_EQ(per_segment[strokes / 2], 9u);

  testing::Trajectory tr;
  tr.period_s = tau;
  double s = 0;
  auto point = [&](double sv) {
    const auto k = std::min<std::size_t>(static_cast<std::size_t>(sv / seg), strokes - 1);
    const Block& b = blocks[k];
    const double f = std::clamp((sv - seg * static_cast<double>(k)) / seg, 0.0, 1.0);
    AxisVec p;
    for (std::size_t i = 0; i < 3; ++i) p[i] = b.start[i] + f * (b.end[i] - b.start[i]);
    return std::make_pair(b.line, p);
  };
  auto [l0, p0] = point(0);
  tr.add(0, l0, p0);
  for (std::size_t k = 0; k < cycles.size(); ++k) {
    s = k + 1 == cycles.size() ? seg * strokes : s + cycles[k];
    auto [ln, p] = point(s);
    tr.add(tau * static_cast<double>(k + 1), ln, p);
  }
  const auto rep = testing::check_trajectory(tr, blocks, lim);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  const double t = tau * static_cast<double>(cycles.size());
  EXPECT_LE(bound, t);         // a lower bound of a checked trajectory
  EXPECT_LE(t, 1.05 * bound);  // and within 1.05 of it: the corners cost sampling little
  std::printf("zigzag %d strokes: bound %.6f s, checked trajectory %.3f s (%.4f)\n", strokes, bound,
              t, t / bound);
}

}  // namespace
}  // namespace cncore::bound
