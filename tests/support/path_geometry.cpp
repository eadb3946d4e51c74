#include "path_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cncore::testing {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

Vec3 unit(Vec3 v) {
  const double l = norm(v);
  return l > 0 ? (1.0 / l) * v : Vec3{};
}

double clamp01(double u) {
  return std::clamp(u, 0.0, 1.0);
}

}  // namespace

AxisVec PathSegment::point_at(double u) const {
  AxisVec p = start + u * (end - start);
  if (arc) {
    const double phi = u * sweep_rad;
    const double r = r0 + (r1 - r0) * u;
    p.set_xyz(center + (r * std::cos(phi)) * e1 + (r * std::sin(phi)) * e2 + (rise_mm * u) * n);
  }
  return p;
}

Vec3 PathSegment::tangent_at(double u) const {
  if (!arc) return unit(end.xyz() - start.xyz());
  const double phi = u * sweep_rad;
  const double r = r0 + (r1 - r0) * u;
  const double dr = (r1 - r0) / sweep_rad;  // dr/dφ
  const Vec3 radial = std::cos(phi) * e1 + std::sin(phi) * e2;
  const Vec3 along = -std::sin(phi) * e1 + std::cos(phi) * e2;
  return unit(dr * radial + r * along + (rise_mm / sweep_rad) * n);
}

double PathSegment::project(const AxisVec& p, double u_min, double& distance_mm) const {
  u_min = clamp01(u_min);
  if (!arc) {
    // Exact projection onto the straight segment over all axes.
    const AxisVec d = end - start;
    const AxisVec q = p - start;
    double dd = 0, qd = 0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      dd += d[i] * d[i];
      qd += q[i] * d[i];
    }
    const double u = dd > 0 ? std::clamp(qd / dd, u_min, 1.0) : 1.0;
    const AxisVec e = p - point_at(u);
    double e2sum = 0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) e2sum += e[i] * e[i];
    distance_mm = std::sqrt(e2sum);
    return u;
  }
  // Arc / helix: minimise f(φ) = |p − H(φ)|² over φ ∈ [u_min·Φ, Φ].
  const Vec3 pv = p.xyz();
  const Vec3 q = pv - center;
  const double phi_lo = u_min * sweep_rad;
  const double phi_hi = sweep_rad;
  const double a0 = std::atan2(dot(q, e2), dot(q, e1));  // in-plane angle, (−π, π]
  const double k_rise = rise_mm / sweep_rad;
  const double k_r = (r1 - r0) / sweep_rad;
  auto f_of = [&](double phi) {
    const double r = r0 + k_r * phi;
    const Vec3 h =
        center + (r * std::cos(phi)) * e1 + (r * std::sin(phi)) * e2 + (k_rise * phi) * n;
    const Vec3 e = pv - h;
    return dot(e, e);
  };
  auto refine = [&](double phi) {
    // Newton on f'(φ) = 0, three steps; the start is within a fraction of a radian.
    for (int it = 0; it < 4; ++it) {
      const double c = std::cos(phi), s = std::sin(phi);
      const double r = r0 + k_r * phi;
      const Vec3 radial = c * e1 + s * e2;
      const Vec3 along = -s * e1 + c * e2;
      const Vec3 h = center + r * radial + (k_rise * phi) * n;
      const Vec3 h1 = k_r * radial + r * along + k_rise * n;
      const Vec3 h2 = (2 * k_r) * along - r * radial;
      const Vec3 e = pv - h;
      const double g = -dot(e, h1);
      const double hess = dot(h1, h1) - dot(e, h2);
      if (!(hess > 0)) break;
      const double step = g / hess;
      phi = std::clamp(phi - step, phi_lo, phi_hi);
      if (std::abs(step) < 1e-15) break;
    }
    return phi;
  };
  // Every turn of a multi-turn arc passes the same points: candidates come in increasing angle
  // and a later one wins only if it is nearer by more than 1e-9 mm, so a tie goes to the next
  // pass, never to a later turn.
  double best_phi = phi_lo;
  double best_d = std::sqrt(std::max(0.0, f_of(phi_lo)));
  auto consider = [&](double phi) {
    const double d = std::sqrt(std::max(0.0, f_of(phi)));
    if (d < best_d - 1e-9) {
      best_d = d;
      best_phi = phi;
    }
  };
  const double m_lo = std::floor((phi_lo - a0) / kTwoPi) - 1;
  const double m_hi = std::ceil((phi_hi - a0) / kTwoPi) + 1;
  for (double m = m_lo; m <= m_hi; m += 1) {
    const double cand = a0 + m * kTwoPi;
    if (cand < phi_lo - 0.5 || cand > phi_hi + 0.5) continue;
    consider(refine(std::clamp(cand, phi_lo, phi_hi)));
  }
  consider(phi_hi);
  const double best_f = best_d * best_d;
  const double u = best_phi / sweep_rad;
  // Other axes (A B C) move linearly with the angle.
  double extra = 0;
  for (std::size_t i = kA; i < kMaxAxes; ++i) {
    const double d = p[i] - (start[i] + u * (end[i] - start[i]));
    extra += d * d;
  }
  distance_mm = std::sqrt(std::max(0.0, best_f) + extra);
  return u;
}

double corner_angle_rad(const PathSegment& a, const PathSegment& b) {
  const Vec3 ta = a.tangent_at(1.0);
  const Vec3 tb = b.tangent_at(0.0);
  if (norm(ta) == 0 || norm(tb) == 0) return 0;
  // atan2 form is accurate for both tiny and near-180° angles.
  return std::atan2(norm(cross(ta, tb)), dot(ta, tb));
}

bool make_segment(const Block& b, std::size_t block_index, PathSegment& out) {
  if (b.kind != BlockKind::kRapid && b.kind != BlockKind::kLine && b.kind != BlockKind::kArc)
    return false;
  out = PathSegment{};
  out.block_index = block_index;
  out.line = b.line;
  out.start = b.start;
  out.end = b.end;
  out.rapid = b.kind == BlockKind::kRapid;
  out.feed_mm_min = b.feed_mm_min;
  if (b.kind == BlockKind::kArc) {
    out.arc = true;
    out.n = unit(b.normal);
    const Vec3 c = b.center;
    Vec3 q0 = b.start.xyz() - c;
    q0 = q0 - dot(q0, out.n) * out.n;
    Vec3 q1 = b.end.xyz() - c;
    q1 = q1 - dot(q1, out.n) * out.n;
    out.center = b.start.xyz() - q0;  // centre in the start point's plane
    out.r0 = norm(q0);
    out.r1 = norm(q1);
    out.e1 = unit(q0);
    out.e2 = cross(out.n, out.e1);
    double phi_end = std::atan2(dot(q1, out.e2), dot(q1, out.e1));
    if (phi_end < 1e-12) phi_end += kTwoPi;  // start == end in the plane: a full circle
    out.sweep_rad = phi_end + kTwoPi * b.turns;
    out.rise_mm = dot(b.end.xyz() - b.start.xyz(), out.n);
    if (out.r0 <= 0) {
      // Degenerate arc (no radius): treat as a straight move.
      out.arc = false;
    } else {
      const double r = 0.5 * (out.r0 + out.r1);
      out.length_mm = std::hypot(r * out.sweep_rad, out.rise_mm);
    }
  }
  if (!out.arc) out.length_mm = norm(b.end.xyz() - b.start.xyz());
  double all_axes = 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) all_axes += std::abs(b.end[i] - b.start[i]);
  return out.arc || all_axes > 1e-12;
}

Path build_path(const std::vector<Block>& blocks) {
  Path path;
  bool have_start = false;
  auto mark_stop = [&](double dwell_s) {
    if (path.segments.empty()) return;
    path.segments.back().stop_after = true;
    path.segments.back().dwell_after_s += dwell_s;
  };
  for (std::size_t bi = 0; bi < blocks.size(); ++bi) {
    const Block& b = blocks[bi];
    if (b.kind == BlockKind::kDwell) {
      mark_stop(b.dwell_s);
      continue;
    }
    if (b.kind == BlockKind::kAux) {
      if (b.aux_waits) mark_stop(0);
      continue;
    }
    if (!have_start) {
      path.start = b.start;
      have_start = true;
    }
    path.end = b.end;
    PathSegment seg;
    const bool moves = make_segment(b, bi, seg);
    if (moves) {
      seg.s0_mm = path.length_mm;
      path.length_mm += seg.length_mm;
      path.segments.push_back(seg);
    }
    if (b.path_mode == PathMode::kExactStop) mark_stop(0);
  }
  if (!path.segments.empty()) path.segments.back().stop_after = true;
  return path;
}

}  // namespace cncore::testing
