// G5 / G5.1 / G5.2–G5.3 splines, measured on the blocks the interpreter emits: the arcs are
// sampled densely and compared with the exact curve evaluated here (Bernstein polynomials, a
// circle), both ways (every point of the arcs near the curve and every point of the curve near the
// arcs); joints between emitted blocks turn by no more than rounding; the last block ends exactly
// on the programmed end point. Also the errors LinuxCNC gives, and G7/G8 diameter mode.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

constexpr double kTol = 0.01;  // the test machine's contour tolerance (the fit's)
constexpr double kPi = std::numbers::pi;

std::vector<Block> moves(const std::string& text, const MachineConfig& m = test_machine()) {
  return motion_blocks(text, "s.ngc", m);
}

std::string error_of(const std::string& text) {
  return error_of_text(text, "s.ngc");
}

Vec3 unit(Vec3 v) {
  return (1 / norm(v)) * v;
}

// A point of a block at s ∈ [0, 1] (arcs about their centre, counter-clockwise about normal).
Vec3 block_point(const Block& b, double s) {
  const Vec3 a = b.start.xyz(), e = b.end.xyz();
  if (b.kind != BlockKind::kArc) return a + s * (e - a);
  const Vec3 u0 = a - b.center, u1 = e - b.center;
  const double r = norm(u0);
  const Vec3 x = unit(u0), y = cross(b.normal, x);
  double sweep = std::atan2(dot(u1, y), dot(u1, x));
  if (sweep <= 0) sweep += 2 * kPi;
  return b.center + r * (std::cos(s * sweep) * x + std::sin(s * sweep) * y);
}

Vec3 start_tangent(const Block& b) {
  if (b.kind != BlockKind::kArc) return unit(b.end.xyz() - b.start.xyz());
  return unit(cross(b.normal, b.start.xyz() - b.center));
}
Vec3 end_tangent(const Block& b) {
  if (b.kind != BlockKind::kArc) return unit(b.end.xyz() - b.start.xyz());
  return unit(cross(b.normal, b.end.xyz() - b.center));
}

double seg_distance(Vec3 p, Vec3 a, Vec3 b) {
  const Vec3 d = b - a;
  const double l2 = dot(d, d);
  const double t = l2 > 0 ? std::clamp(dot(p - a, d) / l2, 0.0, 1.0) : 0;
  return norm(p - (a + t * d));
}

// The largest distance of the points of `from` to the polyline `to`.
double one_way(const std::vector<Vec3>& from, const std::vector<Vec3>& to) {
  double worst = 0;
  for (const Vec3& p : from) {
    double best = 1e300;
    for (std::size_t i = 0; i + 1 < to.size(); ++i) {
      best = std::min(best, seg_distance(p, to[i], to[i + 1]));
    }
    worst = std::max(worst, best);
  }
  return worst;
}

// The distance of p to a block: to the arc itself where p's angle lies within its sweep, else to
// its nearer end (a line: to the segment).
double block_distance(Vec3 p, const Block& b) {
  const Vec3 a = b.start.xyz(), e = b.end.xyz();
  if (b.kind != BlockKind::kArc) return seg_distance(p, a, e);
  const Vec3 u0 = a - b.center, u1 = e - b.center, v = p - b.center;
  const Vec3 x = unit(u0), y = cross(b.normal, x);
  auto angle = [&](Vec3 w) {
    const double phi = std::atan2(dot(w, y), dot(w, x));
    return phi < 0 ? phi + 2 * kPi : phi;
  };
  const double ends = std::min(norm(p - a), norm(p - e));
  if (angle(v) > angle(u1)) return ends;
  return std::min(ends, std::fabs(norm(v) - norm(u0)));
}

struct Measure {
  double distance_mm = 0;  // both ways, arcs against the curve
  double worst_turn = 0;   // largest turn at a joint between emitted blocks (rad)
  double start_turn = 0;   // the first block's start tangent against the curve's
  double end_turn = 0;     // the last block's end tangent against the curve's
  std::size_t arcs = 0, lines = 0;
};

// curve(t), t ∈ [0, 1], against the emitted blocks `b` (from index first on).
Measure measure(const std::vector<Block>& b, std::size_t first,
                const std::function<Vec3(double)>& curve) {
  Measure m;
  std::vector<Vec3> emitted, exact;
  for (std::size_t i = first; i < b.size(); ++i) {
    (b[i].kind == BlockKind::kArc ? m.arcs : m.lines) += 1;
    for (int k = 0; k < 40; ++k) emitted.push_back(block_point(b[i], k / 40.0));
    if (i > first) {
      m.worst_turn = std::max(
          m.worst_turn,
          std::acos(std::clamp(dot(end_tangent(b[i - 1]), start_tangent(b[i])), -1.0, 1.0)));
    }
  }
  emitted.push_back(b.back().end.xyz());
  constexpr int kN = 20000;
  for (int k = 0; k <= kN; ++k) exact.push_back(curve(static_cast<double>(k) / kN));
  // The emitted points against the dense exact polyline (its chords within ~1e-7 mm of the
  // curve), and every exact point against the nearest emitted block.
  m.distance_mm = one_way(emitted, exact);
  for (const Vec3& p : exact) {
    double best = 1e300;
    for (std::size_t i = first; i < b.size(); ++i) best = std::min(best, block_distance(p, b[i]));
    m.distance_mm = std::max(m.distance_mm, best);
  }
  const double h = 1e-7;
  const Vec3 t0 = unit(curve(h) - curve(0)), t1 = unit(curve(1) - curve(1 - h));
  m.start_turn = std::acos(std::clamp(dot(t0, start_tangent(b[first])), -1.0, 1.0));
  m.end_turn = std::acos(std::clamp(dot(t1, end_tangent(b.back())), -1.0, 1.0));
  return m;
}

Vec3 cubic(Vec3 p0, Vec3 p1, Vec3 p2, Vec3 p3, double t) {
  const double s = 1 - t;
  return (s * s * s) * p0 + (3 * s * s * t) * p1 + (3 * s * t * t) * p2 + (t * t * t) * p3;
}

void expect_close(const Measure& m, const char* what) {
  EXPECT_LE(m.distance_mm, kTol) << what;
  EXPECT_LT(m.worst_turn, 1e-6) << what;
  EXPECT_LT(m.start_turn, 1e-5) << what;
  EXPECT_LT(m.end_turn, 1e-5) << what;
  EXPECT_EQ(m.lines, 0U) << what;
  EXPECT_GE(m.arcs, 2U) << what;
}

TEST(Splines, CubicRunsAsTangentArcsWithinTheTolerance) {
  const auto b = moves("G21 G90 G17 G0 X0 Y0\nG5 X60 Y20 I30 J40 P-10 Q-50 F3000\n");
  const auto m = measure(b, 0, [](double t) {
    return cubic({0, 0, 0}, {30, 40, 0}, {50, -30, 0}, {60, 20, 0}, t);
  });
  expect_close(m, "cubic");
  EXPECT_EQ(b.back().end[kX], 60.0);
  EXPECT_EQ(b.back().end[kY], 20.0);
  EXPECT_LT(m.arcs, 200U) << "bounded by curvature and tolerance";
  for (const Block& x : b) EXPECT_EQ(x.line, 2U);
}

TEST(Splines, ChainWithoutIJLeavesAlongThePreviousEndTangent) {
  // LinuxCNC's curvy N and a second one attached without I J: its first control point is the
  // mirror of the previous second one, (1, 1) − (0, −3) → (1, 4) in inches.
  const auto b = moves("G20 G90 G17 G0 X0 Y0\nG5 I0 J3 P0 Q-3 X1 Y1 F100\nG5 P0 Q-3 X2 Y2\n");
  std::size_t split = 0;
  while (b[split].line == 2) ++split;
  const double in = 25.4;
  auto first = [&](double t) {
    return cubic({0, 0, 0}, {0, 3 * in, 0}, {1 * in, -2 * in, 0}, {1 * in, 1 * in, 0}, t);
  };
  auto second = [&](double t) {
    return cubic({in, in, 0}, {in, 4 * in, 0}, {2 * in, -1 * in, 0}, {2 * in, 2 * in, 0}, t);
  };
  const std::vector<Block> a(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(split));
  const std::vector<Block> c(b.begin() + static_cast<std::ptrdiff_t>(split), b.end());
  expect_close(measure(a, 0, first), "first of the chain");
  expect_close(measure(c, 0, second), "second of the chain");
  // No kink where they meet.
  EXPECT_LT(std::acos(std::clamp(dot(end_tangent(a.back()), start_tangent(c.front())), -1.0, 1.0)),
            1e-5);
  EXPECT_EQ(c.back().end[kX], 2 * in);
}

TEST(Splines, QuadraticParabolaWithinTheTolerance) {
  // LinuxCNC's example: the parabola through the origin from (−2, 4) to (2, 4).
  const auto b = moves("G21 G90 G17 G0 X-2 Y4\nG5.1 X2 I2 J-8 F600\n");
  const auto m = measure(b, 1, [](double t) {
    const double s = 1 - t;
    return (s * s) * Vec3{-2, 4, 0} + (2 * s * t) * Vec3{0, -4, 0} + (t * t) * Vec3{2, 4, 0};
  });
  expect_close(m, "parabola");
  EXPECT_EQ(b.back().end[kX], 2.0);
}

TEST(Splines, WeightedNurbsQuarterIsACircle) {
  // A rational quadratic with weights 1, √2/2, 1 on the corners of a square is an exact quarter
  // circle: R 40 about the origin from (40, 0) to (0, 40).
  const auto b = moves(
      "G21 G90 G17 G0 X40 Y0\nF2000\nG5.2 L3\nX40 Y40 P0.70710678118654752\nX0 Y40 P1\nG5.3\n");
  const auto m = measure(b, 1, [](double t) {
    return Vec3{40 * std::cos(t * kPi / 2), 40 * std::sin(t * kPi / 2), 0};
  });
  EXPECT_LE(m.distance_mm, 1e-6) << "the arcs of a circle are that circle";
  EXPECT_LT(m.worst_turn, 1e-6);
  for (std::size_t i = 1; i < b.size(); ++i) {
    ASSERT_EQ(b[i].kind, BlockKind::kArc);
    EXPECT_NEAR(norm(b[i].center), 0, 1e-6) << "centred on the circle's centre";
  }
  EXPECT_EQ(b.back().end[kX], 0.0);
  EXPECT_EQ(b.back().end[kY], 40.0);
}

TEST(Splines, NurbsOfOrderFourFollowsItsControlPolygonWithinTheTolerance) {
  // A clamped cubic B-spline of five points (knots 0 0 0 0 ½ 1 1 1 1), evaluated here by
  // Cox–de Boor's definition.
  const auto b =
      moves("G21 G90 G17 G0 X0 Y0\nF2000\nG5.2 L4\nX10 Y30\nX40 Y30\nX50 Y0\nX80 Y10\nG5.3\n");
  const std::vector<Vec3> p{{0, 0, 0}, {10, 30, 0}, {40, 30, 0}, {50, 0, 0}, {80, 10, 0}};
  const std::vector<double> u{0, 0, 0, 0, 0.5, 1, 1, 1, 1};
  std::function<double(std::size_t, int, double)> n = [&](std::size_t i, int k, double t) {
    if (k == 0) {
      return (u[i] <= t && t < u[i + 1]) || (t == 1 && u[i] < 1 && u[i + 1] == 1) ? 1.0 : 0.0;
    }
    const auto uk = static_cast<std::size_t>(k);
    const double a = u[i + uk] > u[i] ? (t - u[i]) / (u[i + uk] - u[i]) * n(i, k - 1, t) : 0;
    const double c = u[i + uk + 1] > u[i + 1]
                         ? (u[i + uk + 1] - t) / (u[i + uk + 1] - u[i + 1]) * n(i + 1, k - 1, t)
                         : 0;
    return a + c;
  };
  const auto m = measure(b, 0, [&](double t) {
    Vec3 q;
    for (std::size_t i = 0; i < p.size(); ++i) q = q + n(i, 3, t) * p[i];
    return q;
  });
  expect_close(m, "order 4 NURBS");
}

TEST(Splines, ClosedLoopInIncrementalInchRuns) {
  // G91: X Y relative to the start, I J P Q always relative; a G5 ending where it starts is a
  // loop (teardrop) and still runs in full. Inch: every offset times 25.4.
  const auto b = moves("G20 G90 G17 G0 X1 Y1\nG91 G5 X0 Y0 I2 J1 P2 Q-1 F50\n");
  const double in = 25.4;
  const Vec3 s{in, in, 0};
  const auto m = measure(b, 1, [&](double t) {
    return cubic(s, s + Vec3{2 * in, in, 0}, s + Vec3{2 * in, -in, 0}, s, t);
  });
  expect_close(m, "loop");
  EXPECT_EQ(b.back().end[kX], in);
  EXPECT_EQ(b.back().end[kY], in);
}

TEST(Splines, NurbsOfOrderTwoIsItsControlPolygon) {
  // Order 2: the B-spline is the polygon itself, corners included: straight blocks on it.
  const auto b = moves("G21 G90 G17 G0 X0 Y0\nF1000\nG5.2 L2\nX10 Y0\nX10 Y10\nX20 Y10\nG5.3\n");
  ASSERT_FALSE(b.empty());
  EXPECT_LE(b.size(), 9U);
  const std::vector<Vec3> corners{{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {20, 10, 0}};
  for (const Block& x : b) {
    EXPECT_EQ(x.kind, BlockKind::kLine);
    double best = 1e300;
    for (std::size_t i = 0; i + 1 < corners.size(); ++i) {
      best = std::min(best, seg_distance(x.end.xyz(), corners[i], corners[i + 1]));
    }
    EXPECT_LT(best, 1e-9);
  }
  EXPECT_EQ(b.back().end[kX], 20.0);
}

TEST(Splines, ErrorsAtTheirLineAndColumn) {
  EXPECT_EQ(
      error_of("G0 X0 Y0\nG5 X10 Y10 I1 J1 P1 F100\n"),
      "s.ngc:2:1: error: G5 needs both P and Q (the second control point, from the end point)");
  EXPECT_EQ(error_of("G0 X0 Y0\nG5 X10 Y10 P1 Q1 F100\n"),
            "s.ngc:2:1: error: G5 without I and J must follow another G5: the first of a series "
            "needs I and J");
  EXPECT_EQ(error_of("G5 X10 Y10 I1 P1 Q1 F100\n"),
            "s.ngc:1:12: error: G5 needs I and J together (the first control point, from the "
            "start), or neither");
  EXPECT_EQ(error_of("G18 G5 X10 Y10 I1 J1 P1 Q1 F100\n"),
            "s.ngc:1:5: error: G5 splines are in the XY plane only: program G17 first");
  EXPECT_EQ(error_of("G5 X10 Y10 Z1 I1 J1 P1 Q1 F100\n"),
            "s.ngc:1:12: error: Z word with G5: a spline moves X and Y only");
  EXPECT_EQ(error_of("G5.1 X10 Y10 F100\n"),
            "s.ngc:1:1: error: G5.1 needs I or J (the control point, from the start), not both "
            "zero");
  EXPECT_EQ(error_of("F100\nG5.2 L3\nX1 Y1\nG5.3\n"),
            "s.ngc:4:1: error: a NURBS of order 3 needs at least 3 control points, the start "
            "included (2 given)");
  EXPECT_EQ(error_of("F100\nG5.2\nX1 Y1\nG1 X2\n"),
            "s.ngc:4:1: error: the NURBS block (G5.2) is still open: close it with G5.3 before G1");
  EXPECT_EQ(error_of("G5.3\n"), "s.ngc:1:1: error: G5.3 without a NURBS block (G5.2) to close");
  EXPECT_EQ(error_of("F100\nG5.2 L3\nX1 Y1 P0\n"),
            "s.ngc:3:7: error: NURBS weight P must be positive");
  // The feed is asked for after the words.
  EXPECT_EQ(error_of("G5 X10 Y10 I1 J1 P1 Q1\n"),
            "s.ngc:1:1: error: no feed rate: program F before the first G1/G2/G3");
}

TEST(Splines, NurbsPointsDoNotCarryOverToTheNextMdiLine) {
  // A controller carries the motion mode G5.2 to its next line, not the control points.
  Options o;
  o.modal = ModalState{};
  o.modal->motion = Motion::kNurbs;
  std::string error;
  try {
    Interpreter in(Interpreter::FromText{}, "F100 X1 Y1\n", "m.ngc", test_machine(), o);
    Block b;
    while (in.next(b)) {
    }
  } catch (const InputError& e) {
    error = e.formatted();
  }
  EXPECT_EQ(error, "m.ngc:1:1: error: NURBS control point without an open G5.2 block");
}

TEST(LatheDiameterMode, G7ReadsXAsADiameterUntilG8) {
  // G18 lathe: X is the radius axis. In G7, X20 is 10 from the centre (also in G91 and in
  // G92); I stays a radius (LinuxCNC halves X words only); G8 goes back, also for its own block.
  const auto b = moves(
      "G18 G21 G90 G0 X0 Z0\nG7 G0 X20\nG1 Z-10 F100\nG91 G1 X4\nG90\n"
      "G3 X24 Z-20 I0 K-5\nG8 G0 X20\nG7\nG0 X20 Z0\n");
  ASSERT_EQ(b.size(), 6U);
  EXPECT_DOUBLE_EQ(b[0].end[kX], 10.0);
  EXPECT_DOUBLE_EQ(b[2].end[kX], 12.0);  // G91 X4: 2 mm outwards
  // The arc from (12, −10) to (12, −20) about Z −15 at radius 5 in X K: I0 K−5 is a radius.
  ASSERT_EQ(b[3].kind, BlockKind::kArc);
  EXPECT_DOUBLE_EQ(b[3].end[kX], 12.0);
  EXPECT_DOUBLE_EQ(b[3].center.x, 12.0);
  EXPECT_DOUBLE_EQ(b[3].center.z, -15.0);
  EXPECT_DOUBLE_EQ(b[4].end[kX], 20.0);  // G8 in the block: X20 is a radius
  EXPECT_DOUBLE_EQ(b[5].end[kX], 10.0);
}

TEST(LatheDiameterMode, PositionsStayRadii) {
  MachineConfig m = test_machine();
  Options o;
  Interpreter in(Interpreter::FromText{},
                 "G7 G0 X30\n#1=#5420\nG0 X#1\nG0 Y#<_lathe_diameter_mode>\n"
                 "G8\nG0 Z[#<_lathe_radius_mode> * 2]\n",
                 "d.ngc", m, o);
  std::vector<Block> b;
  Block x;
  while (in.next(x)) {
    if (is_motion(x)) b.push_back(x);
  }
  // #5420 reads 15 (the radius, as LinuxCNC's), and X15 in G7 is 7.5 from the centre.
  ASSERT_EQ(b.size(), 4U);
  EXPECT_DOUBLE_EQ(b[1].end[kX], 7.5);
  EXPECT_DOUBLE_EQ(b[2].end[kY], 1.0);  // #<_lathe_diameter_mode> in G7
  EXPECT_DOUBLE_EQ(b[3].end[kZ], 2.0);  // #<_lathe_radius_mode> in G8
}

TEST(LatheDiameterMode, CanonicalListingShowsRadii) {
  // `cncore check --canon`: LinuxCNC's STRAIGHT_TRAVERSE/FEED and ARC_FEED carry the radius.
  Interpreter in(Interpreter::FromText{},
                 "G18 G21 G90\nG7 G0 X20 Z5\nG1 Z-10 F100\nG3 X20 Z-20 I0 K-5\nG8 G1 X20\n",
                 "c.ngc", test_machine(), Options{});
  CanonPrinter p;
  std::string out;
  Block b;
  while (in.next(b)) out += p.print(b, in.canon_frame());
  EXPECT_EQ(out,
            "STRAIGHT_TRAVERSE(10.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n"
            "SET_FEED_RATE(100.0000)\n"
            "STRAIGHT_FEED(10.0000, 0.0000, -10.0000, 0.0000, 0.0000, 0.0000)\n"
            "ARC_FEED(-20.0000, 10.0000, -15.0000, 10.0000, 1, 0.0000, 0.0000, 0.0000, 0.0000)\n"
            "STRAIGHT_FEED(20.0000, 0.0000, -20.0000, 0.0000, 0.0000, 0.0000)\n");
}

}  // namespace
}  // namespace cncore::interp::test
