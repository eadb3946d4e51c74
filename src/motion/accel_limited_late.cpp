// Blocks that arrive late, while the tool may already brake for the window's end: which caps
// would bind at once, and the hold that lets the tool stop and settle before they take effect.
// And the other stop that comes late: one requested at a block end ahead (14.).
//
// 6. Late caps. A block arrives *late* when the interpreter was late: until then the window's
//    last end point was a stop, and the tool may already be braking for it. Its caps may then
//    bind at once: one whose c the commanded position has passed is active at once, and with a
//    filter (8.) the steps still in it were not bounded by it; one ahead may have a braking bound
//    below the last step (the stop's bounds are lattice and real-distance forms, a cap's key is
//    in σ with offset A0: they differ by up to A0/2, and by (1 − r)·A0 on a segment with r < 1).
//    Found (accel_late_test.cpp, before the hold): a corner, a slower feed or an arc arriving
//    during the braking ramp gave tangential accelerations up to 3 365 mm/s² (A 2 000), corners
//    passed at 5× their Vg with a 200-cycle jerk stage (normal 10 769 mm/s²), 0.022 mm of
//    rounding for a 0.01 mm tolerance, and without a filter on slow X/Y a late 30° corner braked
//    an r = 0.8 line at A0 (X 1 740 > 1 500 mm/s²).
//    So a block's range caps and its joint's cap are tested before anything is attached
//    (check_late(), from on_segment() or, at a joint, from joint_zones() before its zone is
//    applied, with σ(c) as low as the zone may leave it; late_cap(): active at once with V below
//    the largest commanded step of the last lag cycles, or approaching with its bound at the
//    commanded position below the last step — from at or above it, following it needs ≤ r·A0
//    per cycle, 3. (ii)), and so is the stop at the joint when the joint's zone (7.) lowers σ
//    ahead of the tool (its lattice bound must still allow the last step; found: a zone ahead of
//    a 1 µm segment gave 2 011.7 mm/s²), and the stop's landing bounds in real distance (3.)
//    at the block's end, with its r and its joint zone's (check_stop()); insert() tests what
//    these did not foresee (on_joint()'s cap for two corners in one cycle). Only when the tool
//    is near enough for anything to bind: every cap starts at or after s0 − (2 + reach_lag)·v_hi
//    (8.), and from c − p ≥ (u²/(2·A0) + u + A0)/r_lo on no key bound is below the step u (r_lo the
//    window's, the block's, and kZoneFloor × the lower r at its joint, the lowest its zone
//    may have). If one binds, the block is *held*: the window's end it
//    arrived at (hold_mm_) stays a stop, the caps of every block arriving meanwhile wait in
//    pending_ (and no joint zone reaches behind hold_mm_), and once the tool has been at rest
//    there for the post filter's length they are inserted with the σ(c) of then. The tool
//    starts from rest with an empty filter, so every cap holds from there on as in 1.–8.
//    A held block costs the rest of the stop and the filter's span (corner arriving during the
//    braking: +7 cycles without a filter, +21 with Tp = 16, +32 with T2 = 40, +191 with T2 = 200
//    and Tp = 16 against the old, violating runs; at most 10 cycles more than the same block in
//    time). Blocks in time, and late ones whose caps it can still follow, are attached as before
//    (same samples: bench_motion --digest). What makes the usual late block followable: the
//    last V_t = min(A0, a_i)/2 before every stop (V_t is the lowest corner cap, a reversal's) is
//    run at ≤ V_t, and the lattice's steps landing within V_t of the stop are ≤ V_t.
//    A step that followed 10.'s curve on an arc (above the keys' bounds) relied on its end e and
//    target W, which a late block may change: a cap entering before e (a lattice cap's entry
//    c − V, a joint cap's j − Vg) or a joint zone starting before it moves e back, and a cap
//    whose bound at σ(e) is below W lowers W. Either holds the block too (found: a 1 µm line
//    after a dwell, its lattice cap entering 0.11 mm before e while the tool braked on a helix:
//    the curve fell by 1.41·A0 at once, 2 827 mm/s² tangential).
//    The release inserts the pending caps kReleasePerCycle per cycle (O(log n) each) while the
//    tool waits at rest, so no cycle does more than a bounded number of inserts.
//
// 14. A stop requested at a block end (Kernel::request_stop_at_block_end). CycleInput::stop_mm
//    drops at once to a block end ahead, with every block after it already here: nothing is
//    late, only the stop's own bounds (3.) are new. At the commanded position p with step u
//    they allow u when
//        lattice in σ:   (u + A0/2)² ≤ A0²/4 + 2·A0·(σ(c) − σ(p))  ⇔  u² + u·A0 ≤ 2·A0·Δσ,
//        landing step:   landing_step(c − p, a_s) ≥ u,
//        tail cap V_t:   √(a_s² + V_t² + 2·a_s·(c − p − V_t)) − a_s ≥ u  (c − p > V_t),
//    a_s = A0 × the lowest r over [p, c), as the cycle takes it. From a bound ≥ the last step
//    following it asks for no more than a_s per cycle (3. (ii)), like the stop at the window's
//    end. u is the last step plus 2·A0: the next cycle may rise by A0, and a centred corner
//    committed in the last cycle (11.) may need a step up to A0 above the last one, which the
//    new stop must not cut. stop_reach_mm() is the first block end the first form allows (σ is
//    monotone along the path: a bisection over the items); can_stop_at() tests all three at a
//    block end (the kernel tries the ends from there on, on the cycle of the request only).
#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/accel_limited.hpp"
#include "motion/accel_limited_common.hpp"

namespace cncore::motion {

using namespace accel_limited_common;  // NOLINT(google-build-using-namespace)
using planner::ItemKind;
using planner::Segment;

namespace {
constexpr std::size_t kReleasePerCycle = 32;  // pending caps a cycle inserts (6.)
}  // namespace

bool AccelLimitedAccDec::late_cap(const Cap& cap) const {
  const double or_ratio = cap.feed ? prev_or_ : 1.0;
  // Active at once: every step still in the filter must be within it.
  if (pos_mm_ >= entry_mm(cap)) return or_ratio * cap.v < late_m_;
  // Approaching: its braking bound at the commanded position (3.) must allow the last step,
  // from which following it needs no more than r·A0 per cycle (3. (ii)).
  const double k_sigma = 2 * a0_ * cap.sigma_c;
  const double h = cap.v - 0.5 * a0_;
  const double v = cap.feed ? static_cast<double>(level_of(or_ratio)) * level_step_ * cap.v : cap.v;
  auto bound_at = [&](double sigma) {
    return cap.lattice ? lattice(h * h + k_sigma, sigma) : brake(v * v + k_sigma, sigma);
  };
  if (bound_at(late_sigma_p_) < step_) return true;
  // The last step followed 10.'s curve to W at e: a cap entering before e moves e back, one
  // whose bound at e is below W lowers W; either may lower that curve by more than one cycle's
  // deceleration (found: a late line's lattice cap entering 0.11 mm before e, 2 827 mm/s²).
  if (relied_e_mm_ == kInf) return false;
  if (entry_mm(cap) < relied_e_mm_) return true;
  const double w = cap.feed ? relied_w_feed_ : relied_w_geo_;
  return w < kInf && bound_at(relied_sigma_e_) < w;
}

void AccelLimitedAccDec::check_late(double at_mm, double zone_mm, double zone_r,
                                    const Cap* joint_cap, std::uint64_t index_a) {
  // σ(c) as the joint zone [zone_mm, at_mm] of rate zone_r (1: none) will leave it, or lower.
  const double r_lo = std::min({1.0, r_zone_.min(), zone_r});
  const double sigma_zone = zone_r < 1 ? sigma_at(zone_mm) : 0;
  auto sigma_c = [&](double c) {
    const double sc = sigma_at(c);
    return zone_r < 1 && c > zone_mm ? std::min(sc, sigma_zone + r_lo * (c - zone_mm)) : sc;
  };
  // A zone starting before the e of 10.'s curve the last step followed moves e (the arc's tail)
  // or σ(e) (see late_cap()).
  if (zone_r < 1 && relied_e_mm_ < kInf && zone_mm < relied_e_mm_) start_hold(at_mm);
  for (std::size_t k = 0; k < n_late_range_ && !late_hold_; ++k) {
    Cap cap = late_range_[k];
    cap.sigma_c = sigma_c(cap.c_mm);
    if (late_cap(cap)) start_hold(at_mm);
  }
  if (joint_cap != nullptr && !late_hold_) {
    Cap cap = *joint_cap;
    cap.sigma_c = sigma_c(cap.c_mm);
    bool binds = late_cap(cap);
    if (!cap.lattice && cap.v >= 0.5 * a0_) {
      cap.lattice = true;  // insert_joint_cap() may choose either form here (3.): test both
      binds = binds || late_cap(cap);
    }
    if (binds) start_hold(at_mm);
  }
  // The caps of earlier blocks that the zone re-keys (joint_zones()) with the σ(c) it leaves:
  // one that binds at once holds the block before the zone is applied (found: a 1 µm G0's zone
  // with a 200-cycle jerk stage lowered σ under the tool over 0.66 mm; the re-keyed joint cap
  // bound, the hold began in the middle of the re-keying and left the older caps' keys stale:
  // a 0.54 µm/cycle cap met at 4.97 µm/cycle, 22 258 mm/s³ on a 20 000 jerk limit).
  if (zone_r >= 1 || late_hold_) return;
  std::size_t walked = 0;
  for (std::uint64_t k = index_a + 1;
       k-- > std::max(cur_, buf_.begin_index()) && walked < kZoneWalk && !late_hold_;) {
    const Segment& x = buf_[k];
    if (x.kind != ItemKind::kMotion) {
      if (x.barrier) break;
      continue;
    }
    if (x.end_mm() <= zone_mm) break;
    ++walked;
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t cs = 3 * buf_.slot(k) + c;
      if (pos_state(cs) != State::kApproaching) continue;
      Cap cap = caps_[owner_[cs]];
      cap.sigma_c = std::min(cap.sigma_c, sigma_c(cap.c_mm));
      if (late_cap(cap)) start_hold(at_mm);
    }
  }
}

void AccelLimitedAccDec::check_stop(double stop_mm, double at_mm, double r_new) {
  // The stop's landing step and tail cap (3.) use the lowest r (with the zones) from the tool
  // up to the stop: with stop_mm as the window's new stop and r_new as low as a new block
  // brings into that span, they must still allow the last step.
  if (step_ <= 0 || late_hold_) return;
  const double a_new = std::min(r_new, r_span(pos_mm_, at_mm)) * a0_;
  const double d = stop_mm - pos_mm_;
  const double vt = tail_cap_pc_;
  const double tail =
      d <= vt ? vt : std::sqrt(a_new * a_new + vt * vt + 2 * a_new * (d - vt)) - a_new;
  if (std::min(landing_step(d, a_new), tail) < step_) start_hold(at_mm);
}

void AccelLimitedAccDec::start_hold(double at_mm) {
  late_hold_ = true;
  hold_mm_ = at_mm;
  rest_cycles_ = 0;
}

void AccelLimitedAccDec::release_hold() {
  // kReleasePerCycle caps per cycle, so the cycle stays O(log n); the tool waits at rest at
  // hold_mm_ until the last one is in (blocks arriving meanwhile queue behind them).
  late_check_ = false;  // (the inserts below are not a block's arrival)
  releasing_ = true;
  const std::size_t end = std::min(pending_.size(), pending_next_ + kReleasePerCycle);
  for (; pending_next_ < end; ++pending_next_) {
    auto& [pos, cap] = pending_[pending_next_];
    // σ ahead may have moved since (joint zones of later blocks): keys with the exact σ(c), 7.
    cap.sigma_c = sigma_at(cap.c_mm);
    if (pos % 3 == 2 && cap.v < a0_) {
      cap.lattice = cap.v >= 0.5 * a0_ && cap.sigma_c - sigma_at(cap.c_mm - cap.v) >= 0.5 * cap.v;
    }
    insert(pos, cap);  // in arrival order: a later cap at the same position replaces it
  }
  releasing_ = false;
  if (pending_next_ == pending_.size()) {
    pending_.clear();
    pending_next_ = 0;
    late_hold_ = false;
  }
  cached_stop_mm_ = -1;
}

double AccelLimitedAccDec::request_step() const {
  // At rest (and nothing committed, 11.) any block end ahead will do.
  return step_ > 0 || commit_.valid ? step_ + 2 * a0_ : 0.0;
}

double AccelLimitedAccDec::stop_reach_mm() {
  const double u = request_step();
  if (u <= 0 || !have_prev_ || buf_.empty()) return pos_mm_;
  const double target = sigma_at(pos_mm_) + (u * u + u * a0_) / (2 * a0_);
  if (target >= sigma_total_) return prev_end_mm_;  // the window's end, a stop already
  // The first item whose end has σ ≥ target (σ never falls along the path; events between the
  // segments end where the segment before them does): galloping from the tool's item, then
  // bisection, O(log n) probes of σ at an item's end (each O(log n)).
  const std::uint64_t first = std::max(cur_, buf_.begin_index()), end = buf_.end_index();
  if (first >= end) return pos_mm_;
  auto reaches = [&](std::uint64_t k) { return sigma_at(buf_.end_mm_of(k)) >= target; };
  std::uint64_t lo = first, hi = end - 1;  // the answer lies in [lo, hi]
  if (!reaches(hi)) return prev_end_mm_;
  for (std::uint64_t step = 1; lo + step < hi; step *= 2) {
    if (reaches(lo + step)) {
      hi = lo + step;
      break;
    }
    lo += step;
  }
  while (lo < hi) {
    const std::uint64_t mid = lo + (hi - lo) / 2;
    if (reaches(mid)) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  return buf_.end_mm_of(lo);
}

bool AccelLimitedAccDec::can_stop_at(double stop_mm) const {
  const double u = request_step();
  const double d = stop_mm - pos_mm_;
  if (u <= 0) return d >= 0;
  if (2 * a0_ * (sigma_at(stop_mm) - sigma_at(pos_mm_)) < u * u + u * a0_) return false;
  const double as = r_span(pos_mm_, std::nextafter(stop_mm, pos_mm_)) * a0_;
  const double vt = tail_cap_pc_;
  const double tail = d <= vt ? vt : std::sqrt(as * as + vt * vt + 2 * as * (d - vt)) - as;
  return landing_step(d, as) >= u && tail >= u;
}

}  // namespace cncore::motion
