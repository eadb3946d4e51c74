// Exact geometry of the programmed path: lengths, tangents, distances to lines, arcs in every
// plane and multi-turn helices, stop points.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "path_geometry.hpp"

namespace cncore::testing {
namespace {

AxisVec P(double x, double y, double z = 0) {
  AxisVec p;
  p[kX] = x;
  p[kY] = y;
  p[kZ] = z;
  return p;
}

Block arc(AxisVec s, AxisVec e, Vec3 c, Vec3 n, std::uint32_t turns = 0) {
  Block b;
  b.kind = BlockKind::kArc;
  b.start = s;
  b.end = e;
  b.center = c;
  b.normal = n;
  b.turns = turns;
  b.feed_mm_min = 1000;
  return b;
}

TEST(PathGeometry, QuarterArcInEachPlane) {
  // G17 G3 (normal +Z): (10,0) → (0,10) about the origin, a quarter turn.
  // G18 (normal ±Y) and G19 (normal ±X) likewise; length π·R/2.
  struct Case {
    AxisVec s, e;
    Vec3 n;
  };
  const Case cases[] = {{P(10, 0, 0), P(0, 10, 0), {0, 0, 1}},
                        {P(0, 0, 10), P(10, 0, 0), {0, 1, 0}},   // Z→X is CCW about +Y
                        {P(0, 10, 0), P(0, 0, 10), {1, 0, 0}}};  // Y→Z is CCW about +X
  for (const auto& c : cases) {
    const Path path = build_path({arc(c.s, c.e, {0, 0, 0}, c.n)});
    ASSERT_EQ(path.segments.size(), 1u);
    const auto& sg = path.segments[0];
    EXPECT_NEAR(sg.sweep_rad, std::numbers::pi / 2, 1e-12);
    EXPECT_NEAR(path.length_mm, 5 * std::numbers::pi, 1e-12);
    const AxisVec mid = sg.point_at(0.5);
    const double r = std::sqrt(mid[kX] * mid[kX] + mid[kY] * mid[kY] + mid[kZ] * mid[kZ]);
    EXPECT_NEAR(r, 10, 1e-12);
    // A point 0.1 mm outside the middle of the arc is 0.1 mm from it, at u = 0.5.
    double d = 0;
    const double u = sg.project((1.01) * mid, 0, d);
    EXPECT_NEAR(d, 0.1, 1e-12);
    EXPECT_NEAR(u, 0.5, 1e-12);
    // The centre is R from every point.
    sg.project(P(0, 0, 0), 0, d);
    EXPECT_NEAR(d, 10, 1e-12);
  }
}

TEST(PathGeometry, ClockwiseArcGoesTheLongWayWhenAsked) {
  // G2 in G17 (normal −Z) from (10,0) to (0,10): three quarters of a turn.
  const Path path = build_path({arc(P(10, 0), P(0, 10), {0, 0, 0}, {0, 0, -1})});
  EXPECT_NEAR(path.segments[0].sweep_rad, 1.5 * std::numbers::pi, 1e-12);
  const AxisVec mid = path.segments[0].point_at(1.0 / 3);  // 90° clockwise: (0, −10)
  EXPECT_NEAR(mid[kX], 0, 1e-12);
  EXPECT_NEAR(mid[kY], -10, 1e-12);
}

TEST(PathGeometry, MultiTurnHelixDistanceAndLength) {
  // Full circle R = 5 with P3 (two extra turns) rising 6 mm: three turns, 2 mm pitch.
  const Path path = build_path({arc(P(5, 0, 0), P(5, 0, 6), {0, 0, 0}, {0, 0, 1}, 2)});
  const auto& sg = path.segments[0];
  EXPECT_NEAR(sg.sweep_rad, 6 * std::numbers::pi, 1e-12);
  EXPECT_NEAR(sg.length_mm, std::hypot(30 * std::numbers::pi, 6.0), 1e-9);
  // Points on the helix are at distance 0 and project to their own parameter.
  for (double u : {0.0, 0.1, 0.37, 0.5, 0.83, 1.0}) {
    double d = 1;
    const double got = sg.project(sg.point_at(u), 0, d);
    EXPECT_LT(d, 1e-9) << u;
    EXPECT_NEAR(got, u, 1e-9) << u;
  }
  // On the axis at height 3 mm the nearest helix point is R away... (the helix passes at
  // z = 3 ± pitch/2 over the turn, so the distance is exactly 5 at a point of equal height).
  double d = 0;
  sg.project(P(0, 0, 3), 0, d);
  EXPECT_NEAR(d, 5, 1e-9);
  // A point 0.05 mm outside, at the height of turn 2: 0.05 mm (the other turns are 2 mm away).
  const AxisVec on = sg.point_at(0.5);
  AxisVec off = on;
  off[kX] *= 1.01;
  off[kY] *= 1.01;
  sg.project(off, 0, d);
  EXPECT_NEAR(d, 0.05, 1e-6);
  // Restricting the parameter (progress never goes back) gives the distance to the rest only.
  sg.project(sg.point_at(0.2), 0.5, d);
  EXPECT_GT(d, 1.0);
}

TEST(PathGeometry, LineDistanceOverAllAxes) {
  Block b;
  b.kind = BlockKind::kLine;
  b.start = P(0, 0, 0);
  b.end = P(10, 0, 0);
  b.end[kA] = 90;  // a rotary axis moving with the line
  b.feed_mm_min = 1000;
  const Path path = build_path({b});
  EXPECT_NEAR(path.length_mm, 10, 1e-12);  // path length counts X Y Z only
  AxisVec p = P(5, 0.3, 0);
  p[kA] = 45;
  double d = 0;
  const double u = path.segments[0].project(p, 0, d);
  EXPECT_NEAR(u, 0.5, 1e-12);
  EXPECT_NEAR(d, 0.3, 1e-12);
}

TEST(PathGeometry, StopsAndCornerAngles) {
  auto line = [](AxisVec a, AxisVec b) {
    Block bl;
    bl.kind = BlockKind::kLine;
    bl.start = a;
    bl.end = b;
    bl.feed_mm_min = 1000;
    return bl;
  };
  Block dwell;
  dwell.kind = BlockKind::kDwell;
  dwell.dwell_s = 0.5;
  Block m0;
  m0.kind = BlockKind::kAux;
  m0.aux_letter = 'M';
  m0.aux_waits = true;
  Block s;
  s.kind = BlockKind::kAux;
  s.aux_letter = 'S';
  std::vector<Block> blocks = {
      line(P(0, 0), P(1, 0)), s,  line(P(1, 0), P(1, 1)), dwell, line(P(1, 1), P(1, 1)),
      line(P(1, 1), P(0, 2)), m0, line(P(0, 2), P(0, 3))};
  const Path path = build_path(blocks);
  ASSERT_EQ(path.segments.size(), 4u);  // the zero-length line is dropped
  EXPECT_FALSE(path.segments[0].stop_after);
  EXPECT_TRUE(path.segments[1].stop_after);
  EXPECT_NEAR(path.segments[1].dwell_after_s, 0.5, 0);
  EXPECT_TRUE(path.segments[2].stop_after);
  EXPECT_TRUE(path.segments[3].stop_after);  // end of program
  EXPECT_NEAR(corner_angle_rad(path.segments[0], path.segments[1]), std::numbers::pi / 2, 1e-12);
  // +Y then (−1, 1)/√2: 45°.
  EXPECT_NEAR(corner_angle_rad(path.segments[1], path.segments[2]), std::numbers::pi / 4, 1e-12);
  EXPECT_NEAR(path.length_mm, 2 + std::sqrt(2.0) + 1, 1e-12);
}

}  // namespace
}  // namespace cncore::testing
