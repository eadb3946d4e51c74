// The path smoothing stage and its curve fit: what comes out is measured against what went in
// (distances both ways between the curves and the chords by dense sampling, vertices kept,
// corners kept, other blocks in order).
#include "planner/path_smoother.hpp"

#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "geometry/curve_fit.hpp"

namespace cncore::planner {
namespace {

constexpr double kPi = std::numbers::pi;

Vec3 rounded(Vec3 p, double q) {
  return {std::round(p.x / q) * q, std::round(p.y / q) * q, std::round(p.z / q) * q};
}

Vec3 unit(Vec3 v) {
  return (1 / norm(v)) * v;
}

double point_segment(Vec3 p, Vec3 a, Vec3 b) {
  const Vec3 d = b - a;
  const double l2 = dot(d, d);
  const double t = l2 > 0 ? std::clamp(dot(p - a, d) / l2, 0.0, 1.0) : 0.0;
  return norm(p - (a + t * d));
}

double point_polyline(Vec3 p, const std::vector<Vec3>& poly) {
  double best = 1e300;
  for (std::size_t i = 1; i < poly.size(); ++i) {
    best = std::min(best, point_segment(p, poly[i - 1], poly[i]));
  }
  return best;
}

// Dense samples of a block's shape (lines and arcs/helices as the planner builds them).
std::vector<Vec3> shape_samples(const Block& b, int n) {
  std::vector<Vec3> out;
  const Vec3 s = b.start.xyz(), e = b.end.xyz();
  if (b.kind != BlockKind::kArc) {
    for (int i = 0; i <= n; ++i) out.push_back(s + (static_cast<double>(i) / n) * (e - s));
    return out;
  }
  const Vec3 nn = unit(b.normal);
  const Vec3 q0 = s - b.center - dot(s - b.center, nn) * nn;
  const Vec3 c = s - q0;
  const double r = norm(q0);
  const Vec3 e1 = (1 / r) * q0, e2 = cross(nn, e1);
  const Vec3 q1 = e - c;
  const double rise = dot(q1, nn);
  const Vec3 q1p = q1 - rise * nn;
  double sweep = std::atan2(dot(q1p, e2), dot(q1p, e1));
  if (sweep <= 0) sweep += 2 * kPi;
  for (int i = 0; i <= n; ++i) {
    const double f = static_cast<double>(i) / n, phi = f * sweep;
    out.push_back(c + r * (std::cos(phi) * e1 + std::sin(phi) * e2) + (f * rise) * nn);
  }
  return out;
}

Block chord(Vec3 from, Vec3 to, double feed = 5000) {
  Block b;
  b.kind = BlockKind::kLine;
  b.start.set_xyz(from);
  b.end.set_xyz(to);
  b.feed_mm_min = feed;
  return b;
}

std::vector<Block> chords_of(const std::vector<Vec3>& pts, double feed = 5000) {
  std::vector<Block> out;
  for (std::size_t i = 1; i < pts.size(); ++i) out.push_back(chord(pts[i - 1], pts[i], feed));
  return out;
}

std::vector<Block> run(PathSmoother& s, const std::vector<Block>& in) {
  std::vector<Block> out;
  Block b;
  for (const Block& x : in) {
    s.put(x);
    while (s.next(b)) out.push_back(b);
  }
  s.finish();
  while (s.next(b)) out.push_back(b);
  return out;
}

// Largest distance from the output's shapes to the input polyline and back (dense samples).
double two_way_distance(const std::vector<Vec3>& poly, const std::vector<Block>& out) {
  std::vector<Vec3> curve;
  for (const Block& b : out) {
    const auto s = shape_samples(b, 400);
    curve.insert(curve.end(), s.begin(), s.end());
  }
  double d = 0;
  for (const Vec3& p : curve) d = std::max(d, point_polyline(p, poly));
  // chord points against the sampled curve (sampling adds at most the samples' sagitta)
  for (std::size_t i = 1; i < poly.size(); ++i) {
    for (int k = 0; k <= 4; ++k) {
      const Vec3 p = poly[i - 1] + (k / 4.0) * (poly[i] - poly[i - 1]);
      d = std::max(d, point_polyline(p, curve));
    }
  }
  return d;
}

std::vector<Vec3> helix_points(Vec3 c, Vec3 n, double r, double pitch_per_rad, double sweep,
                               int chords, double q) {
  const Vec3 a = std::abs(n.z) < 0.9 ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
  const Vec3 e1 = unit(cross(n, a)), e2 = cross(n, e1);
  std::vector<Vec3> pts;
  for (int i = 0; i <= chords; ++i) {
    const double phi = sweep * i / chords;
    pts.push_back(
        rounded(c + r * (std::cos(phi) * e1 + std::sin(phi) * e2) + (pitch_per_rad * phi) * n, q));
  }
  return pts;
}

TEST(CurveFit, RoundedCircleChordsFitOneArcWithinTheTolerance) {
  const auto pts = helix_points({1, 2, 3}, unit({0.3, -0.2, 1}), 20, 0, kPi / 2, 500, 1e-4);
  CurveFit f;
  ASSERT_TRUE(fit_curve(pts, {0.01, kPi, 1e4}, f));
  EXPECT_EQ(f.kind, CurveFit::Kind::kArc);
  EXPECT_NEAR(f.radius_mm, 20, 1e-3);
  EXPECT_NEAR(f.sweep_rad, kPi / 2, 1e-4);
}

TEST(CurveFit, HelixAboutZFitsAndAPlaneArcDoesNot) {
  const auto pts = helix_points({0, 0, 0}, {0, 0, 1}, 10, 2 / (2 * kPi), kPi, 300, 1e-4);
  CurveFit f;
  ASSERT_TRUE(fit_curve(pts, {0.01, kPi, 1e4}, f));
  EXPECT_EQ(f.kind, CurveFit::Kind::kArc);
  EXPECT_NEAR(std::abs(f.normal.z), 1, 1e-12);
  EXPECT_NEAR(f.radius_mm, 10, 1e-3);
}

TEST(CurveFit, CornerOfTwoLongLegsDoesNotFit) {
  std::vector<Vec3> pts;
  for (int i = 0; i <= 10; ++i) pts.push_back({i * 0.1, 0, 0});
  for (int i = 1; i <= 10; ++i) pts.push_back({1, i * 0.1, 0});
  CurveFit f;
  EXPECT_FALSE(fit_curve(pts, {0.01, kPi, 1e4}, f));
}

TEST(CurveFit, ChordsFartherThanTheToleranceFromEveryArcDoNotFit) {
  // A 90° arc of R 1 in 4 chords: sagitta 1 − cos(π/16) = 0.019 mm
  const auto pts = helix_points({0, 0, 0}, {0, 0, 1}, 1, 0, kPi / 2, 4, 1e-9);
  CurveFit f;
  EXPECT_FALSE(fit_curve(pts, {0.01, kPi, 1e4}, f));
  EXPECT_TRUE(fit_curve(pts, {0.02, kPi, 1e4}, f));
}

// Random arcs and helices in random planes, rounded to 3–5 decimals: whatever the smoother
// makes of their chords lies within the tolerance of them both ways, and ends on their vertices.
RC_GTEST_PROP(PathSmoother, RandomCurvesStayWithinTheTolerance, ()) {
  const double r = *rc::gen::inRange(5, 2000) / 100.0;  // 0.05 … 20 mm
  const double sweep = *rc::gen::inRange(10, 600) / 100.0;
  const int chords = *rc::gen::inRange(3, 400);
  const int decimals = *rc::gen::inRange(3, 6);
  const double tol = *rc::gen::element(0.002, 0.005, 0.01, 0.05);
  const bool helix = *rc::gen::arbitrary<bool>();
  const Vec3 n =
      helix ? Vec3{0, 0, 1}
            : unit({*rc::gen::inRange(-100, 100) / 100.0, *rc::gen::inRange(-100, 100) / 100.0, 1});
  const auto pts =
      helix_points({3, -2, 1}, n, r, helix ? 0.3 : 0, sweep, chords, std::pow(10.0, -decimals));
  SmoothingSettings settings;
  settings.tolerance_mm = tol;
  settings.contour_tolerance_mm = 1;
  PathSmoother s(settings);
  const auto out = run(s, chords_of(pts));
  RC_ASSERT(!out.empty());
  RC_ASSERT(out.front().start.xyz() == pts.front());
  RC_ASSERT(out.back().end.xyz() == pts.back());
  for (std::size_t i = 0; i < out.size(); ++i) {
    RC_ASSERT(std::ranges::find(pts, out[i].end.xyz()) != pts.end());
    if (i > 0) RC_ASSERT(out[i].start == out[i - 1].end);
  }
  RC_ASSERT(two_way_distance(pts, out) <= tol * (1 + 1e-6) + 1e-9);
}

TEST(PathSmoother, CircleOfChordsBecomesAFewArcs) {
  // 36 000 chords of R 20 (3.5 µm) with 4 decimals: arcs of at most kMaxChords chords
  const auto pts = helix_points({0, 0, 0}, {0, 0, 1}, 20, 0, 2 * kPi, 36000, 1e-4);
  SmoothingSettings settings;
  settings.tolerance_mm = 0.01;
  settings.free_turn_rad = 0.008;  // the built-in machine's
  PathSmoother s(settings);
  const auto out = run(s, chords_of(pts));
  EXPECT_LE(out.size(), 40u);
  for (std::size_t i = 0; i + 1 < out.size(); ++i) EXPECT_EQ(out[i].kind, BlockKind::kArc);
  EXPECT_EQ(s.chords_in(), 36000u);
  EXPECT_EQ(s.blocks_out(), out.size());
  // 3 600 chords (35 µm): few enough to measure both ways
  const auto coarse = helix_points({0, 0, 0}, {0, 0, 1}, 20, 0, 2 * kPi, 3600, 1e-4);
  PathSmoother s2(settings);
  const auto out2 = run(s2, chords_of(coarse));
  EXPECT_LE(out2.size(), 8u);
  EXPECT_LE(two_way_distance(coarse, out2), 0.01);
}

TEST(PathSmoother, RealCornersStayCorners) {
  // A square of side 10 in 0.5 mm chords: the corners turn 90° between chords longer than the
  // tolerance, and each side becomes one line.
  std::vector<Vec3> pts{{0, 0, 0}};
  const Vec3 corners[] = {{10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {0, 0, 0}};
  for (const Vec3& c : corners) {
    const Vec3 from = pts.back();
    for (int i = 1; i <= 20; ++i) pts.push_back(from + (i / 20.0) * (c - from));
  }
  SmoothingSettings settings;
  settings.tolerance_mm = 0.01;
  PathSmoother s(settings);
  const auto out = run(s, chords_of(pts));
  ASSERT_EQ(out.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(out[i].kind, BlockKind::kLine);
    EXPECT_EQ(out[i].end.xyz(), corners[i]);
  }
}

TEST(PathSmoother, ExactVerticesOtherBlocksAndFeedChangesEndARun) {
  const auto pts = helix_points({0, 0, 0}, {0, 0, 1}, 5, 0, kPi, 60, 1e-6);
  auto in = chords_of(pts);
  in[19].path_mode = PathMode::kExactPath;  // vertex 20 stays exact
  for (std::size_t i = 40; i < in.size(); ++i) in[i].feed_mm_min = 3000;
  Block aux;
  aux.kind = BlockKind::kAux;
  aux.aux_letter = 'M';
  aux.aux_value = 8;
  in.insert(in.begin() + 30, aux);
  SmoothingSettings settings;
  settings.tolerance_mm = 0.01;
  PathSmoother s(settings);
  const auto out = run(s, in);
  std::vector<Vec3> ends;
  std::size_t aux_at = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (out[i].kind == BlockKind::kAux) aux_at = i;
    if (is_motion(out[i])) ends.push_back(out[i].end.xyz());
  }
  EXPECT_NE(std::ranges::find(ends, pts[20]), ends.end());
  EXPECT_NE(std::ranges::find(ends, pts[30]), ends.end());
  EXPECT_NE(std::ranges::find(ends, pts[40]), ends.end());
  ASSERT_GT(aux_at, 0u);
  EXPECT_EQ(out[aux_at - 1].end.xyz(), pts[30]);
  EXPECT_EQ(out.back().feed_mm_min, 3000);
  EXPECT_EQ(out.size(), 5u);  // four arcs and the M8
}

TEST(PathSmoother, OffPassesEveryBlockUnchanged) {
  const auto in = chords_of(helix_points({0, 0, 0}, {0, 0, 1}, 5, 0, kPi, 60, 1e-4));
  PathSmoother s(SmoothingSettings{});
  const auto out = run(s, in);
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t i = 0; i < in.size(); ++i) EXPECT_EQ(out[i].end, in[i].end);
}

TEST(PathSmoother, GcodeQOverridesTheMachineAndTheContourToleranceCapsIt) {
  SmoothingSettings settings;
  settings.tolerance_mm = 0.01;
  settings.contour_tolerance_mm = 0.02;
  PathSmoother s(settings);
  Block b = chord({0, 0, 0}, {1, 0, 0});
  EXPECT_EQ(s.tolerance_of(b), 0.01);
  b.smooth_tolerance_mm = 0;
  EXPECT_EQ(s.tolerance_of(b), 0);
  b.smooth_tolerance_mm = 0.05;
  EXPECT_EQ(s.tolerance_of(b), 0.02);
  b.tolerance_mm = 0.005;
  EXPECT_EQ(s.tolerance_of(b), 0.005);
  b.kind = BlockKind::kRapid;
  EXPECT_EQ(s.tolerance_of(b), 0);
}

}  // namespace
}  // namespace cncore::planner
