#include "io/programmed_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace cncore::io {

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

}  // namespace

ProgrammedMove::ProgrammedMove(const Block& b)
    : arc_(b.kind == BlockKind::kArc), start_(b.start.xyz()), end_(b.end.xyz()) {
  if (arc_) {
    n_ = unit_or_zero(b.normal);
    Vec3 rs = start_ - b.center;
    rs = rs - dot(rs, n_) * n_;
    centre_ = start_ - rs;  // the centre in the start's plane
    radius_mm_arc_ = norm(rs);
    arc_ = radius_mm_arc_ > 0 && norm(n_) > 0;
  }
  if (!arc_) {
    const Vec3 d = end_ - start_;
    length_mm_ = norm(d);
    dir_ = unit_or_zero(d);
    middle_ = start_ + 0.5 * d;
    radius_mm_ = 0.5 * length_mm_;
    return;
  }
  e1_ = (1 / radius_mm_arc_) * (start_ - centre_);
  e2_ = cross(n_, e1_);
  rise_mm_ = dot(end_ - start_, n_);
  // Sweep counter-clockwise about n from the start to the end, in (0, 2π], plus the turns.
  const Vec3 re = end_ - centre_ - rise_mm_ * n_;
  double a = std::atan2(dot(re, e2_), dot(re, e1_));
  if (a <= 1e-12) a += kTwoPi;
  sweep_rad_ = a + kTwoPi * b.turns;
  // Helix length: the arc unrolled, √((r·φ)² + h²).
  length_mm_ = std::hypot(radius_mm_arc_ * sweep_rad_, rise_mm_);
  middle_ = centre_ + 0.5 * rise_mm_ * n_;
  radius_mm_ = std::hypot(radius_mm_arc_, 0.5 * rise_mm_);
}

ProgrammedMove::Nearest ProgrammedMove::nearest(Vec3 p) const {
  if (!arc_) {
    const double u = std::clamp(dot(p - start_, dir_), 0.0, length_mm_);
    return {norm(p - (start_ + u * dir_)), u};
  }
  // p in the arc's frame: (a, b) in its plane, z along the normal. The point at angle θ is
  // (r·cos θ, r·sin θ, h·θ/φ); the nearest lies at p's own angle θp (+ whole turns) on a
  // circle (and nearly so on a helix of small pitch), or at an end.
  const Vec3 q = p - centre_;
  const double a = dot(q, e1_), b = dot(q, e2_), z = dot(q, n_);
  const double r = radius_mm_arc_;
  const double rise_per_rad = rise_mm_ / sweep_rad_;
  Nearest best{std::numeric_limits<double>::infinity(), 0};
  auto consider = [&](double theta) {
    const double dx = a - r * std::cos(theta), dy = b - r * std::sin(theta);
    const double dz = z - rise_per_rad * theta;
    const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (d < best.distance_mm) best = {d, theta / sweep_rad_ * length_mm_};
  };
  consider(0);
  consider(sweep_rad_);
  double theta = std::atan2(b, a);
  if (theta < 0) theta += kTwoPi;
  for (; theta <= sweep_rad_; theta += kTwoPi) consider(theta);
  return best;
}

}  // namespace cncore::io
