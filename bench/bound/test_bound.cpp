// The time-optimal bound on cases with closed-form answers.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "bound.hpp"

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

}  // namespace
}  // namespace cncore::bound
