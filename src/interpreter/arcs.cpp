#include "interpreter/arcs.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cncore::interp {

namespace {
constexpr double kTwoPi = 2 * std::numbers::pi;
constexpr double kSameEps = 1e-9;  // mm: start and end coincide (full circle)
}  // namespace

PlaneAxes plane_axes(Plane plane) {
  switch (plane) {
    case Plane::kZX:
      return {2, 0, 1, 'k', 'i', 'j'};
    case Plane::kYZ:
      return {1, 2, 0, 'j', 'k', 'i'};
    case Plane::kXY:
      break;
  }
  return {0, 1, 2, 'i', 'j', 'k'};
}

const char* plane_gcode(Plane plane) {
  switch (plane) {
    case Plane::kZX:
      return "G18";
    case Plane::kYZ:
      return "G19";
    case Plane::kXY:
      break;
  }
  return "G17";
}

ArcCheck centre_from_radius(Vec2 s, Vec2 e, double r, bool ccw, double tolerance_mm, Vec2& c) {
  const double abs_r = std::fabs(r);
  const Vec2 m{(s.a + e.a) / 2, (s.b + e.b) / 2};
  const double dx = e.a - s.a, dy = e.b - s.b;
  const double chord = std::hypot(dx, dy);
  if (chord < kSameEps) return {false, "R-form arc with the end point equal to the start point"};
  if (abs_r < kSameEps) return {false, "zero radius (R0) arc"};
  double h = chord / 2;
  if (h - abs_r > tolerance_mm) {
    return {false, "impossible R: the radius is too small to reach the end point"};
  }
  if (h > abs_r) h = abs_r;  // within tolerance: a half circle
  // Left normal of the chord: (−dy, dx)/chord. Short CCW or long CW → centre on the left.
  const bool left = (ccw && r > 0) || (!ccw && r < 0);
  const double d = std::sqrt(std::max(0.0, abs_r * abs_r - h * h));
  const double k = (left ? d : -d) / chord;
  c = {m.a - dy * k, m.b + dx * k};
  return {};
}

ArcCheck check_centre(Vec2 s, Vec2 e, Vec2& c, double abs_tol_mm, double rel_tol) {
  const double r0 = std::sqrt((s.a - c.a) * (s.a - c.a) + (s.b - c.b) * (s.b - c.b));
  const double r1 = std::sqrt((e.a - c.a) * (e.a - c.a) + (e.b - c.b) * (e.b - c.b));
  if (r0 < kSameEps || r1 < kSameEps) return {false, "zero-radius arc: the centre is on the arc"};
  const double abs_err = std::fabs(r1 - r0);
  const double rel_err = abs_err / std::max(r0, r1);
  if (abs_err > 100 * abs_tol_mm || (abs_err > abs_tol_mm && rel_err > rel_tol)) {
    return {false, "radius to the end of the arc differs from the radius to the start"};
  }
  const double dx = e.a - s.a, dy = e.b - s.b;
  const double chord = std::sqrt(dx * dx + dy * dy);
  if (chord >= kSameEps) {
    const Vec2 m{(s.a + e.a) / 2, (s.b + e.b) / 2};
    const Vec2 n{-dy / chord, dx / chord};
    const double t = (c.a - m.a) * n.a + (c.b - m.b) * n.b;
    c = {m.a + t * n.a, m.b + t * n.b};
  }
  return {};
}

double arc_sweep(Vec2 s, Vec2 e, Vec2 c, bool ccw, std::uint32_t turns) {
  const double t0 = std::atan2(s.b - c.b, s.a - c.a);
  const double t1 = std::atan2(e.b - c.b, e.a - c.a);
  double sweep;
  if (std::hypot(e.a - s.a, e.b - s.b) < kSameEps) {
    sweep = kTwoPi;
  } else {
    // CCW: t1 − t0 brought into (0, 2π]; CW: t0 − t1 brought into (0, 2π].
    sweep = ccw ? t1 - t0 : t0 - t1;
    while (sweep <= 0) sweep += kTwoPi;
    while (sweep > kTwoPi) sweep -= kTwoPi;
  }
  sweep += kTwoPi * turns;
  return ccw ? sweep : -sweep;
}

void arc_bounds(Vec2 s, Vec2 e, Vec2 c, double sweep_rad, Vec2& lo, Vec2& hi) {
  lo = {std::min(s.a, e.a), std::min(s.b, e.b)};
  hi = {std::max(s.a, e.a), std::max(s.b, e.b)};
  const double r = std::hypot(s.a - c.a, s.b - c.b);
  const double t0 = std::atan2(s.b - c.b, s.a - c.a);
  const double span = std::fabs(sweep_rad);
  for (int q = 0; q < 4; ++q) {
    const double angle = q * (std::numbers::pi / 2);
    // Angle travelled from the start to this extreme, in the direction of motion.
    double travel = sweep_rad >= 0 ? angle - t0 : t0 - angle;
    travel = std::fmod(travel, kTwoPi);
    if (travel < 0) travel += kTwoPi;
    if (span >= kTwoPi || travel <= span) {
      const Vec2 p{c.a + r * std::cos(angle), c.b + r * std::sin(angle)};
      lo = {std::min(lo.a, p.a), std::min(lo.b, p.b)};
      hi = {std::max(hi.a, p.a), std::max(hi.b, p.b)};
    }
  }
}

}  // namespace cncore::interp
