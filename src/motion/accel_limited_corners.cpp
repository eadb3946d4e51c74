// Corner rules of the cycle that use where the joint lies and which step was just taken: the
// cycle after a capped corner, centred corners, and rises across one joint.
//
// 9. The cycle after a capped corner. A joint cap holds the step after the crossing at Vg too,
//    because the crossing's sample may lie anywhere around j. Once the crossing is done, where
//    it lies is known: with α the part of the crossing step before j and β the part after, the
//    chords are d1 = α·E + β·S and d2 = u2·S, so the second difference at the sample after j is
//    (u2 − β)·S − α·E — only α of the turn is left to it (none when the crossing sample lies on
//    j). Between two lines (linear axes, no filter) after_corner() computes the interval of u2
//    that keeps every axis, the tangential and the normal acceleration (and the resultant
//    option) there, and replaces the joint's cap and its head zone by it for that one step: the
//    samples after it see plain speed changes along S (b's own r). Kept only when the interval
//    holds u1 − ρ·A0 (every step a cycle may choose lies in [u1 − ρ·A0, its bounds]; ρ as in
//    11.: the larger of σ's mean r over the crossing step and the r of b's piece at the tool,
//    what a hold or an override decrease slows by — in this cycle they keep that r, only the
//    increase gets b's own) and the step stays inside b. The steps before the corner and the
//    crossing step are unchanged, so every braking plan still holds. Capped corners along a
//    lattice approach put the crossing sample near j, and the speed then rises by up to A0 at
//    once: zigzag_0.002 22.53 → 20.54 s. (With u1 − A0 as the lower end, a corner inside its
//    zone at the floor, r = 0.25, never had an interval: line-contouring-xz's 4.8° corners.)
//
// 11. Centred corners (between two lines, linear axes, no filter, turns ≤ 120°, b ≥ Vg + A0).
//    The joint cap holds the step that lands within Vg before j to Vg as well, because the
//    crossing after it may split the turn anyhow (9.). With the step u0 landing α before j and
//    the crossing u1 = α + β, the sample between them has the second difference
//    (α − u0)·E + β·S: the turn is shared between this sample and the next (9.) as β : α. So u0
//    may exceed Vg where that sample keeps every limit for every u1 the next cycle may take:
//      - u1 ≤ Vg: the sample lands in [c, j) = [j − Vg, j), where the cap is active;
//      - u1 ≥ u0 − ρ·A0: every bound but this cap's allowed u0 (the step is ≤ the cycle's
//        bound with this cap's key or active leaf left out, the stop's bounds included), so
//        each allows u0 − r̄·A0 next, r̄ = Δσ/u0 the mean r over the step (3. (ii); the stop's
//        landing bounds take the lowest r up to the stop, ≤ r̄); a hold or an override decrease
//        slows by A0 × the r of the next step's reach, ≤ the r of the piece the step lands in
//        (an override decrease by at most r̄·A0 more, 5.); ρ the larger (slowdown_r()). (With r_hi,
//        the highest r from the tool to j, a step from before a tail zone at the floor counted on
//        slowing by A0 at the sample, and the committing step was never feasible there.)
//    The limits at the sample: per axis |(α − u0)·E_i + β·S_i| ≤ a_i, tangential |u1 − u0| ≤ A0
//    (path speeds), the checker's chord normal a_n² = 2·u0·(|d1| − α − β·c) ≤ A0² (c = E·S,
//    increasing in β), resultant |d1 − d0|² ≤ A0². Each is convex in u1 on u1 ≤ α (no crossing:
//    a plain speed change) and on u1 ≥ α, so the ends of both pieces decide (centred_ok()). The
//    sample after the crossing is 9.'s (or, where 9. gives no interval, the cap's Vg as before:
//    7.'s pair of steps ≤ Vg, whatever b's length: the crossing is ≤ Vg as without 11.; b ≥
//    Vg + A0 keeps it inside b, so d1 = α·E + β·S). The sample stays ≥ 10 nm before j (the
//    checker takes a sample that close as reaching the joint). The step u0 is the largest
//    feasible one up to that bound: the per-axis limits with u1 = Vg are linear in u0
//    (α = j − tool − u0), their largest u0 first, then a bisection of 6 checks (every answer is
//    checked itself).
//    One step earlier (the tool ≥ 2·Vg + A0 before j): a step u_{-1} above the cap's bound
//    (≤ the cycle's bound without it) is taken when from its landing point p0 the slowest next
//    step, u_{-1} − ρ·A0 (ρ of that step), is a feasible centred step (lands in [c, j), limits
//    as above). It is *committed*: the cycle at p0 takes the largest feasible centred step
//    ≥ that (or the held step under a hold, if feasible), and every bound but the cap's allows
//    it there by 3. (ii).
//    The braking lattice of the cap's key lands the tool at c − Vg with Vg + A0; from there the
//    two steps let it reach the bound's pattern …, V + A0, **V** (centred), V + A0 …
//    (zigzag_0.002: 20.54 → 18.54 s; with ρ for r_hi and b ≥ Vg + A0, line-contouring-xz
//    22.575 → 22.348 s, braid_cut2d 20.526 → 20.338 s). Cost: only within 3·Vg + 3·A0 of such a
//    corner, a few closed forms and two tree updates (the cap's leaf left out and put back).
//
// 12. Rises across one joint (pair_rise()). The zones (7.) hold a pair of steps anywhere in
//    [j − 2V, j + V] to r_j, sized for the corner's V and any sample position. For an increase
//    the cycle knows both: the step just taken u1 and where the joint lies. When the pair spans
//    exactly one joint between two lines (no filter, no hold, no stop in reach, no resultant
//
//    so D is the largest value with |u1·(S_i − E_i) + D·S_i| ≤ a_i on every axis and
//    D ≤ min(r_a, r_b)·A0. Decreases keep the zones (σ): the braking plans do not change.
//    circle_small_segments 12.926 → 12.768 s; the sampled reference (bench/bound, cncore-sref)
//    runs it in 10.924 s: what is left there is the joint caps' hold of the steps beside the
//    crossing and the zones' r for decreases, sized for the caps rather than the speeds run.
//
// 13. Zones sized again for the next cap (rezone_before()). A zone is sized when its joint
//    arrives, for the speed V the tool may have there: the corner's cap, or what it can reach
//    from the cap before it. The cap vc of the next joint, when it arrives, bounds the speed over
//    the zone too (its braking bound, 3.). Where that V' is well below V and the tool has not
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
constexpr double kMinAlphaMm = 1e-5;  // 11.: the sample before a centred crossing, before j
constexpr int kCentreSearch = 6;      // 11.: bisection steps of a centred step search

// The cosine c = E·S of the turn between two lines that move X, Y, Z only; false when a rotary
// axis moves (the closed forms of 9. and 11. are for linear axes).
bool linear_turn_cos(const AxisVec& e, const AxisVec& s, double& c) {
  for (std::size_t i = 3; i < kMaxAxes; ++i) {
    if (e[i] != 0 || s[i] != 0) return false;
  }
  c = dot(e.xyz(), s.xyz());
  return true;
}

// The largest x in (u, hi] with ok(x) (11.'s step searches): hi itself, else the best of a
// bisection of kCentreSearch checks (every answer is checked itself); u when none is found.
template <typename Ok>
double largest_ok(double u, double hi, Ok ok) {
  if (ok(hi)) return hi;
  double lo = u, best = u;
  for (int it = 0; it < kCentreSearch; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (ok(mid)) {
      best = mid;
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return best;
}
}  // namespace

double AccelLimitedAccDec::pair_rise(const Segment& s) const {
  // 12. A pair across one joint between two lines. The zones (7.) hold every pair within
  // [j − 2V, j + V] to r_j, sized for the joint's passing speed V and for any sample position;
  // on paths whose corners lie a few steps apart they cover the whole path, and the speed
  // rises at the floor between corners that are passed far below their caps. For an increase
  // the exact limit is known here: u1 (the step just taken) and the joint j. With the pair
  // spanning j alone (the step before started in a, the next one cannot leave b), 7.'s
  // second difference at the tool for u2 = u1 + D is (u2 − u1)·S + c·(S − E),
  // c ∈ [u1 − u2, u1], linear in c: its extremes are D·E (within a's r) and u2·S − u1·E, so
  //     |u1·(S_i − E_i) + D·S_i| ≤ a_i  on every axis,  D ≤ min(r_a, r_b)·A0,
  // an interval of D that holds 0 when the tool's last pair did (u1 met the cap). Tangential:
  // D ≤ A0; normal: the step crossing j and the one beside it are ≤ Vg (the joint's cap, or 9.'s
  // exact limit). Decreases keep the zones' r (σ, the braking bounds, 3.): only the rise
  // changes. Returns 0 where this does not apply (the zones' r stays).
  const double u1 = step_;
  const double from = pos_mm_ - u1, to = pos_mm_ + u1 + a0_;
  const bool behind = from < s.s0_mm, ahead = to >= s.end_mm();
  if (behind == ahead) return 0;  // none (the line's own rise above) or two joints
  const std::uint64_t ia = behind ? cur_ - 1 : cur_, ib = ia + 1;
  if (ia < buf_.begin_index() || ib >= buf_.end_index()) return 0;
  const Segment& a = buf_[ia];
  const Segment& b = buf_[ib];
  if (a.kind != ItemKind::kMotion || b.kind != ItemKind::kMotion || a.arc || b.arc) return 0;
  if (a.s0_mm > from || b.end_mm() <= to || a.end_mm() != b.s0_mm) return 0;
  const AxisVec e = a.end_direction(), sd = b.start_direction();
  double c = 0;
  if (!linear_turn_cos(e, sd, c)) return 0;
  constexpr double kMargin = 1 - 1e-6;
  double d = std::min(ratio_[buf_.slot(ia)], ratio_[buf_.slot(ib)]) * kMargin * a0_;
  for (std::size_t i = 0; i < 3; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    const double ai = kMargin * lim_.axis_amax_pc2[i];
    const double t = u1 * (sd[i] - e[i]);
    if (std::abs(t) > ai) return 0;
    if (std::abs(sd[i]) <= 1e-12) continue;
    // −a_i ≤ t + D·S_i ≤ a_i: D ≤ (a_i − t)/S_i for S_i > 0, (−a_i − t)/S_i for S_i < 0.
    d = std::min(d, sd[i] > 0 ? (ai - t) / sd[i] : (-ai - t) / sd[i]);
  }
  return std::max(0.0, d);
}

double AccelLimitedAccDec::after_corner() {
  // The tool's segment b and the joint j at its start: the last step crossed j alone (it started
  // in the line a before j, recorded by step()), b is a line and j has a joint cap.
  const Crossed x = crossed_;
  crossed_.valid = false;
  if (!x.valid || buf_.empty() || cur_ < buf_.begin_index() || cur_ >= buf_.end_index()) {
    return kInf;
  }
  const Segment& b = buf_[cur_];
  const double j = b.s0_mm;
  if (b.kind != ItemKind::kMotion || b.arc || x.j_mm != j || !(j <= pos_mm_)) return kInf;
  const std::size_t sb = buf_.slot(cur_), cap_pos = 3 * sb + 2;
  if (pos_state(cap_pos) != State::kActive) return kInf;
  const AxisVec& e = x.e;
  const AxisVec sd = b.start_direction();
  double c = 0;
  if (!linear_turn_cos(e, sd, c)) return kInf;
  // Chords: d1 = α·E + β·S (the crossing, u1 = α + β), d2 = u2·S. With t = u2 − β:
  //   per axis |t·S_i − α·E_i| ≤ a_i,  tangential |u2 − u1| ≤ A0,
  //   normal a_n² = |d2 − d1|² − (|d2| − |d1|)² = 2·u2·(|d1| − β − α·c) ≤ A0²  (c = E·S; the
  //   quadratic terms cancel, |d1|² = α² + β² + 2αβc), and with a resultant limit
  //   |d2 − d1|² = t² − 2αc·t + α² ≤ A0². Each gives an interval of u2.
  constexpr double kMargin = 1 - 1e-6;
  const double alpha = j - x.from_mm, beta = pos_mm_ - j, u1 = alpha + beta;
  const double amax = kMargin * a0_;
  double lo = u1 - a0_, hi = u1 + amax;
  // The slowest step this cycle may take: u1 − ρ·A0, ρ the larger of the mean r over the
  // crossing (every braking bound allowed u1, 3. (ii)) and the r of b's piece at the tool (a
  // hold or an override decrease: step() keeps the zone's r for them in this cycle), as 11.
  const double rho = std::min(
      1.0,
      std::max((sigma0_[sb] + seg_sigma(sb, beta) - x.sigma_from) / u1, piece_r(sb, beta)) + 1e-12);
  const double slowest = u1 - rho * a0_;
  for (std::size_t i = 0; i < 3; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    const double ai = kMargin * lim_.axis_amax_pc2[i];
    const double ae = alpha * e[i];
    if (std::abs(sd[i]) <= 1e-12) {
      if (std::abs(ae) > ai) return kInf;
      continue;
    }
    const double t1 = (ae - ai) / sd[i], t2 = (ae + ai) / sd[i];
    lo = std::max(lo, beta + std::min(t1, t2));
    hi = std::min(hi, beta + std::max(t1, t2));
  }
  const double d1 = std::sqrt(std::max(0.0, alpha * alpha + beta * beta + 2 * alpha * beta * c));
  const double bend = d1 - beta - alpha * c;
  if (bend > 0) hi = std::min(hi, amax * amax / (2 * bend));
  // At a fold (a reversal, c ≈ −1) the sample before j also lies on b, α past j: a reading of
  // the positions that takes it there measures the crossing as |β − α| = |d1|, so u2 − |d1| ≤ A0
  // too (found by the late-block property: 1.0 → 3.0 µm/cycle across a 1.5 µm G0 reversed,
  // read as 0.99 → 3.0, 2 010 mm/s²).
  if (c < -0.999) hi = std::min(hi, d1 + amax);
  if (lim_.bound_resultant) {
    const double disc = amax * amax - alpha * alpha * (1 - c * c);
    if (disc < 0) return kInf;
    lo = std::max(lo, beta + alpha * c - std::sqrt(disc));
    hi = std::min(hi, beta + alpha * c + std::sqrt(disc));
  }
  // d2 inside b (past b's end the next joint turns too): u2 ≤ u1 + A0 ≤ what is left of b. (A
  // shorter b is left to the cap: there the next corner's cap follows within a step or two, and
  // a faster step out of this one measured slower on the whole, 13.07 → 13.24 s on
  // circle_small_segments.)
  if (b.end_mm() - pos_mm_ < u1 + a0_) return kInf;
  // Every step the cycle may choose lies in [u1 − ρ·A0, the bounds]: the interval must hold its
  // lower end, or the cap stays.
  if (!(lo <= slowest && hi >= lo)) return kInf;
  clear(cap_pos);
  return hi;
}

bool AccelLimitedAccDec::centre_setup(std::size_t g, const Segment& a, const Segment& b,
                                      Centre& ct) const {
  const Cap& cap = caps_[g];
  ct.vg = cap.v;
  ct.j = b.s0_mm;
  ct.c_mm = cap.c_mm;
  ct.e = a.end_direction();
  ct.sd = b.start_direction();
  if (!linear_turn_cos(ct.e, ct.sd, ct.c)) return false;
  // Not at folds: there the checker may read the sample before j as lying after it (9.).
  if (ct.c < -0.5) return false;
  // The cycle after the step u0 takes u1 ≤ Vg (the cap is active from c = j − Vg on, and the
  // sample lands in [c, j)) and ≥ u0 − r_hi·A0: every bound but this cap's allowed u0 here, so
  // it allows u0 − (mean r over the step)·A0 there (3. (ii); the stop's bounds with a_stop ≤ the
  // r there), and a hold or an override decrease slows by r·A0. r_hi: the highest r over
  // [tool, j] (a's, or its tail zone's when the tool is inside it).
  const std::size_t sa = buf_.slot(cur_);
  ct.slot_a = sa;
  ct.a_s0 = a.s0_mm;
  ct.r_hi = ratio_[sa];
  if (pos_mm_ - a.s0_mm >= a.length_mm - tail_mm_[sa]) ct.r_hi = std::min(ct.r_hi, tail_r_[sa]);
  ct.r_lo = tail_mm_[sa] > 0 ? std::min(ratio_[sa], tail_r_[sa]) : ratio_[sa];
  return true;
}

double AccelLimitedAccDec::piece_r(std::size_t slot, double x_mm) const {
  // r_span() from here: the head's r while x < h, the tail's once the span reaches L − t.
  double rate = ratio_[slot];
  if (x_mm < head_mm_[slot]) rate = std::min(rate, head_r_[slot]);
  if (tail_mm_[slot] > 0 && x_mm >= len_mm_[slot] - tail_mm_[slot]) {
    rate = std::min(rate, tail_r_[slot]);
  }
  return rate;
}

double AccelLimitedAccDec::slowdown_r(std::size_t slot, double s0, double from_mm,
                                      double to_mm) const {
  // A step x ≤ every braking bound lets the next one be ≥ x − r̄·A0, r̄ = Δσ/x the mean r over
  // the step (3. (ii); the stop's lattice too, and its landing bounds take the lowest r up to
  // the stop, ≤ r̄). A hold or an override decrease slows by A0 × the r of the next step's
  // reach, ≤ the r of the piece it starts in. (1e-12: roundings of σ.)
  const double x0 = from_mm - s0, x1 = to_mm - s0;
  const double mean = x1 > x0 ? (seg_sigma(slot, x1) - seg_sigma(slot, x0)) / (x1 - x0) : 1.0;
  return std::min(1.0, std::max(mean, piece_r(slot, x1)) + 1e-12);
}

bool AccelLimitedAccDec::centred_ok(const Centre& ct, double from_mm, double u0) const {
  constexpr double kMargin = 1 - 1e-6;
  const double amax = kMargin * a0_;
  const double vg = ct.vg, c = ct.c;
  // The sample α before j between the step u0 (along E) and u1: the chords d0 = u0·E and
  // d1 = u1·E (u1 ≤ α) or α·E + β·S (β = u1 − α). Per axis |(α − u0)·E_i + β·S_i| ≤ a_i,
  // tangential |u1 − u0| ≤ A0 (path speeds), normal a_n² = 2·u0·(|d1| − α − β·c) ≤ A0² (as in
  // after_corner(), increasing in β), resultant |d1 − d0|² ≤ A0². Each is convex in u1 on
  // u1 ≤ α and on u1 ≥ α, so the ends of both pieces decide.
  auto sample_ok = [&](double alpha, double u1) {
    // (u0 − r·A0 at the low end: the deceleration every braking plan uses.)
    if (u1 - u0 > amax || u0 - u1 > a0_) return false;
    const double al = std::min(alpha, u1), beta = std::max(0.0, u1 - alpha);
    for (std::size_t i = 0; i < 3; ++i) {
      if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
      if (std::abs((al - u0) * ct.e[i] + beta * ct.sd[i]) > kMargin * lim_.axis_amax_pc2[i]) {
        return false;
      }
    }
    if (beta <= 0) return true;
    const double d1 = std::sqrt(std::max(0.0, al * al + beta * beta + 2 * al * beta * c));
    if (2 * u0 * (d1 - al - beta * c) > amax * amax) return false;
    if (lim_.bound_resultant) {
      const double w = al - u0;
      if (w * w + beta * beta + 2 * w * beta * c > amax * amax) return false;
    }
    return true;
  };
  const double p1 = from_mm + u0;
  const double alpha = ct.j - p1;
  // (Not within 10 nm of j: the checker takes a sample that close as reaching the joint.)
  if (!(alpha >= kMinAlphaMm) || p1 < ct.c_mm || u0 - vg > amax) return false;
  const double rho = slowdown_r(ct.slot_a, ct.a_s0, from_mm, p1);
  const double lo = std::max(0.0, std::min(vg, u0 - rho * a0_));
  if (!sample_ok(alpha, vg) || !sample_ok(alpha, lo)) return false;
  return !(alpha > lo && alpha < vg) || sample_ok(alpha, alpha);
}

double AccelLimitedAccDec::centred_top(const Centre& ct, double k_e, double k_s, double m_e,
                                       double m_s) const {
  // Per axis |k·x + m| ≤ a_i with k = k_e·E_i + k_s·S_i, m = m_e·E_i + m_s·S_i: the largest x.
  double top = kInf;
  for (std::size_t i = 0; i < 3; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    const double k = k_e * ct.e[i] + k_s * ct.sd[i], m = m_e * ct.e[i] + m_s * ct.sd[i];
    const double ai = (1 - 1e-6) * lim_.axis_amax_pc2[i];
    if (k > 1e-12) top = std::min(top, (ai - m) / k);
    if (k < -1e-12) top = std::min(top, (-ai - m) / k);
  }
  return top;
}

double AccelLimitedAccDec::centred_step(const Centre& ct, double u, double hi) const {
  // Every feasible step meets the per-axis limits with the crossing u1 = Vg, linear in u0:
  // (α − u0)·E + (Vg − α)·S with α = D − u0 (D = j − tool). Their largest u0 first.
  const double d = ct.j - pos_mm_;
  hi = std::min(hi, centred_top(ct, -2, 1, d, ct.vg - d));
  if (!(hi > u)) return u;
  return largest_ok(u, hi, [&](double x) { return centred_ok(ct, pos_mm_, x); });
}

double AccelLimitedAccDec::committing_step(const Centre& ct, double u, double hi,
                                           double& lo_next) const {
  // The step u_{-1} to p0 may exceed the cap's braking bound when from p0 the centred step
  // lo_next = u_{-1} − r_hi·A0 (the slowest the cycle at p0 can be made to go) is feasible.
  // lo_next = u_{-1} − ρ·A0 (the slowest the cycle at p0 can be made to go, ρ = slowdown_r()
  // of the step) is feasible.
  auto slowest = [&](double x) {
    return x - slowdown_r(ct.slot_a, ct.a_s0, pos_mm_, pos_mm_ + x) * a0_;
  };
  auto ok = [&](double x) {
    const double l = slowest(x);
    return l > 0 && ct.j - (pos_mm_ + x) > ct.vg && centred_ok(ct, pos_mm_ + x, l);
  };
  // The same per-axis limits from p0 = tool + x with u0 = x − ρ·A0: α − u0 = D + 2·ρ·A0 − 3x,
  // Vg − α = Vg − D − ρ·A0 + 2x; ρ between the lowest and the highest r up to j (a search
  // bound only: every answer is checked).
  const double d = ct.j - pos_mm_;
  auto top = [&](double ra) { return centred_top(ct, -3, 2, d + 2 * ra, ct.vg - d - ra); };
  hi = std::min(hi, std::max(top(ct.r_hi * a0_), top(ct.r_lo * a0_)));
  if (!(hi > u)) return u;
  const double best = largest_ok(u, hi, ok);
  if (best > u) lo_next = slowest(best);
  return best;
}

}  // namespace cncore::motion
