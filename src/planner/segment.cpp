#include "planner/segment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace cncore::planner {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTiny = 1e-12;
// Contour tolerance for curved shapes through the post filter in exact-path mode (G61): a
// moving average cannot follow an arc exactly, so P1's 1 µm is used.
constexpr double kExactPathArcTolMm = 1e-3;

std::uint32_t ceil_cycles(double x) {
  // Rounded up, but 84.0000000001 from rounding noise stays 84.
  return static_cast<std::uint32_t>(std::max(1.0, std::ceil(x - 1e-9)));
}

// Largest v with (h/ρ)·v² + (d/T)·v ≤ a (normal + tangential ramp of one axis); stable form
// v = 2a / (b + √(b² + 4·(h/ρ)·a)), b = d/T, valid for h = 0 too.
double axis_accel_speed(double a, double d, double h_over_rho, double t) {
  const double b = d / t;
  // Lines (h = 0): √(b²) = b exactly in IEEE arithmetic, so 2a / 2b = a / b bit for bit; the
  // square root is skipped (segment construction is the per-block cost of fine programs).
  if (h_over_rho == 0) return b > 0 ? a / b : kInf;
  const double den = b + std::sqrt(b * b + 4 * h_over_rho * a);
  return den > 0 ? 2 * a / den : kInf;
}

}  // namespace

Limits make_limits(const MachineConfig& m, bool bound_resultant) {
  Limits l;
  const double tau = m.period_s;
  l.period_s = tau;
  const double vmax_mm_s = m.max_feed_mm_min / 60.0;
  // T = ceil(Vmax / (Amax·τ)): a step 0 → Vmax through the moving average ramps at ≤ Amax.
  l.t_cycles = ceil_cycles(vmax_mm_s / (m.max_accel_mm_s2 * tau));
  // Second stage: its output's jerk is (a1[t] − a1[t−T2])/T2 with the first stage's
  // acceleration a1 ∈ [−Amax, Amax]; a short move flips a1 from +Amax to −Amax, so the jerk
  // can reach 2·Amax/T2 and T2 = ceil(2·Amax / (Jmax·τ)) keeps it ≤ Jmax (spec 01 writes
  // Amax/T2, which holds only while the acceleration does not change sign within T2).
  l.t2_cycles =
      m.max_jerk_mm_s3 > 0 ? ceil_cycles(2 * m.max_accel_mm_s2 / (m.max_jerk_mm_s3 * tau)) : 1;
  l.post_cycles =
      m.post_filter_s > 0 ? static_cast<std::uint32_t>(std::lround(m.post_filter_s / tau)) : 0;
  l.vmax_pc = vmax_mm_s * tau;
  l.amax_pc2 = m.max_accel_mm_s2 * tau * tau;
  // Rapids share T (computed from the max feed), so a step to the rapid rate would ramp faster
  // than Amax if the rate exceeded Amax·T·τ: the rapid speed is held to that.
  l.rapid_pc = std::min(m.rapid_mm_min / 60.0 * tau, l.amax_pc2 * l.t_cycles);
  l.contour_tolerance_mm = m.contour_tolerance_mm;
  l.bound_resultant = bound_resultant;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    const AxisConfig& a = m.axes[i];
    l.axis_on[i] = a.enabled;
    l.axis_vmax_pc[i] = a.max_speed_mm_min / 60.0 * tau;
    l.axis_amax_pc2[i] = a.max_accel_mm_s2 * tau * tau;
  }
  return l;
}

AxisVec Segment::direction_at(double phi) const {
  AxisVec d = (1.0 / length_mm) * (end - start);
  if (arc) {
    // dH/dφ · Φ/L (the arc is parametrised proportionally to its length).
    const double f = sweep_rad > 0 ? phi / sweep_rad : 0;
    const double r = r0 + (r1 - r0) * f;
    const double dr = (r1 - r0) / sweep_rad;
    const Vec3 c{std::cos(phi), std::sin(phi), 0};
    const Vec3 dh =
        (r * -c.y + dr * c.x) * e1 + (r * c.x + dr * c.y) * e2 + (rise_mm / sweep_rad) * n;
    d.set_xyz((sweep_rad / length_mm) * dh);
  }
  return d;
}

// Size: every field of a motion segment (geometry, shape passing speed Vb, per-axis limits,
// post-filter bound) with the formula beside the field it sets, spec 01's order.
Segment make_motion_segment(const Block& b, const Limits& lim) {
  Segment s;
  s.kind = ItemKind::kMotion;
  s.line = b.line;
  s.start = b.start;
  s.end = b.end;
  s.rapid = b.kind == BlockKind::kRapid;
  if (b.kind != BlockKind::kArc) {
    s.e1 = b.first_piece_dir;
    s.e2 = b.last_piece_dir;
  }
  s.mode = b.path_mode;
  s.tol_mm = b.path_mode == PathMode::kBlend
                 ? (b.tolerance_mm >= 0 ? b.tolerance_mm : lim.contour_tolerance_mm)
                 : 0.0;
  s.feed_pc = s.rapid ? lim.rapid_pc : b.feed_mm_min / 60.0 * lim.period_s;
  s.correction = b.correction;
  s.override_fixed = b.override_fixed;

  const AxisVec delta = b.end - b.start;
  const double xyz_len = norm(delta.xyz());
  // (Rotary-only moves: their length in degrees; the root only where it is used.)
  auto rot_len = [&] {
    return std::sqrt(delta[kA] * delta[kA] + delta[kB] * delta[kB] + delta[kC] * delta[kC]);
  };

  if (b.kind == BlockKind::kArc) {
    const double nn = norm(b.normal);
    const Vec3 n = nn > kTiny ? (1.0 / nn) * b.normal : Vec3{0, 0, 1};
    const Vec3 v0 = b.start.xyz() - b.center;
    const Vec3 c = b.center + dot(v0, n) * n;  // centre in the plane of the start point
    const Vec3 v0p = b.start.xyz() - c;
    const double r0 = norm(v0p);
    if (r0 > 1e-9) {
      const Vec3 e1 = (1.0 / r0) * v0p;
      const Vec3 e2 = cross(n, e1);
      const Vec3 v1 = b.end.xyz() - c;
      const double rise = dot(v1, n);
      const Vec3 v1p = v1 - rise * n;
      const double r1 = norm(v1p);
      double phi = std::atan2(dot(v1p, e2), dot(v1p, e1));
      if (phi < 0) phi += 2 * std::numbers::pi;
      // End on the start radius line: a full turn (a zero-sweep arc is not an arc).
      if (phi * std::max(r0, r1) < 1e-9) phi = 2 * std::numbers::pi;
      phi += 2 * std::numbers::pi * b.turns;
      s.arc = true;
      s.center = c;
      s.e1 = e1;
      s.e2 = e2;
      s.n = n;
      s.r0 = r0;
      s.r1 = r1;
      s.sweep_rad = phi;
      s.rise_mm = rise;
      const double rm = 0.5 * (r0 + r1);
      s.length_mm = std::sqrt(rm * phi * rm * phi + rise * rise);
      const double p = rise / phi;
      s.rho_mm = (rm * rm + p * p) / rm;
    }
  }
  if (!s.arc) s.length_mm = xyz_len > kTiny ? xyz_len : rot_len();
  if (s.length_mm <= kTiny) {
    s.length_mm = 0;
    return s;
  }

  // Shape passing speed Vb.
  double vb = s.rapid ? lim.rapid_pc : lim.vmax_pc;
  const double t = lim.t_cycles;
  if (s.arc) {
    const double a = lim.amax_pc2;
    // Spec 01: Vb = √(R·Amax) with the arc's radius R (for a helix R < ρ, the radius of
    // curvature, so the normal acceleration v²/ρ stays below Amax with room).
    const double rho = 0.5 * (s.r0 + s.r1);
    if (!lim.bound_resultant) {
      // v²/R ≤ Amax, with 1/T kept for the ramp inside the arc: while the speed changes by
      // up to v/T per cycle, consecutive chords differ by that much and the direction change
      // measured over two chords reads up to (1 + 1/T)·v²/R.
      vb = std::min(vb, std::sqrt(rho * a / (1 + 1 / t)));
    } else {
      // (v²/ρ)² + (v/T)² ≤ Amax²: normal plus the filter's tangential ramp (≤ Vb/T per cycle).
      const double it2 = 1 / (t * t);
      const double x = 0.5 * rho * rho * (-it2 + std::sqrt(it2 * it2 + 4 * a * a / (rho * rho)));
      vb = std::min(vb, std::sqrt(x));
    }
  }
  // Per-axis limits: speed v·|d_i| ≤ vmax_i; acceleration (h_i/ρ)·v² + (|d_i|/T)·v ≤ a_i,
  // h_i the share of axis i in the arc's plane (normal acceleration) — the slowest axis decides.
  const double rmax = std::max(s.r0, s.r1);
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim.axis_on[i]) continue;
    double d = std::abs(delta[i]) / s.length_mm;
    double h = 0;
    if (s.arc && i < 3) {
      const double e1i = component(s.e1, i), e2i = component(s.e2, i), ni = component(s.n, i);
      h = std::hypot(e1i, e2i);
      d = (rmax * h + std::abs(s.r1 - s.r0) / s.sweep_rad * h +
           std::abs(s.rise_mm / s.sweep_rad * ni)) *
          s.sweep_rad / s.length_mm;
    }
    if (lim.axis_vmax_pc[i] > 0 && d > kTiny) vb = std::min(vb, lim.axis_vmax_pc[i] / d);
    if (lim.axis_amax_pc2[i] > 0 && (d > kTiny || h > kTiny)) {
      vb = std::min(vb, axis_accel_speed(lim.axis_amax_pc2[i], d, s.arc ? h / s.rho_mm : 0, t));
    }
  }
  // Post filter on an arc: a moving average over Tp cycles (arc length ≤ v·Tp) pulls the point
  // inside by ρ·(1 − sin(x)/x) ≈ (v·Tp)²/(24ρ), x the half angle; keep it ≤ tolerance.
  if (s.arc && lim.post_filter()) {
    const double tol = s.tol_mm > 0 ? s.tol_mm : kExactPathArcTolMm;
    vb = std::min(vb, std::sqrt(24 * s.rho_mm * tol) / lim.post_cycles);
  }
  s.vb_pc = vb;
  return s;
}

double corner_rounding_mm(double v_pc, double sin_theta, std::uint32_t tp_cycles) {
  return v_pc * (tp_cycles + 1) * sin_theta / 8;
}

double turn_speed_pc(const AxisVec& e, const AxisVec& s, const Limits& lim, double curvature) {
  double v = kInf;
  // Path corner: the velocity turns from v·E to v·S within one cycle, |Δv| = v·|S − E| =
  // 2·v·sin(θ/2) ≤ Amax·τ  ⇒  V = Amax·τ / |S − E| (per-cycle units: Amax·τ²). Next to an arc
  // the chords also turn by up to v·κ (κ = 1/R of the arcs on both sides) in that cycle:
  // v·(|S − E| + v·κ) ≤ Amax, solved as 2A / (d + √(d² + 4Aκ)).
  auto limit = [curvature](double a, double d) {
    if (curvature == 0) return d > 0 ? a / d : kInf;  // = 2a / (d + √(d²)) exactly, see above
    const double den = d + std::sqrt(d * d + 4 * a * curvature);
    return den > 0 ? 2 * a / den : kInf;
  };
  // |S − E|² well below kTiny² means |S − E| ≤ kTiny: straight joints (most joints of fine
  // programs) skip the square root; the comparison on |S − E| decides as before otherwise.
  const Vec3 dse = s.xyz() - e.xyz();
  const double turn2 = dot(dse, dse);
  const double turn = turn2 < 0.5 * kTiny * kTiny ? 0.0 : std::sqrt(turn2);
  if (turn > kTiny) v = std::min(v, limit(lim.amax_pc2, turn));
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    const double di = std::abs(s[i] - e[i]);
    if (lim.axis_on[i] && lim.axis_amax_pc2[i] > 0 && di > kTiny) {
      v = std::min(v, limit(lim.axis_amax_pc2[i], di));
    }
  }
  return v;
}

double joint_speed_pc(const Segment& a, const Segment& b, const Limits& lim,
                      bool slow_corner_stops) {
  AxisVec e, s;
  return joint_speed_pc(a, b, lim, slow_corner_stops, e, s);
}

double joint_speed_pc(const Segment& a, const Segment& b, const Limits& lim, bool slow_corner_stops,
                      AxisVec& a_end, AxisVec& b_start) {
  a_end = a.end_direction();
  b_start = b.start_direction();
  const AxisVec& e = a_end;
  const AxisVec& s = b_start;
  const double kappa = (a.arc ? 1 / a.rho_mm : 0.0) + (b.arc ? 1 / b.rho_mm : 0.0);
  double v = std::min({a.vb_pc, b.vb_pc, turn_speed_pc(e, s, lim, kappa)});
  // A merged line's direction differs from its end pieces' by up to its tolerance over its
  // length, and the corner it makes can turn less than the programmed one: the corner of the
  // pieces too (found: a 3.48° corner of line-contouring-xz crossed at 33.12 mm/s, its Vg 32.94).
  const Vec3 a_last = a.last_piece_dir(), b_first = b.first_piece_dir();
  const bool piece_a = a_last != Vec3{}, piece_b = b_first != Vec3{};
  if (piece_a || piece_b) {
    AxisVec pe = e, ps = s;
    if (piece_a) pe.set_xyz(a_last);
    if (piece_b) ps.set_xyz(b_first);
    v = std::min(v, turn_speed_pc(pe, ps, lim, kappa));
  }
  const double turn = norm(s.xyz() - e.xyz());
  if (lim.post_filter() && turn > 1e-9) {
    const double tol = std::min(a.tol_mm, b.tol_mm);
    const double sin_theta = norm(cross(e.xyz(), s.xyz()));
    if (tol <= 0) {
      v = 0;  // exact path: stop at the corner so that the filter cannot round it
    } else if (sin_theta > kTiny) {
      // e = v·(Tp + 1)·sin θ / 8 ≤ 0.9·tol (10 % kept for the discrete rounding of the crossing).
      v = std::min(v, 0.9 * 8 * tol / ((lim.post_cycles + 1) * sin_theta));
    }
  }
  if (!slow_corner_stops) return std::max(0.0, v);
  // With the moving-average acc/dec a slow corner costs more than a stop. Passing at Vg, the
  // commanded position crawls through the range Vg·T and on until the filtered tool has passed
  // the joint (the mean of the last T positions reaches it after T + (T−1)/2 cycles): about
  // 1.5·T·(1 − Vg/W) cycles lost against the speed W reached around the corner. A stop loses T
  // cycles (the filter empties). So below W/3 the stop is faster, and it keeps every limit.
  // W is at most the blocks' Vb and feed, and L/T on a block of length L (the filtered speed of
  // a move of L shorter than a ramp peaks at L/T): on tiny segments one crawl passes many
  // corners, and stopping at each would lose T every time.
  const auto t = static_cast<double>(lim.t_cycles);
  const double w =
      std::min({a.vb_pc, b.vb_pc, a.feed_pc, b.feed_pc, a.length_mm / t, b.length_mm / t});
  if (v < w / 3) v = 0;
  return std::max(0.0, v);
}

}  // namespace cncore::planner
