#include "bound.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "jerk_bound.hpp"

namespace cncore::bound {

using testing::PathSegment;

double segment_time_s(double length, double v0, double v1, double vc, double a, double d) {
  if (length <= 0) return 0;
  // Envelope e(s) = min(vc, √(v0² + 2as), √(v1² + 2d(L − s))): rising branch up to s*, where it
  // meets the falling one, clamped to [0, L]; the cap cuts the top.
  const double ss = std::clamp((v1 * v1 - v0 * v0 + 2 * d * length) / (2 * (a + d)), 0.0, length);
  const double up_end = std::sqrt(v0 * v0 + 2 * a * ss);               // rising branch at s*
  const double dn_start = std::sqrt(v1 * v1 + 2 * d * (length - ss));  // falling branch at s*
  if (std::min(up_end, dn_start) <= vc) {
    // No cruise: rise from v0 over [0, s*] (or fall there when s* = 0), fall to v1 after.
    double t = 0;
    if (ss > 0) t += (up_end - v0) / a;
    if (ss < length) t += (dn_start - v1) / d;
    return t;
  }
  // Cruise at vc between s1 (rising branch reaches vc) and s2 (falling branch leaves it).
  const double vin = std::min(v0, vc), vout = std::min(v1, vc);
  const double s1 = std::max(0.0, (vc * vc - vin * vin) / (2 * a));
  const double s2 = length - std::max(0.0, (vc * vc - vout * vout) / (2 * d));
  return (vc - vin) / a + std::max(0.0, s2 - s1) / vc + (vc - vout) / d;
}

double segment_time_s(double length, double v0, double v1, double vc, double a) {
  if (length <= 0) return 0;
  vc = std::max(vc, std::max(v0, v1));
  // Peak of the triangle: v_p² − v0² + v_p² − v1² = 2·a·L.
  const double vp = std::min(vc, std::sqrt((2 * a * length + v0 * v0 + v1 * v1) / 2));
  const double d_acc = (vp * vp - v0 * v0) / (2 * a);
  const double d_dec = (vp * vp - v1 * v1) / (2 * a);
  const double cruise = std::max(0.0, length - d_acc - d_dec);
  double t = (vp - v0) / a + (vp - v1) / a;
  if (cruise > 0 && vp > 0) t += cruise / vp;
  return t;
}

void BoundBuilder::add(const Block& b) {
  const std::size_t bi = block_index_++;
  auto stop_here = [&] {
    if (!segs_.empty()) segs_.back().join = 0;
  };
  if (b.kind == BlockKind::kDwell) {
    dwell_s_ += b.dwell_s;
    stop_here();
    return;
  }
  if (b.kind == BlockKind::kAux) {
    if (b.aux_waits) stop_here();
    return;
  }
  PathSegment sg;
  if (!testing::make_segment(b, bi, sg)) {
    if (b.path_mode == PathMode::kExactStop) stop_here();
    return;
  }
  const double amax = lim_.max_accel_mm_s2;
  const double vkind = sg.rapid ? lim_.rapid_mm_s() : lim_.feed_mm_s();
  double cap = vkind;
  if (!sg.rapid && sg.feed_mm_min > 0) cap = std::min(cap, sg.feed_mm_min / 60.0);
  Seg s;
  s.length = sg.length_mm;
  s.cap = cap;
  s.accel = amax;
  s.join = std::numeric_limits<double>::infinity();
  s.line = b.line;
  s.arc = sg.arc;
  const bool rotary_only = sg.length_mm <= 1e-12;
  if (rotary_only) {
    // A move of rotary axes only: its own length (degrees) and the slowest moving axis.
    s.length = 0;
    double cap_t = std::numeric_limits<double>::infinity();
    for (std::size_t i = kA; i < kMaxAxes; ++i) {
      const double d = std::abs(sg.end[i] - sg.start[i]);
      if (d <= 0) continue;
      // Time-optimal for the axis that needs longest; approximate with the largest move.
      if (d > s.length) {
        s.length = d;
        const double va = lim_.axis_speed_mm_min[i] > 0 ? lim_.axis_speed_mm_min[i] / 60 : cap;
        cap_t = std::min(cap, va);
        s.accel = lim_.axis_accel_mm_s2[i] > 0 ? lim_.axis_accel_mm_s2[i] : amax;
      }
    }
    s.cap = cap_t;
  } else if (sg.arc) {
    s.cap = std::min(s.cap, std::sqrt(sg.radius_mm() * amax));
  } else {
    // Per-axis speed by direction: axis i moves at v·|Δ_i|/L.
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      const double d = std::abs(sg.end[i] - sg.start[i]);
      if (d <= 0) continue;
      if (lim_.axis_speed_mm_min[i] > 0)
        s.cap = std::min(s.cap, lim_.axis_speed_mm_min[i] / 60 * sg.length_mm / d);
      // Axis i accelerates at a_t·|Δ_i|/L ≤ A_i (exact on a line).
      if (model_ == Model::kCoupled && lim_.axis_accel_mm_s2[i] > 0)
        s.accel = std::min(s.accel, lim_.axis_accel_mm_s2[i] * sg.length_mm / d);
    }
  }
  // Joint with the previous segment.
  if (!segs_.empty()) {
    auto& pj = segs_.back().join;
    if (rotary_only || prev_rotary_only_) {
      pj = 0;
    } else if (have_prev_) {
      pj = std::min({pj, segs_.back().cap, s.cap});
      const double theta = testing::corner_angle_rad(prev_, sg);
      const double tau = lim_.period_s;
      if (theta > 1e-12) pj = std::min(pj, amax * tau / (2 * std::sin(theta / 2)));
      const Vec3 e = prev_.tangent_at(1.0), st = sg.tangent_at(0.0);
      const double dt[3] = {st.x - e.x, st.y - e.y, st.z - e.z};
      for (std::size_t i = 0; i < 3; ++i) {
        if (lim_.axis_accel_mm_s2[i] > 0 && std::abs(dt[i]) > 1e-12)
          pj = std::min(pj, lim_.axis_accel_mm_s2[i] * tau / std::abs(dt[i]));
      }
    }
  }
  length_mm_ += sg.length_mm;
  if (record_) {
    s.start = {sg.start[kX], sg.start[kY], sg.start[kZ]};
    s.end = {sg.end[kX], sg.end[kY], sg.end[kZ]};
  }
  if (sg.arc && model_ == Model::kCoupled) {
    add_arc_pieces(sg, s);
  } else {
    segs_.push_back(s);
  }
  if (b.path_mode == PathMode::kExactStop) segs_.back().join = 0;
  prev_ = sg;
  have_prev_ = true;
  prev_rotary_only_ = rotary_only;
}

// Lower bound of |f| on [φa, φb] for f with |f'| ≤ 1 (a component of a unit tangent or
// normal of a circle or helix as a function of the angle): min of the ends − (φb − φa)/2; 0
// when f may change sign there. `sign` gets the sign f keeps (0 if unknown).
static double min_abs_on(double fa, double fb, double width, int& sign) {
  const double m = std::min(std::abs(fa), std::abs(fb)) - width / 2;
  const bool same = (fa > 0 && fb > 0) || (fa < 0 && fb < 0);
  if (!same || m <= 0) {
    sign = 0;
    return 0;
  }
  sign = fa > 0 ? 1 : -1;
  return m;
}

void BoundBuilder::add_arc_pieces(const testing::PathSegment& sg, Seg s) {
  // A spiral (start and end radii differ) or an arc moving other axes too: the simple model.
  const double r = sg.radius_mm();
  bool other_axes = false;
  for (std::size_t i = kA; i < kMaxAxes; ++i) other_axes |= sg.end[i] != sg.start[i];
  if (std::abs(sg.r1 - sg.r0) > 1e-9 * std::max(1.0, r) || r <= 0 || sg.sweep_rad <= 0 ||
      other_axes) {
    segs_.push_back(s);
    return;
  }
  // H(φ) = c + r(cos φ e1 + sin φ e2) + h·φ·n, h = rise/Φ, |H'| = ℓ = √(r² + h²):
  // T = (r(−sin φ e1 + cos φ e2) + h n)/ℓ, curvature κ = r/ℓ², N = −(cos φ e1 + sin φ e2).
  // |dT_i/dφ| ≤ r/ℓ ≤ 1 and |dN_i/dφ| ≤ 1, which min_abs_on needs.
  const double h = sg.rise_mm / sg.sweep_rad;
  const double ell = std::hypot(r, h);
  const double kappa = r / (ell * ell);
  const double max_piece = std::numbers::pi / 180;  // 1°
  const auto count = static_cast<std::size_t>(std::ceil(sg.sweep_rad / max_piece));
  const double width = sg.sweep_rad / static_cast<double>(count);
  auto comp = [&](const Vec3& v, std::size_t i) { return i == 0 ? v.x : (i == 1 ? v.y : v.z); };
  auto tangent = [&](double phi) {
    return (1 / ell) * (r * (-std::sin(phi) * sg.e1 + std::cos(phi) * sg.e2) + h * sg.n);
  };
  auto normal = [&](double phi) { return -1.0 * (std::cos(phi) * sg.e1 + std::sin(phi) * sg.e2); };
  const double piece_len = sg.length_mm / static_cast<double>(count);
  for (std::size_t k = 0; k < count; ++k) {
    const double pa = width * static_cast<double>(k), pb = pa + width;
    const Vec3 ta = tangent(pa), tb = tangent(pb), na = normal(pa), nb = normal(pb);
    Piece pc;
    pc.kappa = kappa;
    for (std::size_t i = 0; i < 3; ++i) {
      const double ai = lim_.axis_accel_mm_s2[i];
      if (ai <= 0) continue;
      int st = 0, sn = 0;
      const double tmin = min_abs_on(comp(ta, i), comp(tb, i), width, st);
      const double nmin = min_abs_on(comp(na, i), comp(nb, i), width, sn);
      if (st == 0 || sn == 0) continue;  // a sign may change: leave the axis out (optimistic)
      // a_i = a_t·T_i + v²κ·N_i: accelerating, the axis with T_i·N_i > 0 adds both parts;
      // braking (a_t < 0), the axis with T_i·N_i < 0 does.
      (st == sn ? pc.acc[i] : pc.brake[i]) = {ai, nmin, tmin};
    }
    Seg piece = s;
    piece.length = piece_len;
    piece.piece = static_cast<std::uint32_t>(pieces_.size());
    piece.continues = k + 1 < count;
    if (piece.continues) piece.join = std::numeric_limits<double>::infinity();
    pieces_.push_back(pc);
    segs_.push_back(piece);
  }
}

double BoundBuilder::accel_at(const Seg& s, double v, bool brake) const {
  if (s.piece == kNoPiece) return s.accel;
  const Piece& pc = pieces_[s.piece];
  const double an = v * v * pc.kappa;
  double a = s.accel;
  if (lim_.max_resultant_accel_mm_s2 > 0) {
    const double ar = lim_.max_resultant_accel_mm_s2;
    a = std::min(a, std::sqrt(std::max(0.0, ar * ar - an * an)));
  }
  for (const AxisTerm& t : brake ? pc.brake : pc.acc) {
    if (t.t > 0) a = std::min(a, (t.a - an * t.n) / t.t);
  }
  // Never exactly 0 (a speed that leaves no tangential acceleration holds; tiny is optimistic).
  return std::max(a, 1e-9 * s.accel);
}

std::vector<double> BoundBuilder::node_speeds(const std::vector<Seg>& segs) const {
  const std::size_t n = segs.size();
  // Node speeds: u[0] = 0 (start), u[k+1] = joint at the end of segment k.
  std::vector<double> u(n + 1);
  u[0] = 0;
  for (std::size_t k = 0; k < n; ++k) u[k + 1] = segs[k].join;
  // Forward pass: reachable from the previous node by accelerating along segment k.
  // (ā evaluated at the entry speed bounds the whole piece: see bound.hpp.)
  for (std::size_t k = 0; k < n; ++k) {
    const Seg& s = segs[k];
    const double a = accel_at(s, u[k], false);
    u[k + 1] = std::min({u[k + 1], s.cap, std::sqrt(u[k] * u[k] + 2 * a * s.length)});
    if (k + 1 < n) u[k + 1] = std::min(u[k + 1], segs[k + 1].cap);
  }
  // Backward pass: able to brake to the next node.
  for (std::size_t k = n; k-- > 0;) {
    const Seg& s = segs[k];
    const double d = accel_at(s, u[k + 1], true);
    u[k] = std::min(u[k], std::sqrt(u[k + 1] * u[k + 1] + 2 * d * s.length));
  }
  return u;
}

std::vector<EnvelopePiece> BoundBuilder::envelope(const std::vector<Seg>& segs,
                                                  const std::vector<double>& u) const {
  std::vector<EnvelopePiece> e;
  e.reserve(segs.size());
  for (std::size_t k = 0; k < segs.size(); ++k) {
    const Seg& s = segs[k];
    const bool line = s.piece == kNoPiece;
    e.push_back({s.length, s.cap, u[k], u[k + 1], line ? s.accel : accel_at(s, u[k], false),
                 line ? s.accel : accel_at(s, u[k + 1], true)});
  }
  return e;
}

double BoundBuilder::jerk_motion_time() const {
  double amax = lim_.max_accel_mm_s2;
  for (const Seg& s : segs_) amax = std::max(amax, s.accel);  // a rotary-only move's own
  // The jerk stage spans T2 = ⌈2·Amax/(Jmax·τ)⌉ cycles whatever a segment's own acceleration:
  // a rotary-only move accelerating faster than Amax changes its acceleration faster too.
  const double jerk = lim_.max_jerk_mm_s3 * amax / lim_.max_accel_mm_s2;
  const std::vector<EnvelopePiece> first = envelope(segs_, node_speeds(segs_));
  const std::vector<PeakCap> caps = peak_caps(first, amax, jerk);
  const double plain = jerk_motion_time_s(first, amax, jerk);
  if (caps.empty()) return plain;
  // The segments cut at the peaks, each cut a joint capped at the peak's speed; the passes
  // again with those caps.
  std::vector<Seg> cut;
  cut.reserve(segs_.size() + caps.size());
  double s0 = 0;
  std::size_t c = 0;
  for (const Seg& sg : segs_) {
    Seg rest = sg;
    double at = s0;
    const double end = s0 + sg.length;
    for (; c < caps.size() && caps[c].s_mm < end; ++c) {
      if (caps[c].s_mm <= at) {  // on the joint before
        if (!cut.empty()) cut.back().join = std::min(cut.back().join, caps[c].cap_mm_s);
        continue;
      }
      Seg first_part = rest;
      first_part.length = caps[c].s_mm - at;
      first_part.join = caps[c].cap_mm_s;
      cut.push_back(first_part);
      rest.length -= first_part.length;
      at = caps[c].s_mm;
    }
    cut.push_back(rest);
    s0 = end;
  }
  // Both are lower bounds; either may be the higher (a lower peak also ends the valleys' lag
  // sooner).
  return std::max(plain, jerk_motion_time_s(envelope(cut, node_speeds(cut)), amax, jerk));
}

BoundResult BoundBuilder::finish() {
  BoundResult r;
  r.dwell_s = dwell_s_;
  r.length_mm = length_mm_;
  r.segments = segs_.size();
  const std::size_t n = segs_.size();
  if (n == 0) {
    r.time_s = dwell_s_;
    return r;
  }
  segs_.back().join = 0;
  const std::vector<double> u = node_speeds(segs_);
  if (record_) times_.clear();
  bool merge = false;  // the previous Seg was a piece of the same arc
  for (std::size_t k = 0; k < n; ++k) {
    const Seg& s = segs_[k];
    // Lines (one constant acceleration): the closed form of the first bound, digit for digit.
    const double t = s.piece == kNoPiece
                         ? segment_time_s(s.length, u[k], u[k + 1], s.cap, s.accel)
                         : segment_time_s(s.length, u[k], u[k + 1], s.cap, accel_at(s, u[k], false),
                                          accel_at(s, u[k + 1], true));
    r.motion_time_s += t;
    if (u[k + 1] == 0) ++r.stops;
    if (record_) {
      if (merge) {
        SegmentTime& st = times_.back();
        st.length += s.length;
        st.v_out_mm_s = u[k + 1];
        st.join_cap_mm_s = s.join;
        st.time_s += t;
      } else {
        times_.push_back(
            {s.line, s.arc, s.length, s.cap, u[k], u[k + 1], s.join, t, s.start, s.end});
      }
    }
    merge = s.continues;
  }
  r.accel_motion_time_s = r.motion_time_s;
  if (lim_.max_jerk_mm_s3 > 0) r.motion_time_s = jerk_motion_time();
  r.time_s = r.motion_time_s + r.dwell_s;
  return r;
}

BoundResult optimal_profile(const std::vector<Block>& blocks, const testing::Limits& limits,
                            Model model) {
  BoundBuilder b(limits, model);
  for (const auto& bl : blocks) b.add(bl);
  return b.finish();
}

double optimal_time_s(const std::vector<Block>& blocks, const testing::Limits& limits,
                      Model model) {
  return optimal_profile(blocks, limits, model).time_s;
}

}  // namespace cncore::bound
