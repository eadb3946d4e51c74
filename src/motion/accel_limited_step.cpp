// The motion cycle of the acceleration-limited type: one step per interpolation period, the
// minimum of every bound (4. in accel_limited.cpp), then the jerk stage.
#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/accel_limited.hpp"
#include "motion/accel_limited_common.hpp"

namespace cncore::motion {

using namespace accel_limited_common;  // NOLINT(google-build-using-namespace)
using planner::ItemKind;
using planner::MinTree;
using planner::Segment;

// Size: one minimum over every bound of the cycle (4.), built in the order of the derivation.
// The terms share the cycle's state (the tool's item, the reach and its r, σ at the tool, the
// running minimum below which a costly bound is skipped); split up, a dozen of these would be
// passed by reference through the real-time path, and the skip order would be harder to see.
void AccelLimitedAccDec::step(const CycleInput& in) {
  advance_current();
  if (!held_cycle_) {
    if (lag_ > 0) {
      recent_[recent_pos_] = step_;  // (6.: the steps the filter may still hold)
      recent_pos_ = recent_pos_ + 1 == recent_.size() ? 0 : recent_pos_ + 1;
    }
    if (late_hold_) {
      // A held late block (6.) is released once the tool has been at rest at hold_mm_ for the
      // post filter's length (its output is then hold_mm_ too); until then hold_mm_ is a stop.
      rest_cycles_ = at_rest() ? rest_cycles_ + 1 : 0;
      const std::uint32_t settle = lim_.post_filter() ? lim_.post_cycles : 0;
      if (pos_mm_ >= hold_mm_ && rest_cycles_ > settle) release_hold();
      if (late_hold_ && in.stop_mm > hold_mm_) {
        CycleInput held = in;
        held.stop_mm = hold_mm_;
        held_cycle_ = true;
        step(held);
        held_cycle_ = false;
        return;
      }
    }
  }
  // Caps whose range the tool has entered, then caps it has left.
  while (entry_.min() <= pos_mm_) activate(entry_.argmin());
  // (release_ may hold an active cap's earlier end, ≤ its e: on_segment() extends caps without
  // a tree update; such a cap gets its current end and stays.)
  while (release_.min() <= pos_mm_) {
    const std::size_t g = release_.argmin();
    if (caps_[g].e_mm > pos_mm_) {
      release_.set(g, caps_[g].e_mm);
    } else {
      clear(where_[g]);
    }
  }

  // After a capped corner between lines: the exact limit of the step after the crossing (9.).
  const double after = lag_ == 0 && step_ > 0 ? after_corner() : kInf;

  double sigma_p = sigma_total_;
  double r = 1;
  // The tool's arc whose deceleration may follow its speed (5.); none: capacity.
  std::size_t recover_arc = buf_.capacity();
  // The tool's arc whose braking bounds may follow its speed (10.); none: capacity.
  std::size_t brake_arc = buf_.capacity();
  // The rise where the pair at the tool is a plain speed change along its line (0: none).
  double line_rise = 0;
  if (!buf_.empty() && cur_ < buf_.end_index() && buf_[cur_].kind == ItemKind::kMotion) {
    const Segment& s = buf_[cur_];
    const std::size_t slot = buf_.slot(cur_);
    sigma_p = sigma0_[slot] + seg_sigma(slot, pos_mm_ - s.s0_mm);
    // The lowest r over where the next step can go (the next segment, joint zones: 7.) — not
    // past a stop ahead: a segment after it with a lower r would make the landing lattice near
    // the stop switch to that r, a deceleration step of up to 1.5·A0 (found with the post
    // filter, whose exact-path corners are stops).
    double reach = pos_mm_ + step_ + a0_;
    // (A stop past the reach leaves it: the double below the stop is then ≥ reach.)
    if (in.stop_mm > pos_mm_ && in.stop_mm <= reach) {
      reach = std::min(reach, std::nextafter(in.stop_mm, pos_mm_));
    }
    const double r_reach = r_span(pos_mm_, reach, &reach_skip_);
    r = r_reach;
    // The last step started on this line and this one cannot leave it: the sample at the tool
    // turns nothing, so its speed may rise by the line's own r (a joint zone ahead within the
    // reach lowers r for the pairs whose sample is near the joint, 7.; no filter: 8. averages).
    if (lag_ == 0 && !s.arc && pos_mm_ - step_ >= s.s0_mm &&
        pos_mm_ + step_ + ratio_[slot] * a0_ < s.end_mm()) {
      line_rise = ratio_[slot] * a0_;
    } else if (lag_ == 0 && !s.arc && !in.hold && !lim_.bound_resultant &&
               !(in.stop_mm > pos_mm_ && in.stop_mm <= pos_mm_ + step_ + a0_)) {
      line_rise = pair_rise(s);
    }
    // Past the corner just crossed, its head zone (7.) is replaced by the exact limit: within
    // b before its tail zone, b's own r.
    // (Not for a hold or an override decrease: after_corner() counted on the zone's r for them.)
    if (after < kInf && reach < s.end_mm() - tail_mm_[slot] && !in.hold && !feed_recover_ &&
        !(in.or_ratio < prev_or_)) {
      r = ratio_[slot];
    }
    // Both steps of the pair inside the arc: the step before started in it too (a pair across
    // the joint before the arc is the joint zone's, 7., which counts on r).
    if (lag_ == 0 && arc_g_[slot] > 0 && reach < s.end_mm() && pos_mm_ - step_ >= s.s0_mm &&
        r_reach == ratio_[slot]) {
      recover_arc = slot;
    }
    // The pair of this step and the one before is inside the arc, or this step lands past the
    // point e where 9. hands over to the keys (then ≤ W, a step the keys allow).
    if (lag_ == 0 && arc_g_[slot] > 0 && pos_mm_ - step_ > s.s0_mm) brake_arc = slot;
  }
  // a: the speed change allowed in this cycle.
  const double a = r * a0_;

  // The cycle's step is a plain minimum, u = min(the change, the feed limit, the geometric caps,
  // the braking bounds, the stop bounds, to_stop), and a minimum does not change when a term
  // ≥ it is left out. So each braking or stop bound (a square root, the stop's landing step) is
  // computed only where it may be below the minimum of the cheap terms so far, t; otherwise a
  // test on squares shows that it is ≥ t (with a relative margin of kSkipMargin, far above the
  // rounding of either side: the skipped term, rounded, is > t). Same double as the full
  // computation (the order of a minimum does not matter; max(0, ·) below makes −0 and +0 one).
  // The feed bound is computed exactly: the override-decrease ramp compares against it.
  // The braking bound on the tool's arc with what the speed leaves (10.), computed only where a
  // braking bound is the binding term; each braking bound b becomes max(b, T).
  // (The geometric keys and the feed keys separately: after an override decrease the feed part
  // is left by the ramp of 5., the geometric part stays a hard limit.)
  double arc_t[2] = {-1, -1};
  ArcTarget arc_at[2];
  auto arc_brake = [&](bool feed) {
    const std::size_t i = feed ? 1 : 0;
    if (arc_t[i] < 0) {
      arc_t[i] = brake_arc < buf_.capacity()
                     ? arc_brake_step(brake_arc, buf_[cur_], in.or_ratio, feed, arc_at[i])
                     : 0.0;
    }
    return arc_t[i];
  };
  double feed_limit = feed_bound(in.or_ratio, sigma_p);
  const double feed_keys = feed_limit;  // without 10.
  if (brake_arc < buf_.capacity()) {
    const double active = in.or_ratio * active_feed_.min();
    if (feed_limit < active) feed_limit = std::min(active, std::max(feed_limit, arc_brake(true)));
  }
  if (check_) {
    const Bounds full = bound(in.or_ratio, sigma_p);
    last_bound_ = std::min(full.geo, full.feed);
    if (reference_bound(in.or_ratio) != last_bound_) ++mismatches_;
  }

  if (in.stop_mm != cached_stop_mm_) {
    cached_stop_mm_ = in.stop_mm;
    cached_stop_sigma_ = sigma_at(in.stop_mm);
  }
  const double to_stop = std::max(0.0, in.stop_mm - pos_mm_);
  const double d_sigma = std::max(0.0, cached_stop_sigma_ - sigma_p);

  // On an arc whose r was fixed for its top speed (a_n = 0.95·g there), a step below the top
  // leaves more for the tangent: rise by min(A0, √((0.98·g)² − (u⁺²/ρ)²)), u⁺ = this step plus
  // the most it may rise (inside the tool's arc, no joint zone in reach, no filter: as 5.).
  double rise = a;
  if (!in.hold && recover_arc < buf_.capacity()) {
    const std::size_t slot = recover_arc;
    const double most = std::min(a0_, lin_r_[slot] * a0_);
    const double u_hi = step_ + most;
    const double an = u_hi * u_hi / arc_rho_[slot];
    const double g = kRecoverShare * arc_g_[slot];
    rise = std::max(a, std::min(most, std::sqrt(std::max(0.0, g * g - an * an))));
  }
  rise = std::max(rise, line_rise);
  double u = in.hold ? step_ - a : step_ + rise;
  // Geometric caps and stops are hard limits, and so is the feed limit while the override has
  // not been lowered (following its bound needs no more than the deceleration of the zone just
  // run, 3. (ii) and 7.). After an override decrease the feed limit may drop by more than one
  // step's deceleration: then decelerate at a until the tool is within it again.
  if (in.or_ratio < prev_or_) feed_recover_ = true;
  prev_or_ = in.or_ratio;
  // On an arc r was fixed for its top speed, where a_n = v²/ρ leaves √(g² − a_n²) for the
  // tangent: slowing down for a lower override, the current step's a_n leaves more (inside the
  // tool's segment, no joint zone in reach, no filter after this type: 8. carries r).
  double a_recover = a;
  if (feed_recover_ && recover_arc < buf_.capacity()) {
    const std::size_t slot = recover_arc;
    const double an = step_ * step_ / arc_rho_[slot];
    // 2 % of g kept for the chords' discrete normal acceleration (the top-speed rule keeps 5 %).
    const double g = kRecoverShare * arc_g_[slot];
    const double at = std::sqrt(std::max(0.0, g * g - an * an));
    a_recover = std::max(a, std::min({a0_, lin_r_[slot] * a0_, at}));
  }
  // At least σ's mean r over the step just taken (no filter): the feed keys of the level before
  // the decrease allowed it, so they allow it less that mean·A0 now (3. (ii)). Decelerating at
  // a alone (the r over the next step's reach, lower in a joint zone than σ's r for decreases,
  // 7.) fell behind them: 50.26 mm/s at a 50 mm/s feed (RandomProgramsWithCoupledAxesAndLines).
  if (feed_recover_ && lag_ == 0 && step_ > 0) {
    a_recover = std::max(a_recover, std::clamp((sigma_p - prev_sigma_) / step_, 0.0, 1.0) * a0_);
  }
  const double feed = feed_recover_ ? std::max(step_ - a_recover, feed_limit) : feed_limit;
  // (Nested: an initializer list became a loop over a stack array; the same double, the first
  // of equal values as there.)
  u = std::min(std::min(std::min(std::min(u, feed), active_geo_.min()), to_stop), after);

  // The geometric braking bounds (3.): x ≤ √(A0² + K − 2·A0·σ) − A0 ≥ u when the root's
  // argument is ≥ (u + A0)²; lattice keys: x ≤ √(K − 2·A0·σ) − A0/2 ≥ u when K − 2·A0·σ ≥
  // (u + A0/2)².
  const bool skip = u > 0 && u < kInf;
  double geo_keys = kInf;  // the lowest geometric braking bound below u, without 10.
  const double k_geo = key_geo_.min();
  if (k_geo != kInf) {
    const double arg = a0_ * a0_ + k_geo - 2 * a0_ * sigma_p;
    if (!(skip && arg >= above(u + a0_))) {
      const double b = brake(k_geo, sigma_p);
      if (b < u) {
        geo_keys = b;
        u = std::min(u, std::max(b, arc_brake(false)));
      }
    }
  }
  const double k_lat = key_lattice_.min();
  if (k_lat != kInf) {
    const double arg = k_lat - 2 * a0_ * sigma_p;
    if (!(skip && arg >= above(u + 0.5 * a0_))) {
      const double b = lattice(k_lat, sigma_p);
      if (b < u) {
        geo_keys = std::min(geo_keys, b);
        u = std::min(u, std::max(b, arc_brake(false)));
      }
    }
  }

  // The stop: its σ lattice (≥ u when A0²/4 + 2·A0·Δσ ≥ (u + A0/2)²), the landing step in real
  // distance (≥ √(2·a·d) − a/2 for every m: d/(m + 1) + a·(m + 1)/2 ≥ √(2·a·d) by AM–GM, so
  // ≥ u when 2·a·d ≥ (u + a/2)²; d ≤ a returns d ≥ √(2·a·d) − a/2) and the tail cap V_t.
  // In real distance with the lowest r from the tool up to the stop, a_stop: with the r over the
  // next step's reach only, a lower r coming into reach would lower these bounds by more than
  // one step's deceleration at once (a 0.5 µm arc after a full circle at F 500: 8.3 → 6.8 →
  // 5.2 → 1.5 µm/cycle, 3 698 mm/s² on a 2 000 axis). The minimum over [tool, stop) only rises
  // as the tool moves on, and each bound rises with a, so following them stays within a_stop.
  // Computed only where the landing step with the window's lowest r may be below u.
  const double vt = tail_cap_pc_;
  const bool lattice_far = skip && u > 0 && a0_ * a0_ / 4 + 2 * a0_ * d_sigma >= above(u + a0_ / 2);
  auto landing_far = [&](double ac) {
    return 2 * ac * to_stop >= above(u + ac / 2) &&
           (to_stop <= vt ? vt >= u : ac * ac + vt * vt + 2 * ac * (to_stop - vt) >= above(u + ac));
  };
  double a_stop = a;
  bool stop_far = false;
  if (to_stop > 0 && !buf_.empty()) {
    // With the zones' r (3.; a block whose r or zone would lower these bounds at once is held,
    // 6.). (Both bounds rise with a where to_stop ≥ 2·V_t: far with the window's lowest r is far.)
    const double a_lo = std::min(a, r_zone_.min() * a0_);
    if (lattice_far && to_stop >= 2 * vt && landing_far(a_lo)) {
      stop_far = true;
    } else {
      a_stop = std::min(a, r_span(pos_mm_, std::nextafter(in.stop_mm, pos_mm_)) * a0_);
    }
  }
  if (!stop_far) stop_far = lattice_far && landing_far(a_stop);
  auto stop_bound = [&](double as) {
    double stop_limit = std::sqrt(a0_ * a0_ / 4 + 2 * a0_ * d_sigma) - a0_ / 2;
    stop_limit = std::max(stop_limit, std::min(to_stop, as));
    stop_limit = std::min(stop_limit, landing_step(to_stop, as));
    // The last V_t = min(A0, a_i)/2 before a stop (the lowest corner cap, a reversal) is run at
    // ≤ V_t: a joint cap that arrives late at a stop's position (the window's tail) then finds
    // the steps around it already within its cap (see 6.).
    if (to_stop > 0) {
      // In real distance with the local acceleration a (the cap lies within a few steps of the
      // stop; farther away the stop's own σ bound is the stricter one).
      const double tail =
          to_stop <= vt ? vt : std::sqrt(as * as + vt * vt + 2 * as * (to_stop - vt)) - as;
      stop_limit = std::min(stop_limit, tail);
    }
    return stop_limit;
  };
  if (!stop_far) u = std::min(u, stop_bound(a_stop));

  // 11. A capped corner between two lines just ahead, the step before its crossing: that step
  // may exceed the cap's braking bound when its sample keeps every limit for each crossing step
  // the next cycle may take; and the step before it too, when from there such a step remains
  // however the next cycle is slowed (committed: that cycle then takes one). A bounded few
  // evaluations, only in the two or three cycles before such a corner.
  const Commit commit = commit_;
  commit_.valid = false;
  // (Gated on the compact cap arrays first: the segments are loaded only near such a corner.)
  const std::size_t cp = cur_ + 1 < buf_.end_index() ? 3 * buf_.slot(cur_ + 1) + 2 : std::size_t{0};
  const std::uint32_t cg = cur_ + 1 < buf_.end_index() ? owner_[cp] : kNone;
  if (cg != kNone && lag_ == 0 && !jerk_on_ && (!in.hold || commit.valid) &&
      (u > 0 || commit.valid) && to_stop > 0 && cur_ >= buf_.begin_index() && !caps_[cg].feed &&
      pos_mm_ + caps_[cg].v < caps_[cg].c_mm + caps_[cg].v &&
      caps_[cg].c_mm + caps_[cg].v - pos_mm_ < 3 * caps_[cg].v + 3 * a0_) {
    const Segment& sa = buf_[cur_];
    const Segment& sb = buf_[cur_ + 1];
    const double j = sa.end_mm();
    const Cap& cap = caps_[cg];
    Centre ct;
    if (sa.kind == ItemKind::kMotion && sb.kind == ItemKind::kMotion && !sa.arc && !sb.arc &&
        sb.s0_mm == j && pos_mm_ - step_ >= sa.s0_mm && pos_mm_ + u < j &&
        std::abs(cap.c_mm + cap.v - j) <= 1e-9 * std::max(1.0, std::abs(j)) &&
        sb.length_mm >= cap.v + a0_ && centre_setup(cg, sa, sb, ct)) {
      const double first = in.hold ? step_ - a : step_ + rise;
      // The cycle's bound with this joint's cap left out (its key or its active leaf: two tree
      // updates), the stop's bounds included; above `want` it may answer min(bound, want).
      auto free_bound = [&](double want) {
        const bool active = state_[cg] == State::kActive;
        MinTree& t = active ? active_geo_ : (cap.lattice ? key_lattice_ : key_geo_);
        const double saved = t.at(cg);
        t.set(cg, MinTree::kEmpty);
        double f = std::min({first, feed, active_geo_.min(), to_stop, after});
        if (const double k = key_geo_.min(); k != kInf) f = std::min(f, brake(k, sigma_p));
        if (const double k = key_lattice_.min(); k != kInf) f = std::min(f, lattice(k, sigma_p));
        t.set(cg, saved);
        // The stop's bounds are ≥ x where far (the same tests as above, with x for u).
        const double x = std::min(f, want);
        const double a_lo = std::min(a, r_zone_.min() * a0_);
        const bool far = to_stop >= 2 * vt &&
                         a0_ * a0_ / 4 + 2 * a0_ * d_sigma >= above(x + a0_ / 2) &&
                         2 * a_lo * to_stop >= above(x + a_lo / 2) &&
                         a_lo * a_lo + vt * vt + 2 * a_lo * (to_stop - vt) >= above(x + a_lo);
        if (far) return x;
        const double as = std::min(a, r_span(pos_mm_, std::nextafter(in.stop_mm, pos_mm_)) * a0_);
        return std::min(f, stop_bound(as));
      };
      // What the step can be at most without that minimum (the search runs first, the minimum
      // only where the search found a step).
      const double pre = std::min({first, feed, to_stop, after});
      const double d0 = j - pos_mm_;
      const double top = ct.vg + (1 - 1e-6) * a0_;
      if (commit.valid && commit.j_mm == j && commit.from_mm == pos_mm_) {
        // Every bound but the cap's allows at least commit.lo here (3. (ii)), and the centred
        // step commit.lo was found feasible from here: the largest feasible one up to them.
        const double free = free_bound(std::min(top, d0));
        const double lo = std::min(commit.lo, free);
        u = in.hold ? (centred_ok(ct, pos_mm_, free) ? free : lo)
                    : centred_step(ct, lo, std::min({free, top, d0}));
      } else if (!in.hold && d0 < 2 * ct.vg + a0_) {
        double x = centred_step(ct, u, std::min({pre, top, d0}));
        if (x > u) {
          const double free = free_bound(x);
          if (x > free) x = centred_step(ct, u, std::min({free, top, d0}));
          u = x;
        }
      } else if (!in.hold) {
        double lo_next = 0;
        double x = committing_step(ct, u, std::min(pre, d0 - ct.vg), lo_next);
        if (x > u) {
          const double free = free_bound(x);
          if (x > free) x = committing_step(ct, u, std::min(free, d0 - ct.vg), lo_next);
          if (x > u) commit_ = {true, j, pos_mm_ + x, lo_next};
          u = x;
        }
      }
    }
  }
  u = std::max(0.0, u);
  if (u <= feed_limit) feed_recover_ = false;
  // A step above the keys' braking bounds follows 10.'s curve, whose e and W only blocks that
  // arrive in time may change: late_cap() holds a late block that would move them (6.).
  const bool geo_relied = arc_t[0] > 0 && u > geo_keys;
  const bool feed_relied = arc_t[1] > 0 && u > feed_keys;
  relied_e_mm_ = geo_relied ? arc_at[0].e_mm : feed_relied ? arc_at[1].e_mm : kInf;
  relied_sigma_e_ = geo_relied ? arc_at[0].sigma_e : arc_at[1].sigma_e;
  relied_w_geo_ = geo_relied ? arc_at[0].w : kInf;
  relied_w_feed_ = feed_relied ? arc_at[1].w : kInf;
  // A step from inside a line across its end: after_corner() looks at it in the next cycle.
  crossed_.valid = false;
  if (lag_ == 0 && !buf_.empty() && cur_ >= buf_.begin_index() && cur_ < buf_.end_index()) {
    const Segment& s = buf_[cur_];
    if (s.kind == ItemKind::kMotion && !s.arc && pos_mm_ >= s.s0_mm && pos_mm_ < s.end_mm() &&
        pos_mm_ + u >= s.end_mm()) {
      crossed_ = {true, s.end_mm(), pos_mm_, sigma_p, s.end_direction()};
    }
  }
  if (u > 0 && u >= to_stop) {
    pos_mm_ = in.stop_mm;  // land exactly on the stop
  } else {
    pos_mm_ += u;
  }
  prev_sigma_ = sigma_p;
  step_ = u;
  if (!jerk_on_) {
    tool_mm_ = pos_mm_;
    tool_step_ = u;
    return;
  }
  // Jerk stage (8.): the tool's step is the mean of the last T2 commanded steps.
  tool_step_ = jerk_.push(u);
  tool_mm_ = jerk_.at_rest() ? pos_mm_ : std::min(tool_mm_ + tool_step_, pos_mm_);
}

}  // namespace cncore::motion
