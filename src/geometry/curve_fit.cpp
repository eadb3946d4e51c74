#include "geometry/curve_fit.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cncore::geometry {
namespace {

// Every vertex within tol of the chord p0 pn, projections strictly increasing inside it (the
// sagitta of a line is 0, so the chord rule is ei ≤ tol).
bool fits_line(std::span<const Vec3> p, double tol) {
  const Vec3 a = p.front();
  const Vec3 d = p.back() - a;
  const double len2 = dot(d, d);
  if (!(len2 > 0)) return false;
  double t_prev = 0;
  for (std::size_t i = 1; i + 1 < p.size(); ++i) {
    const Vec3 v = p[i] - a;
    const double t = dot(v, d) / len2;
    if (!(t > t_prev) || !(t < 1)) return false;
    if (norm(v - t * d) > tol) return false;
    t_prev = t;
  }
  return true;
}

// The chord rule at every vertex for the arc (or helix, rising linearly to pn along n) about
// centre c in the plane of p0.
bool check_arc(std::span<const Vec3> p, const Vec3& c, const Vec3& n, const CurveFitLimits& lim,
               CurveFit& out) {
  const Vec3 a = p.front();
  const double r = norm(a - c);
  if (!(r > 0) || !(r <= lim.max_radius_mm)) return false;
  const Vec3 u = (1 / r) * (a - c);
  const Vec3 w = cross(n, u);
  auto angle = [&](const Vec3& v) {
    const Vec3 d = v - c;
    const double phi = std::atan2(dot(d, w), dot(d, u));
    return phi < 0 ? phi + 2 * std::numbers::pi : phi;
  };
  const double sweep = angle(p.back());
  if (!(sweep > 0) || sweep > lim.max_sweep_rad) return false;
  const double rise_per_rad = dot(p.back() - a, n) / sweep;
  double phi_prev = 0, e_prev = 0;
  for (std::size_t i = 1; i < p.size(); ++i) {
    const double phi = i + 1 == p.size() ? sweep : angle(p[i]);
    if (!(phi > phi_prev)) return false;
    const Vec3 on = c + r * (std::cos(phi) * u + std::sin(phi) * w) + (rise_per_rad * phi) * n;
    const double e = norm(p[i] - on);
    // sagitta R·(1 − cos(Δφ/2)) = 2R·sin²(Δφ/4), which keeps its digits at small Δφ
    const double s = std::sin(0.25 * (phi - phi_prev));
    if (2 * r * s * s + std::max(e, e_prev) > lim.tolerance_mm) return false;
    phi_prev = phi;
    e_prev = e;
  }
  out.kind = CurveFit::Kind::kArc;
  out.center = c;
  out.normal = n;
  out.radius_mm = r;
  out.sweep_rad = sweep;
  return true;
}

// The circle through p0, pm and pn (projected along `axis` when it is not zero: a helix about
// it), then the chord rule.
bool fits_circle(std::span<const Vec3> p, const Vec3& axis, const CurveFitLimits& lim,
                 CurveFit& out) {
  const bool helix = dot(axis, axis) > 0;
  const Vec3 a = p.front();
  auto in_plane = [&](Vec3 q) { return helix ? q - dot(q - a, axis) * axis : q; };
  const Vec3 ab = in_plane(p[p.size() / 2]) - a;
  const Vec3 ac = in_plane(p.back()) - a;
  const Vec3 nn = cross(ab, ac);
  const double nn2 = dot(nn, nn);
  // Collinear (to 1e-12 of the product of the sides): no circle.
  if (!(nn2 > 1e-24 * dot(ab, ab) * dot(ac, ac))) return false;
  // Circumcentre: a + (|ac|²·(nn × ab) + |ab|²·(ac × nn)) / (2·|nn|²).
  const Vec3 c = a + (0.5 / nn2) * (dot(ac, ac) * cross(nn, ab) + dot(ab, ab) * cross(ac, nn));
  const Vec3 n = helix ? (dot(nn, axis) > 0 ? axis : -1.0 * axis) : (1 / std::sqrt(nn2)) * nn;
  return check_arc(p, c, n, lim, out);
}

}  // namespace

void CurveFit::end_tangents(const Vec3& p0, const Vec3& pn, Vec3& t0, Vec3& tn) const {
  if (kind == Kind::kLine) {
    t0 = tn = (1 / norm(pn - p0)) * (pn - p0);
    return;
  }
  // d/dφ of c + R·(cos φ·u + sin φ·w) + (rise/Φ)·φ·n: R·(n × radial) + (rise/Φ)·n
  const Vec3 along = (dot(pn - p0, normal) / sweep_rad) * normal;
  auto tangent = [&](const Vec3& p) {
    Vec3 radial = p - center;
    radial = radial - dot(radial, normal) * normal;
    const Vec3 t = (radius_mm / norm(radial)) * cross(normal, radial) + along;
    return (1 / norm(t)) * t;
  };
  t0 = tangent(p0);
  tn = tangent(pn);
}

bool fit_tangent_curve(std::span<const Vec3> p, const Vec3& t0, const CurveFitLimits& limits,
                       CurveFit& out) {
  if (p.size() < 3) return false;
  const Vec3 a = p.front();
  const Vec3 ch = p.back() - a;
  const Vec3 nn = cross(t0, ch);
  const double nn2 = dot(nn, nn);
  if (!(nn2 > 1e-24 * dot(ch, ch))) {  // the chord along t0: a line, if it fits
    if (!(dot(ch, t0) > 0) || !fits_line(p, limits.tolerance_mm)) return false;
    out = CurveFit{};
    return true;
  }
  // Centre on the inward normal n × t0 at the distance R = |ch|² / (2·ch·(n × t0)) that puts
  // pn on the circle.
  const Vec3 n = (1 / std::sqrt(nn2)) * nn;
  const Vec3 inward = cross(n, t0);
  const Vec3 c = a + (dot(ch, ch) / (2 * dot(ch, inward))) * inward;
  return check_arc(p, c, n, limits, out);
}

bool fit_curve(std::span<const Vec3> p, const CurveFitLimits& limits, CurveFit& out) {
  if (p.size() < 3) return false;
  // The arc first: on a short stretch of a curve a line fits too, but its ends turn away from
  // the curve's tangent by half its turn, a corner at each end.
  static constexpr Vec3 kNoAxis{}, kAxes[] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
  if (fits_circle(p, kNoAxis, limits, out)) return true;
  if (fits_line(p, limits.tolerance_mm)) {
    out = CurveFit{};
    return true;
  }
  return std::ranges::any_of(kAxes, [&](const Vec3& e) { return fits_circle(p, e, limits, out); });
}

}  // namespace cncore::geometry
