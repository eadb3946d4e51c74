// The braking bounds of the cycle: the keys' closed forms, the feed bound at the override level,
// the plain reference walk the tests compare with, and braking on an arc with what the speed
// leaves of the axis budget.
//
// 10. Braking on an arc with what the speed leaves. On an arc whose r was fixed for its top speed
//    (2.), the braking bounds (3.) decelerate at r·A0 = √(g² − a_n,top²) at every speed, where
//    a(v) = min(A_c, √(g'² − (v²/ρ)²)) is allowed (A_c = min(A0, the linear axes' share);
//    arc_time braked at 0.31·A0 all the way down from 139 mm/s). While the tool is on
//    such an arc (no filter, the step before also on it), let e be the end of the arc before its
//    tail zone (7.), or the first entry of a cap not yet active if that is earlier, and W the
//    lowest braking bound of the keys at σ(e) (3.; the geometric and lattice keys, and the feed
//    keys of the override level separately). Every cap not yet active starts at or after e, so
//    reaching e at ≤ W and following the keys from there meets all of them. Back from e, with
//    q = v², dq/dp = −2·a(√q) gives the largest q at p from which a(v) still reaches W at e:
//        Q(p) = W² + 2·A_c·(e − p) up to q* = ρ·√(g'² − A_c²) (where a stops being A_c), then
//        Q = ρg'·sin(θ), θ = θ* + 2·(e − p − d*)/ρ (d/dp of ρg'·sin θ is −2g'·cos θ = −2·a),
//        ρg' once θ ≥ π/2; Q = W² past e.
//    The bound T is the step x with x² = Q(s + x) (Newton from above on the convex
//    x² − Q(s + x), accepted only below the root). A step x_k ≤ T lands at s_{k+1} with
//    x_k² ≤ Q(s_{k+1}), and the next bound has x_{k+1}² = Q(s_{k+1} + x_{k+1}), so
//    x_k² − x_{k+1}² ≤ Q(s_{k+1}) − Q(s_{k+1} + x_{k+1}) ≤ 2·x_{k+1}·a(x_{k+1}) (a grows as q
//    falls, and Q ≥ x_{k+1}² over that stretch): x_k − x_{k+1} ≤ a(x_{k+1}), the same argument as
//    3. (ii) with a(v) for r·A0; a step landing past e is ≤ W, which the keys allow. Each braking
//    bound b then becomes max(b, T): both are bounds from which the next cycle's bound is at most
//    one allowed deceleration lower, so their maximum is too.
//    a is taken at the later (smaller) step while the pair's normal acceleration is up to
//    u1²/ρ: with d ≤ a(u2), a(u2)² + (u1²/ρ)² − (u2²/ρ)² ≤ g'² + 4·d·u1³/ρ² ≤ g'² + 2g'²φ +
//    12g²φ² (φ = u1/ρ ≤ V_b/ρ, d·u1²/ρ ≤ g'²/2 + 3g²φ), so g'² = g²·min(0.98², 1 − 2.5φ −
//    12φ²) keeps the pair within g (the 2 % of 5. for the chords at small φ).
//    The stop's bounds are not relaxed; in real distance they take the lowest r up to the stop
//    (3.), so a state above the keys' bounds meets no lower r coming into the step's reach there
//    (with the reach's r: a short arc before the window's end, 0.63 → 0.19 µm/cycle² at once).
#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/accel_limited.hpp"
#include "motion/accel_limited_common.hpp"

namespace cncore::motion {

using namespace accel_limited_common;  // NOLINT(google-build-using-namespace)
using planner::ItemKind;
using planner::Segment;

double AccelLimitedAccDec::brake(double k, double sigma_p) const {
  return std::sqrt(std::max(0.0, a0_ * a0_ + k - 2 * a0_ * sigma_p)) - a0_;
}

double AccelLimitedAccDec::lattice(double k, double sigma_p) const {
  return std::max(0.0, std::sqrt(std::max(0.0, k - 2 * a0_ * sigma_p)) - 0.5 * a0_);
}

std::size_t AccelLimitedAccDec::level_of(double or_ratio) const {
  if (or_ratio != level_or_) {
    level_or_ = or_ratio;
    level_ =
        std::min(levels_ - 1, static_cast<std::size_t>(std::floor(or_ratio / level_step_ + 1e-9)));
  }
  return level_;
}

double AccelLimitedAccDec::feed_bound(double or_ratio, double sigma_p) const {
  // min(OR·F of the active feed caps, the braking bound of the level's feed keys): the braking
  // bound is ≥ OR·F, and left out, when its root's argument is ≥ (OR·F + A0)² (see step()).
  const double active = or_ratio * active_feed_.min();
  const double k = key_feed_.min(level_of(or_ratio));
  if (k == kInf) return active;
  if (active > 0 && active < kInf && a0_ * a0_ + k - 2 * a0_ * sigma_p >= above(active + a0_)) {
    return active;
  }
  return std::min(active, brake(k, sigma_p));
}

double AccelLimitedAccDec::arc_brake_step(std::size_t slot, const Segment& arc, double or_ratio,
                                          bool feed, ArcTarget& at) const {
  // 9. The caps ahead, all starting at or after e: the target speed W at e (their braking
  // bounds there, 3.), then the arc's braking curve back from e.
  const double e = std::min(arc.end_mm() - tail_mm_[slot], entry_.min());
  if (!(e > pos_mm_)) return 0;
  const double sigma_e = sigma0_[slot] + seg_sigma(slot, e - arc.s0_mm);
  double w = kInf;
  if (feed) {
    if (const double k = key_feed_.min(level_of(or_ratio)); k != kInf) w = brake(k, sigma_e);
  } else {
    if (const double k = key_geo_.min(); k != kInf) w = std::min(w, brake(k, sigma_e));
    if (const double k = key_lattice_.min(); k != kInf) w = std::min(w, lattice(k, sigma_e));
  }
  at = {e, sigma_e, w};
  const double rho = arc_rho_[slot];
  // g'² = g²·min(0.98², 1 − 2.5·φ − 12·φ²), φ = V_b/ρ the arc's largest angle per cycle (10.).
  const double phi = vcap_[slot] / rho;
  const double g = arc_g_[slot] * std::sqrt(std::min(kRecoverShare * kRecoverShare,
                                                     1 - 2.5 * phi - 12 * phi * phi));
  const double q_top = rho * g;  // v² where the normal acceleration alone is g'
  if (!(g > 0) || w == kInf || w * w >= q_top) return 0;
  // a(q) = min(A_c, √(g'² − (q/ρ)²)): A_c below q*, the circle law above.
  const double a_c = std::min(a0_, lin_r_[slot] * a0_);
  const double q_star = rho * std::sqrt(std::max(0.0, g * g - a_c * a_c));
  const double w2 = w * w;
  const double d_star = w2 < q_star ? (q_star - w2) / (2 * a_c) : 0.0;
  const double theta0 = std::asin(std::max(w2, q_star) / q_top);
  constexpr double kQuarter = 1.5707963267948966;
  // Q(p): the largest v² at p from which braking at a(v) reaches ≤ W at e; dQ/dp = −2·a.
  auto q_at = [&](double p, double& slope) {
    const double d = e - p;
    if (d <= 0) {
      slope = 0;
      return w2;
    }
    if (d <= d_star) {
      slope = -2 * a_c;
      return w2 + 2 * a_c * d;
    }
    const double th = theta0 + 2 * (d - d_star) / rho;
    if (th >= kQuarter) {
      slope = 0;
      return q_top;
    }
    slope = -2 * g * std::cos(th);
    return q_top * std::sin(th);
  };
  // The step x with x² = Q(pos + x): f(x) = x² − Q(pos + x) is increasing, and convex up to
  // e − pos (Q is concave there); beyond it Q = W², so the root is W when e − pos < W.
  if (e - pos_mm_ < w) return w;
  // Newton from a point with f ≥ 0 inside [0, e − pos] (f(e − pos) = (e − pos)² − W² ≥ 0, and
  // f(√Q(pos)) ≥ 0) stays above the root there; the result is accepted only with f ≤ 0.
  double slope = 0;
  double x = std::min(e - pos_mm_, std::sqrt(q_at(pos_mm_, slope)));
  for (int it = 0; it < 30; ++it) {
    const double f = x * x - q_at(pos_mm_ + x, slope);
    if (!(f > 0)) break;
    const double dx = f / (2 * x - slope);
    x -= dx;
    if (!(dx > 1e-13 * x)) break;
  }
  x *= 1 - 1e-9;  // just below the root
  return x > 0 && x * x <= q_at(pos_mm_ + x, slope) ? x : 0.0;
}

AccelLimitedAccDec::Bounds AccelLimitedAccDec::bound(double or_ratio, double sigma_p) const {
  auto brake_or_inf = [&](double k) { return k == kInf ? kInf : brake(k, sigma_p); };
  const std::size_t level = level_of(or_ratio);
  const double k_lat = key_lattice_.min();
  const double lat = k_lat == kInf ? kInf : lattice(k_lat, sigma_p);
  const double geo = std::min({active_geo_.min(), brake_or_inf(key_geo_.min()), lat});
  const double feed = std::min(or_ratio * active_feed_.min(), brake_or_inf(key_feed_.min(level)));
  return {geo, feed};
}

double AccelLimitedAccDec::reference_bound(double or_ratio) const {
  // Independent of the trees and of the cap states: every cap decides by position.
  double sigma_p = sigma_total_;
  if (!buf_.empty() && cur_ >= buf_.begin_index() && cur_ < buf_.end_index() &&
      buf_[cur_].kind == ItemKind::kMotion) {
    const Segment& s = buf_[cur_];
    const std::size_t slot = buf_.slot(cur_);
    sigma_p = sigma0_[slot] + seg_sigma(slot, pos_mm_ - s.s0_mm);
  }
  const std::size_t level =
      std::min(levels_ - 1, static_cast<std::size_t>(std::floor(or_ratio / level_step_ + 1e-9)));
  double out = kInf;
  for (std::size_t i = 0; i < caps_.size(); ++i) {
    if (state_[i] == State::kEmpty) continue;  // by id: every live cap once
    const Cap& c = caps_[i];
    if (pos_mm_ >= c.e_mm) continue;
    if (pos_mm_ >= c.entry) {
      out = std::min(out, c.feed ? or_ratio * c.v : c.v);
    } else if (c.lattice) {
      const double h = c.v - 0.5 * a0_;
      const double k = h * h + 2 * a0_ * c.sigma_c;
      out =
          std::min(out, std::max(0.0, std::sqrt(std::max(0.0, k - 2 * a0_ * sigma_p)) - 0.5 * a0_));
    } else {
      const double v = c.feed ? static_cast<double>(level) * level_step_ * c.v : c.v;
      const double k = v * v + 2 * a0_ * c.sigma_c;
      out = std::min(out, std::sqrt(std::max(0.0, a0_ * a0_ + k - 2 * a0_ * sigma_p)) - a0_);
    }
  }
  return out;
}

}  // namespace cncore::motion
