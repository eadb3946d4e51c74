// Joint zones: where a turn and a speed change share the same cycles, the acceleration ratio r is
// lowered next to the joint so that both fit the axis limits; sized when the joint arrives and
// sized again for the next joint's cap.
//
// 7. Joint zones: a turn and a speed change in the same cycles. Samples P[k] = p(s_k) on a path
//    with one corner at j (unit tangents E before, S after), steps u1 = s_k − s_{k−1} and
//    u2 = s_{k+1} − s_k with j in [s_{k−1}, s_{k+1}]: with α the part of step 1 after j and β the
//    part of step 2 before j,  P[k+1] − 2P[k] + P[k−1] = (u2 − u1)·S + c·(S − E), c = u1 − α − β,
//    c ∈ [min(0, u1 − u2), u1]. Linear in c: the extremes are c = u1 (a sample on the joint:
//    u2·S − u1·E) and c = min(0, u1 − u2) ((u2 − u1)·S or (u2 − u1)·E: a plain speed change,
//    within the segments' r). |u2·S_i − u1·E_i| is convex in (u1, u2), so over u1, u2 ≤ V,
//    |u2 − u1| ≤ D its maximum is at a vertex: (V, V), (V, V − D), (V − D, V), (D, 0), (0, D):
//        |V·(S_i − E_i)| ≤ a_i (the corner limit), D·|S_i|, D·|E_i| ≤ a_i (the segments' r), and
//        |V·(S_i − E_i) − D·S_i| ≤ a_i,   |V·(S_i − E_i) + D·E_i| ≤ a_i.
//    The corner limit alone uses the whole budget for the turn, the segments' r alone the whole
//    budget for the speed change: on a diagonal path with axis limits = Amax the last two add
//    both on one axis (measured up to 1.38 × the limit at gentle corners). At a reversal
//    (S = −E) or a right angle along the axes they need nothing more. So every joint without a
//    stop gets a *zone* in which r is lowered to r_j = D/A0, D the largest value meeting the
//    last two with V = V0, the corner's passing speed (or the larger of the segments' caps
//    where the corner allows more: the step after the joint starts in b and is bounded by b's
//    cap only — with the smaller one, an arc at 1 µm/cycle into a rapid turned 75° while the
//    step grew to 3 µm, 2 479 mm/s² on a 2 000 axis); a smaller V keeps them (convex in V, and
//    true at V = 0). When D would fall
//    below kZoneFloor·min(r_a, r_b)·A0, D = that floor and the corner is passed slower instead
//    (the largest V meeting both, a joint cap).
//    The zone covers [j − 2V, j + V] (V: the largest step near the joint, V_j or the segments'
//    caps): the speed change u2 − u1 of a pair around j is
//      - for an increase, ≤ A0 × the lowest r over where step 2 can go (step()), and step 2
//        starts in [j − V, j + V];
//      - for a decrease by a braking bound, ≤ A0 × the mean r over step 1 (3. (ii), in the
//        lattice forms the same: (1/2 − ρ)² ≤ 1/4), and step 1 lies in [j − 2V, j + V].
//    The zone is part of σ, so every braking plan already accounts for it; a feed limit is
//    followed exactly (no extra deceleration step) unless the override was just lowered.
//    Decreases and increases need different vertices: a decrease (u2 < u1, c ∈ [0, u1]) has the
//    extremes u2·S − u1·E and (u2 − u1)·S, so only |V·(S_i − E_i) − D·S_i| ≤ a_i and D·|S_i|,
//    D·|E_i| ≤ a_i; an increase (c ∈ [u1 − u2, u1]) only |V·(S_i − E_i) + D·E_i| ≤ a_i and the
//    same two. Decreases come from the braking bounds and an override decrease (σ's mean r over
//    step 1, 3. (ii), 5.), the stop's landing bounds and a hold (the lowest r over the reach or
//    up to the stop, 3., 4.); increases from the reach's r. So without a filter σ takes the
//    zone's r for decreases alone, r_d = D_dec/A0 ≥ r_j (head_rd_, tail_rd_; at the V the zone
//    is sized for, V0 or the one lowered to the floor), and r_span() keeps r_j, the lower of
//    both. On a gentle corner whose turn leans on the speed increase's axis (the decrease
//    relieves it) r_d is far above the floor: line-contouring-xz's 4.8° corners brake at 0.82
//    instead of 0.25 × A0 next to the turn (22.348 → 22.193 s), cam-short-segments 7.279 →
//    7.215, braid_cut2d 20.338 → 20.076.
//    A zone lowers r on the tail of a (and of up to kZoneWalk earlier short segments) when b
//    arrives: σ after the first changed segment moves, so the starts of the later segments,
//    the window's end and the keys of the caps from there on are recomputed with the exact
//    σ(c) (a bounded number of caps per joint). Never under or behind the tool (a late joint).
//    Keys use the exact σ(c) (a σ below the true one lets the bound reach 0 before c, a stall).
//    Not covered: a zone reaching back over more than kZoneWalk segments (tiny segments with a
//    sharp corner: the corner cap then keeps V small, so 2V spans few of them).
//    Chains: when a (and the segment before it) is shorter than a step, one pair of steps can
//    turn from E (the end of the segment before the chain) to S at once, the middle tangent M
//    over length L between. The extremes are then u2·S − u1·E + L·(E − M) (the sample on the
//    last joint, step 1 over the whole chain) and u2·S − u1·E + L·(M − S) (on the first, step 2
//    over it); with M_i = λE_i + (1 − λ)S_i, λ ∈ [0, 1], both are (u2 − u1)·S_i + c·(S_i − E_i)
//    with c = u1 − (1 − λ)L or u1 − λL, inside the range of c above: the vertex bounds hold with
//    E and S, each axis less L·(how far M_i lies outside [E_i, S_i]). So the zone of the chain's
//    last joint also meets them for the turn E → S at the chain's V (the lower of both joints'
//    caps), and reaches back over the middle (the pairs' steps lie in [c − 2V, j + V], c the
//    first corner); below the floor the chain is passed at the V that fits the floor — a cap on
//    both joints — or, if that is below L, at L (no step then skips the middle, and each
//    corner's own zone holds). Sized for the turn alone (the speed change left to the zones of
//    the single corners), a 1.3 µm line between two corners gave 1 407 mm/s² on a 1 400 axis.
//    Longer chains (a polyline fillet, a tiny polygon: many corners within one step) are bounded
//    by the kernel (planner/turn_window.hpp): the joint's speed V keeps V·spread_i ≤ a_i, the
//    spread of the tangent over (j − V, j]; given that spread T, the zone here also meets
//    |Δu|·max|e_i| + V·T_i ≤ a_i and |Δu| + V·|T| ≤ A0 (d_max), and where its reach back over
//    kZoneWalk segments falls short of 2V the chain is passed at what that reach covers.
//
//    change: r only rises, σ and the keys after it are recomputed) and the joint's cap lowered
//    to V', so that the zone's premise holds by the cap whatever comes later. Only plain zones
//    (two lines, no turn-window chain, no filter). line-contouring-xz 22.023 → 21.955 s: a 2°
//    joint 0.25 mm before a 68° corner had its zone sized for 46 µm/cycle. A zone whose tail
//    reached back over up to kRezoneWalk segments keeps their tails as they were before it
//    (LastZone::walk), restored and zoned again for V'; a chain's zone (a shorter than the step,
//    7.) only where V' ≤ a's length, where no step skips a and each corner's own zone holds
//    (line-contouring-xz 21.932 → 21.922 s).
//    That bound carries the lattice's and 11.'s slack (+A0, +2·A0), large where A0 is large
//    against the speeds. Where braking at A0 over b leaves less, V_r = √(vc² + 2·A0·L_b) − A0/2,
//    and a zone sized for it has ≥ 20 % more room for the speed change, the zone is sized for
//    V_r and the joint capped there instead, if the tool can still follow that cap (a choice:
//    a lower cap may cost a cycle's rounding; line-contouring-xz 21.922 → 21.864 s,
//    circle_small_segments 12.517 → 12.435). Forward, a joint's zone is sized the same way for
//    what the caps before it leave, √(vc² + 2·A0·d) (joint_zones(): circle_small 12.276 s,
//    line-contouring-xz 21.848).
//
// Without a filter the tool position is the commanded position and at rest means step 0.
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
constexpr double kRezoneGain = 1.2;  // 13.: a zone sized below its braking bound gains this much D

// Segments shorter than a step between corners (a chain, 7.): tangent at both ends, length,
// sweep (0 on a line).
struct ChainMid {
  AxisVec start_dir, end_dir;
  double len_mm = 0, sweep_rad = 0;
};

// A chain's share of axis i beyond the turn from e to s: with the middle tangent M over length
// L, the extremes of the second difference over the whole chain (7.: a sample on its first or
// last joint, one step over all of it) are u2·S − u1·E + L·(E − M) and u2·S − u1·E + L·(M − S).
// M_i = λE_i + (1 − λ)S_i with λ ∈ [0, 1] makes them (u2 − u1)·S_i + c·(S_i − E_i) with
// c = u1 − (1 − λ)·L or u1 − λ·L, inside 7.'s range of c: the turn from E to S alone. M_i
// outside [E_i, S_i] by ε adds ≤ L·ε (an arc's tangent moves by ≤ its sweep).
double chain_slack(const AxisVec& e, const AxisVec& s, const ChainMid* mid, std::size_t n,
                   std::size_t i) {
  const double lo = std::min(e[i], s[i]), hi = std::max(e[i], s[i]);
  double slack = 0;
  for (std::size_t m = 0; m < n; ++m) {
    const double out = std::max({0.0, mid[m].start_dir[i] - hi, lo - mid[m].start_dir[i],
                                 mid[m].end_dir[i] - hi, lo - mid[m].end_dir[i]});
    slack += mid[m].len_mm * (out + mid[m].sweep_rad);
  }
  return slack;
}

// The largest speed change d ≤ d0 per cycle that a chain from e to s passed at v leaves room
// for (7.'s vertices with E, S and the slack; < 0: the turn alone is too much).
double chain_d_max(const AxisVec& e, const AxisVec& s, const ChainMid* mid, std::size_t n, double v,
                   double d0, const planner::Limits& lim) {
  double d = d0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim.axis_on[i] || lim.axis_amax_pc2[i] <= 0) continue;
    const double ai = lim.axis_amax_pc2[i] - chain_slack(e, s, mid, n, i);
    const double t = v * (s[i] - e[i]);
    if (std::abs(t) > ai) return -1;
    if (std::abs(s[i]) > 1e-12)
      d = std::min(d, std::min(ai, ai + (s[i] > 0 ? t : -t)) / std::abs(s[i]));
    if (std::abs(e[i]) > 1e-12)
      d = std::min(d, std::min(ai, ai - (e[i] > 0 ? t : -t)) / std::abs(e[i]));
  }
  return d;
}

// The largest V at which a chain from e to s leaves room for a speed change d (linear in V:
// |V·Δ_i − d·S_i|, |V·Δ_i + d·E_i| ≤ a_i − slack, Δ = S − E); 0 where even V = 0 does not.
double chain_speed_pc(const AxisVec& e, const AxisVec& s, const ChainMid* mid, std::size_t n,
                      double d, const planner::Limits& lim) {
  double v = kInf;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim.axis_on[i] || lim.axis_amax_pc2[i] <= 0) continue;
    const double ai = lim.axis_amax_pc2[i] - chain_slack(e, s, mid, n, i);
    // (d ≤ a_i/|S_i| is what the segments' r gives, up to rounding: a relative margin.)
    if (d * std::max(std::abs(s[i]), std::abs(e[i])) > ai * (1 + 1e-9)) return 0;
    const double delta = s[i] - e[i];
    if (std::abs(delta) <= 1e-12) continue;
    const double sg = delta > 0 ? 1.0 : -1.0;
    v = std::min({v, ai / std::abs(delta), (ai + d * s[i] * sg) / std::abs(delta),
                  (ai - d * e[i] * sg) / std::abs(delta)});
  }
  return std::max(v, 0.0);
}

bool straight_joint(const AxisVec& u, const AxisVec& w) {
  double q = 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) q += (u[i] - w[i]) * (u[i] - w[i]);
  return q <= 1e-18;
}
}  // namespace

double AccelLimitedAccDec::plain_zone_d(const AxisVec& e, const AxisVec& s, double r_hi, double v,
                                        bool decreases_only) const {
  // 7.'s vertices between two lines (joint_zones()' d_max() without arcs or chains).
  double d = r_hi * a0_;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    const double ai = lim_.axis_amax_pc2[i];
    const double t = v * (s[i] - e[i]);
    if (std::abs(t) > ai) return -1.0;
    if (std::abs(s[i]) > 1e-12) {
      d = std::min(d, std::min(ai, ai + (s[i] > 0 ? t : -t)) / std::abs(s[i]));
    }
    if (std::abs(e[i]) > 1e-12) {
      d = std::min(d,
                   (decreases_only ? ai : std::min(ai, ai - (e[i] > 0 ? t : -t))) / std::abs(e[i]));
    }
  }
  return d;
}

// Size: 13.'s resizing in one pass (the new V, the restored tails, the new zone, σ and the cap),
// each step using the one before.
bool AccelLimitedAccDec::rezone_before(const LastZone& z, std::uint64_t index_b, double vc) {
  // 13. The zone of the joint j_a at b's start was sized for the speed V the tool may have
  // there. The cap vc of the joint j_b at b's end, now known, bounds every step over
  // [j_a − 2V', j_a + V'] by its braking bound (3.: x ≤ √(A0² + vc² + 2·A0·(j_b − s)) − A0
  // at s, σ(j_b) − σ(s) ≤ j_b − s), plus 2·A0 for 11.'s steps above it. Where that V' is well
  // below V and the tool has not reached the zone yet, the zone is sized again for V' (shorter,
  // with more room for the speed change) and j_a's cap lowered to V' (the zone's premise then
  // holds by the cap, as in the forward case). Only a plain zone (two lines, no turn-window
  // chain, no filter, b's head set by this joint alone) or a chain's where V' ≤ a's length.
  if (!z.valid || z.index_a + 1 != index_b || late_hold_ || z.n_walk == 0) return false;
  const std::uint64_t ia = z.index_a;
  const std::uint64_t first = z.walk[z.n_walk - 1].index;
  if (first < buf_.begin_index() || first < cur_) return false;
  // (The old zone, [j − 2V − its chain's middle, j], ahead of the tool too: σ under the tool is
  // in use.)
  if (!(z.j_mm - 2 * z.v - z.chain_mm > pos_mm_ + 2 * (step_ + a0_))) return false;
  const Segment& a = buf_[ia];
  const Segment& b = buf_[index_b];
  if (a.kind != ItemKind::kMotion || b.kind != ItemKind::kMotion) return false;
  double v = z.v;
  for (int it = 0; it < 8; ++it) {
    const double reach =
        std::sqrt(vc * vc + a0_ * a0_ + 2 * a0_ * (b.end_mm() - (z.j_mm - 2 * v))) + 2 * a0_;
    if (reach >= v) break;
    v = reach;
  }
  // The speed the tool can reach at j_a braking at A0 for vc over b, √(vc² + 2·A0·L_b), is far
  // below that bound where A0 is large against the speeds (a 13.6° joint 10.4 µm before a 55°
  // corner of line-contouring-xz: 6.8 against 14.8 µm/cycle). Sized and capped a little below
  // it, V_r = that − A0/2, the zone's speed change is the larger one of the lower V; the cap
  // costs a cycle's rounding where the tool would have passed faster, so only where it raises
  // the zone's D by 20 % or more (a choice, not a bound: each V with its cap is sound; on
  // line-contouring-xz and circle_small_segments it gains 0.3–0.7 %). Only where the tool can
  // follow the new cap (its key's bound at the tool, with σ as now — the new zone only raises r —
  // is at least the last step, 3. (ii)), and no committed step of 11. or step on 10.'s curve relies
  // on what is ahead.
  double d = -1;  // plain_zone_d() at v, once computed
  if (const double v_r = std::max(vc, std::sqrt(vc * vc + 2 * a0_ * b.length_mm) - 0.5 * a0_);
      v_r < v && !commit_.valid && relied_e_mm_ == kInf) {
    const double d_r = plain_zone_d(z.e, z.s, z.r_hi, v_r, false);
    if (d_r >= kRezoneGain * std::max(z.floor, plain_zone_d(z.e, z.s, z.r_hi, v, false))) {
      // The cap's key (3., either form insert_joint_cap() may choose) at the tool.
      const double sc = sigma_at(z.j_mm - v_r), sp = sigma_at(pos_mm_);
      const double h = v_r - 0.5 * a0_;
      if (sc > sp && brake(v_r * v_r + 2 * a0_ * sc, sp) >= step_ &&
          lattice(h * h + 2 * a0_ * sc, sp) >= step_) {
        v = v_r;
        d = d_r;
      }
    }
  }
  if (!(v < 0.95 * z.v)) return false;
  // A chain's zone (7.): at V' within its middle, a (no step skips it), each corner's own zone
  // holds, and this one is plain.
  if (z.chain_mm > 0 && !(v <= a.length_mm)) return false;
  // Every pair that may span j_a is still to come, each under j_b's cap.
  if (!(z.j_mm - 2 * v > pos_mm_ + 2 * (step_ + a0_))) return false;
  if (d < 0) d = plain_zone_d(z.e, z.s, z.r_hi, v, false);
  if (!(d >= z.floor)) return false;
  const double rj = std::max(d / a0_, 1e-6);
  const double rjd = std::max(rj, std::max(d, plain_zone_d(z.e, z.s, z.r_hi, v, true)) / a0_);
  const std::size_t sa = buf_.slot(ia), sb = buf_.slot(index_b);
  // A joint without a cap gets one only between segments of a step or more (as in 7.).
  const std::uint32_t g = owner_[3 * sb + 2];
  if (g == kNone) {
    double turn = 0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) turn = std::max(turn, std::abs(z.s[i] - z.e[i]));
    if (!(z.v * turn >= 0.25 * a0_ && a.length_mm >= 2 * v && b.length_mm >= v)) return false;
  }
  const bool zoned = rj < z.r_top;
  // The tails as they were before the zone (each walked segment), then the new zone's
  // [j − 2V', j] over them (shorter: a part of the same segments).
  const double zone_start = z.j_mm - 2 * v;
  for (std::size_t w = 0; w < z.n_walk; ++w) {
    const WalkedTail& t = z.walk[w];
    const std::size_t sx = buf_.slot(t.index);
    tail_mm_[sx] = t.mm;
    tail_r_[sx] = t.r;
    tail_rd_[sx] = t.rd;
    const Segment& x = buf_[t.index];
    if (zoned && x.end_mm() > zone_start) {
      const double covered = x.end_mm() - std::max(zone_start, x.s0_mm);
      tail_r_[sx] = t.mm > 0 ? std::min(t.r, rj) : rj;
      tail_rd_[sx] = t.mm > 0 ? std::min(t.rd, rjd) : rjd;
      tail_mm_[sx] = std::max(t.mm, covered);
    }
    refresh_pieces(sx);
    update_r(t.index);
  }
  head_mm_[sb] = zoned ? std::min(b.length_mm, v) : 0.0;
  head_r_[sb] = zoned ? rj : 1.0;
  head_rd_[sb] = zoned ? rjd : 1.0;
  refresh_pieces(sb);
  update_r(index_b);
  resigma(z.walk[z.n_walk - 1].index, index_b);
  if (v < (g != kNone ? caps_[g].v : kInf)) {
    insert_joint_cap(sa, sb, z.j_mm, a.length_mm, v);
    if (prev_.valid && prev_.index_a == ia) prev_.vg = std::min(prev_.vg, v);
  }
  return true;
}

// Size: the zone of one joint (7.) from its cases in the derivation's order: the corner's
// speed, the chain before it, the vertex bounds, the floor and the joint cap, the walk back
// over earlier short segments and the late-block test before anything is applied. Each case
// reads and narrows the same joint state (directions, V, D, the zone's extent).
void AccelLimitedAccDec::joint_zones(std::uint64_t index_a, std::size_t slot_b, const Segment& b) {
  const LastZone zone_before = last_zone_;
  last_zone_.valid = false;
  const Segment& a = buf_[index_a];
  const std::size_t sa = buf_.slot(index_a);
  // (Directions and corner speed from the kernel when it computed them for this joint.)
  const bool given = corner_index_a_ == index_a;
  const AxisVec e = given ? corner_e_ : a.end_direction();
  const AxisVec s = given ? corner_s_ : b.start_direction();
  const AxisVec a_start = a.start_direction();  // (on_joint() needs it too)
  const double r_ab = std::min(ratio_[sa], ratio_[slot_b]);
  // A pair of steps around the joint changes speed by up to the r of either side: an increase
  // by the r where step 2 goes (all in b when the sample is on the joint), a decrease by the r
  // of step 1 (all in a). So the larger of both must fit in the other's direction too.
  const double r_hi = std::max(ratio_[sa], ratio_[slot_b]);
  const double around = std::max(vcap_[sa], vcap_[slot_b]);  // as in on_joint
  const double corner = given ? corner_pc_ : planner::joint_speed_pc(a, b, lim_, false);
  corner_index_a_ = ~std::uint64_t{0};
  double v0 = std::min(around, corner);
  // After a capped joint close before (at a's start, chained; no filter) the tool cannot be
  // faster here than it can get from that cap: ≤ √(Vp² + 2·A0·d) + 2·A0 within d of it
  // (accelerating from ≤ Vp, or braking towards it, 3.), d ≤ L_a + 2V over the zone. A short
  // segment between a sharp and a gentle corner otherwise got the gentle one's zone sized for
  // the segments' caps (0.1 mm of line-contouring-xz braked at 0.22·A for a 3.6 µm segment).
  // Used as V it becomes this joint's cap (on_joint), so the zone's premise holds either way.
  // Also at a joint with no cap of its own (a gentle turn the top speed passes): its zone, sized
  // for the segments' caps, reached 2·V_top back over the braking for the corner before it
  // (0.33 mm at 0.3·A0 before a 30° corner of line-contouring-xz: 22.061 → 22.023 s).
  if (lag_ == 0 && prev_.valid && prev_.index_b == index_a) {
    const double vp = prev_.vg / 0.999;  // its cap, or the caps around it when it had none
    double v = v0;
    for (int it = 0; it < 8; ++it) {
      const double reach = std::sqrt(vp * vp + 2 * a0_ * (a.length_mm + 2 * v)) + 2 * a0_;
      if (reach >= v) break;
      v = reach;
    }
    // (A joint without a cap gets one only where its turn at the top speed takes a quarter of
    // A0 or more, between segments of a step or more: a cap at every joint of tiny segments,
    // several per cycle, each entering and leaving the trees, cost stress_test 40 % of its step
    // rate, and at the straight joints of long merged lines 20 %.)
    double turn = 0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) turn = std::max(turn, std::abs(s[i] - e[i]));
    if (corner < around ||
        (around * turn >= 0.25 * a0_ && a.length_mm >= 2 * v && b.length_mm >= v)) {
      v0 = v;
    }
  }
  // At gentle corners the segments' caps (the machine's top speed) are far above a CAM
  // program's feed, and the zone sized for them let the speed change by little more than the
  // floor's share (bench/README (c)). Sized for F instead, with a joint cap of F so that it
  // holds at any override: F the highest feed of the segments the pairs around the joint can
  // start in, [j − (2 + reach_lag)·V, j + V] (b at least V long, the walk back over at most
  // kZoneWalk segments ahead of the tool's), so that at ≤ 100 % the cap costs nothing. Only
  // where that leaves the speed change more room (below). Sizing for OR_max·F without a cap
  // instead changed nothing on the built-in machine (200 % of F 6 000 is above its top speed).
  const double v_feed = [&] {
    double vf = std::max(a.feed_pc, b.feed_pc);
    if (!(b.length_mm >= vf)) return kInf;
    double from = a.s0_mm;
    std::size_t walked = 0;
    for (std::uint64_t k = index_a; from > a.end_mm() - (2 + reach_lag_) * vf;) {
      if (k <= std::max(cur_, buf_.begin_index())) return kInf;  // the tool's segment
      const Segment& x = buf_[--k];
      if (x.kind != ItemKind::kMotion) {
        if (x.barrier) break;  // a stop: no step crosses it
        continue;
      }
      if (++walked > kZoneWalk) return kInf;
      vf = std::max(vf, x.feed_pc);
      from = x.s0_mm;
    }
    return vf;
  }();
  // Arcs next to the joint: a step of length u on an arc of curvature κ leaves its tangent's
  // line by R(1 − cos φ) ≤ u²κ/2 along the normal N (φ = uκ) and falls short along it by
  // u − R sin φ ≤ u³κ²/6; N turns by ≤ uκ over the step. Per axis ≤ (u²κ/2)(|N_i| + uκ·h_i)
  // + u³κ²/6 (h_i: the axis' share of the arc plane), from each side (7.).
  struct ArcSide {
    double k = 0;                    // curvature 1/ρ; 0: not an arc
    std::array<double, 3> n{}, h{};  // |N_i| at the joint, the axis' share of the plane
  };
  auto arc_side = [](const Segment& x, double phi) {
    ArcSide side;
    if (!x.arc || x.rho_mm <= 0) return side;
    side.k = 1.0 / x.rho_mm;
    const Vec3 nrm = std::cos(phi) * x.e1 + std::sin(phi) * x.e2;
    for (std::size_t i = 0; i < 3; ++i) {
      side.n[i] = std::abs(component(nrm, i));
      side.h[i] = std::hypot(component(x.e1, i), component(x.e2, i));
    }
    return side;
  };
  const ArcSide side_a = arc_side(a, a.sweep_rad), side_b = arc_side(b, 0.0);
  auto sag = [](const ArcSide& x, double v, std::size_t i) {
    if (x.k == 0 || i >= 3) return 0.0;
    const double k = x.k;
    return 0.5 * v * v * k * (x.n[i] + v * k * x.h[i]) + v * v * v * k * k / 6.0;
  };
  // Headroom per axis left by the turn at speed v (7.): with both steps ≤ V and |u2 − u1| ≤ D
  // the worst second differences are V·(S_i − E_i) − D·S_i, V·(S_i − E_i) + D·E_i, D·S_i and
  // D·E_i, each plus the arcs' sag; the largest D meeting all (< 0: the turn alone is too much).
  // A chain of short segments (the tangent's spread over the window before the joint,
  // planner/turn_window.hpp, beyond this corner's own turn): a pair of steps ≤ V whose window
  // ends here sees |Δu|·|e_i| + V·T_i on axis i (e_i the tangent somewhere in the window, ≤ its
  // largest |e_i|) and |Δu| + V·T as a whole; T taken at the kernel's speed, ≥ every V used
  // here (a shorter window has no more spread).
  const planner::Turn chain_turn = given ? corner_turn_ : planner::Turn{};
  const bool chained = [&] {
    double own2 = 0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) own2 += (s[i] - e[i]) * (s[i] - e[i]);
    // (A spread beyond the corner's own that adds less than 0.01 % of A0 at the corner speed,
    // the wobble of a line cut into pieces with rounded coordinates, is left to the margins.)
    return (chain_turn.total - std::sqrt(own2)) * corner > 1e-4 * a0_;
  }();
  // A decrease (u2 < u1) meets only the first vertex and D·|S_i|, D·|E_i| ≤ a_i (its extremes
  // over c ∈ [0, u1] are u2·S − u1·E and (u2 − u1)·S), an increase only the second (c ∈
  // [u1 − u2, u1]: u2·S − u1·E and (u2 − u1)·E): decreases_only gives the decrease's D.
  auto d_max = [&](double v, bool decreases_only = false) {
    double d = r_hi * a0_;
    if (chained) {
      if (v * chain_turn.total > a0_) return -1.0;
      d = std::min(d, a0_ - v * chain_turn.total);
    }
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
      const double ai = lim_.axis_amax_pc2[i] - sag(side_a, v, i) - sag(side_b, v, i);
      if (chained) {
        const double tc = v * chain_turn.axis[i];
        if (tc > ai) return -1.0;
        const double m = chain_turn.top[i];  // the largest |tangent_i| in the window
        if (m > 1e-12) d = std::min(d, (ai - tc) / m);
      }
      const double t = v * (s[i] - e[i]);
      if (std::abs(t) > ai) return -1.0;
      if (std::abs(s[i]) > 1e-12) {
        d = std::min(d, std::min(ai, ai + (s[i] > 0 ? t : -t)) / std::abs(s[i]));
      }
      if (std::abs(e[i]) > 1e-12) {
        d = std::min(
            d, (decreases_only ? ai : std::min(ai, ai - (e[i] > 0 ? t : -t))) / std::abs(e[i]));
      }
    }
    return d;
  };
  double d = d_max(v0);
  // Only where the feed leaves the speed change more room than the passing speed does (at
  // 100 % the cap then costs nothing; where the zone allows the segments' r anyway it would
  // only add a cap that holds the corner at F above 100 %).
  if (v_feed < v0) {
    const double d_feed = d_max(v_feed);
    if (d_feed > 1.001 * d) {
      v0 = v_feed;
      d = d_feed;
    }
  }
  // Forward, what the caps before can leave here (13.'s counterpart): from a cap vc at j_c the
  // tool accelerating at A0 reaches about √(vc² + 2·A0·(j − j_c)) at j (the discrete steps
  // vc + k·A0 land below it: u_k² = vc² + 2·A0·D_k − k·A0²); the minimum over the caps before
  // is kept as one running square (reach_sq_, + 2·A0·L per segment, reset where the joints are
  // not consecutive). Sized and capped there where that gives the zone ≥ 20 % more room for the
  // speed change (a choice, as in 13.: the cap makes it hold; A0/2 below it, as 13. takes,
  // slowed vcarve by 1.4 s). Only at joints with a corner cap of their own, between lines,
  // without a filter. circle_small_segments 12.435 → 12.276 s.
  const double reach_sq = reach_b_ == index_a ? reach_sq_ + 2 * a0_ * a.length_mm : kInf;
  if (lag_ == 0 && reach_sq < kInf && corner < around && !a.arc && !b.arc) {
    const double v_r = std::sqrt(reach_sq);
    if (v_r < v0 && v_r > 0) {
      const double d_r = d_max(v_r);
      if (d_r >= kRezoneGain * std::max(d, kZoneFloor * r_ab * a0_)) {
        v0 = v_r;
        d = d_r;
      }
    }
  }
  double vj = v0;
  const double floor = kZoneFloor * r_ab * a0_;
  if (d < floor) {
    // Too little left: the corner is passed slower instead, so that Δu ≤ floor fits. Without
    // the sag the bound is linear in V: |V·Δ_i − F·S_i| ≤ a_i and |V·Δ_i + F·E_i| ≤ a_i
    // (Δ = S − E, F = floor; true at V = 0); the sag, growing with V, is then met by bisection.
    d = floor;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
      const double delta = s[i] - e[i];
      if (std::abs(delta) <= 1e-12) continue;
      const double sg = delta > 0 ? 1.0 : -1.0, ai = lim_.axis_amax_pc2[i];
      vj = std::min(vj, (ai + d * s[i] * sg) / std::abs(delta));
      vj = std::min(vj, (ai - d * e[i] * sg) / std::abs(delta));
    }
    vj = std::max(vj, 0.0);
    if (d_max(vj) < floor) {
      double lo = 0, hi = vj;  // d_max(0) ≥ floor: r_ab·A0·|S_i|, r_ab·A0·|E_i| ≤ a_i
      for (int it = 0; it < 40; ++it) (d_max(0.5 * (lo + hi)) >= floor ? lo : hi) = 0.5 * (lo + hi);
      vj = lo;
    }
  }
  // The speed decreases' D at the speed the zone is sized for (vj: v0, or lowered to the floor;
  // a smaller V keeps it, convex in V and true at V = 0), ≥ d; chains below lower it too.
  double d_dec = std::max(d, d_max(vj, true));
  // Two or three corners within one step (a and the segment x before it shorter than the step,
  // on_joint()): a pair of steps may turn from x's end (or the end of the one before x) to b at
  // once while the speed changes. Its zone: d also meets 7.'s vertices for that turn at the
  // chain's V (chain_d_max()), over [c − 2V, j + V] (c the chain's first corner, so the zone
  // reaches back over the middle segments too). Where that leaves less than the floor, the
  // chain is passed slower (chain_speed_pc(), the cap of both joints) or, below the middle's
  // length, at most that (no step then skips a middle segment, and each corner's own zone
  // holds). The turn alone at the chain's V used the whole axis budget before: 1 407 mm/s² on
  // a 1 400 axis over a 1.3 µm line between two corners.
  zone_chain_vg_ = kInf;
  double chain_mm = 0;
  double r_top = r_hi;
  if (prev_.valid && prev_.index_b == index_a && a.length_mm < vj && !straight_joint(e, s)) {
    const double xr = prev_.index_a >= buf_.begin_index() ? ratio_[buf_.slot(prev_.index_a)] : 1.0;
    r_top = std::max(r_hi, xr);
    ChainMid mids[2] = {
        {prev_.a_start_dir, prev_.end_dir, prev_.a_len_mm, prev_.a_sweep_rad},
        {a_start, e, a.length_mm, a.arc && a.rho_mm > 0 ? a.length_mm / a.rho_mm : 0.0}};
    auto chain = [&](const AxisVec& from, const ChainMid* m, std::size_t n, double v_in) {
      double mid_mm = 0;
      for (std::size_t k = 0; k < n; ++k) mid_mm += m[k].len_mm;
      const double vc = std::min(v_in, planner::turn_speed_pc(from, s, lim_));
      if (!(vc > mid_mm)) return;  // steps ≤ the middle: each corner's own zone holds
      chain_mm = std::max(chain_mm, mid_mm);
      const double dc = chain_d_max(from, s, m, n, vc, r_top * a0_, lim_);
      if (dc >= floor) {
        d = std::min(d, dc);
        d_dec = std::min(d_dec, dc);
        return;
      }
      const double vf = chain_speed_pc(from, s, m, n, floor, lim_);
      if (vf > mid_mm) {
        zone_chain_vg_ = std::min(zone_chain_vg_, vf);
        const double df = std::max(floor, chain_d_max(from, s, m, n, vf, r_top * a0_, lim_));
        d = std::min(d, df);
        d_dec = std::min(d_dec, df);
      } else {
        zone_chain_vg_ = std::min(zone_chain_vg_, mid_mm);
        d_dec = d;  // (each corner's own zone: the joint's d)
      }
    };
    if (!straight_joint(prev_.end_dir, a_start)) {
      chain(prev_.end_dir, &mids[1], 1, std::min(prev_.vg, vj));
    }
    if (prev_.short_a && !straight_joint(prev_.end_dir2, prev_.a_start_dir)) {
      chain(prev_.end_dir2, mids, 2, std::min({prev_.vg2, prev_.vg, vj}));
    }
    vj = std::min(vj, zone_chain_vg_);
  }
  // A chain's zone must reach back over [j − (2 + reach_lag)·V, j]; the walk below covers at most
  // kZoneWalk segments, so where they are shorter the chain is passed slower instead.
  if (chained && d < r_top * a0_) {
    double from = a.end_mm();
    std::size_t walked = 0;
    bool limited = false;
    for (std::uint64_t k = index_a + 1; k-- > std::max(cur_, buf_.begin_index());) {
      if (!buf_.is_motion(k)) {
        if (buf_[k].barrier) break;
        continue;
      }
      if (walked == kZoneWalk) {
        limited = true;
        break;
      }
      from = buf_[k].s0_mm;
      ++walked;
      if (from <= a.end_mm() - (2 + reach_lag_) * vj) break;
    }
    if (limited) vj = std::min(vj, (a.end_mm() - from) / (2 + reach_lag_));
  }
  // The joint's cap: the passing speed, or lower where the floor or a chain needs it.
  const double cap_v = std::min(vj, zone_chain_vg_);
  // 13. This joint's cap bounds the speed over the zone of the joint before it.
  if (lag_ == 0) {
    const double vc = std::min({corner, around, cap_v});
    if (vc < 0.999 * around) rezone_before(zone_before, index_a, vc);
    reach_sq_ = std::min(reach_sq, vc * vc);
    reach_b_ = index_a + 1;
  }
  zone_vg_ = cap_v;
  zone_joint_pc_ = corner;
  zone_index_a_ = index_a;
  zone_e_ = e;
  zone_s_ = s;
  zone_a_start_ = a_start;
  const double rj = std::max(d / a0_, 1e-6);
  // σ's r (decreases, 3. (ii)): without a filter only (with one, the output averages both).
  const double rjd = lag_ == 0 ? std::max(rj, d_dec / a0_) : rj;
  // Every step within V of the joint is ≤ V: the joint cap's Vg when there is one, else the
  // segments' caps.
  const double v = std::min(cap_v < 0.999 * around ? cap_v : around, v_feed);
  const double zone_from = a.end_mm() - (2 + reach_lag_) * v - chain_mm;
  if (late_check_ && !late_hold_) {
    // The block's range caps and the joint cap on_joint() will set (6.), with σ(c) no higher
    // than the zone below leaves it (r ≥ min(r_lo, r_j) over [zone start, c]).
    Cap joint_cap{0, 0, 0, 0, false, false};
    const double vg = std::min({corner, around, cap_v});
    if (vg < 0.999 * around) {
      const double w = vg * (1 + cap_lag_);
      joint_cap = {a.end_mm() - w, a.end_mm() + w, vg, 0, false, vg >= a0_};
    }
    check_late(a.end_mm(), std::max(zone_from, pos_mm_), rj < r_hi ? rj : 1,
               vg < 0.999 * around ? &joint_cap : nullptr, index_a);
    if (!late_hold_ && rj < r_hi && step_ > 0) {
      // The zone also lowers σ between the tool and the stop it brakes for: that stop's lattice
      // bound (3.) must still allow the last step. Taken at the joint, not at b's end: a hold
      // that on_joint()'s cap for two corners in one cycle may still start (insert()) keeps the
      // stop there (found: 2 011.7 mm/s² with a 1 µm segment between a reversal and 8°).
      const double zs = std::max(zone_from, pos_mm_);
      const double sigma_j = std::min(
          sigma_at(a.end_mm()), sigma_at(zs) + std::min(rj, r_zone_.min()) * (a.end_mm() - zs));
      const double d_sigma = std::max(0.0, sigma_j - late_sigma_p_);
      if (std::sqrt(a0_ * a0_ / 4 + 2 * a0_ * d_sigma) - a0_ / 2 < step_) start_hold(a.end_mm());
      // And the landing bounds in real distance, which take the zones' r (3.).
      check_stop(b.end_mm(), a.end_mm(), std::min(rj, ratio_[slot_b]));
    }
  }
  if (rj >= r_top) return;  // the segments' own r already fits (rjd ≥ rj)
  // The zone [j − 2V, j] may reach back over several short segments (at most kZoneWalk): each
  // gets it as (part of) its tail zone. Never under or behind the tool (σ there is in use; a
  // late joint, see 6.).
  // (While a late block is held the tool stops at hold_mm_: no zone behind it.)
  const double zone_start = std::max(zone_from, late_hold_ ? hold_mm_ : pos_mm_);
  std::uint64_t first = index_a + 1;
  std::size_t walked = 0;
  std::array<WalkedTail, kRezoneWalk> walk{};
  for (std::uint64_t k = index_a + 1;
       k-- > std::max(cur_, buf_.begin_index()) && walked < kZoneWalk;) {
    const Segment& x = buf_[k];
    if (x.kind != ItemKind::kMotion) {
      if (x.barrier) break;
      continue;
    }
    if (x.end_mm() <= zone_start) break;
    const std::size_t sx = buf_.slot(k);
    const double covered = x.end_mm() - std::max(zone_start, x.s0_mm);
    if (walked < kRezoneWalk) walk[walked] = {k, tail_mm_[sx], tail_r_[sx], tail_rd_[sx]};
    if (tail_mm_[sx] > 0) {
      tail_r_[sx] = std::min(tail_r_[sx], rj);
      tail_rd_[sx] = std::min(tail_rd_[sx], rjd);
    } else {
      tail_r_[sx] = rj;
      tail_rd_[sx] = rjd;
    }
    tail_mm_[sx] = std::max(tail_mm_[sx], covered);
    refresh_pieces(sx);
    update_r(k);
    first = k;
    ++walked;
  }
  const double head = (1 + reach_lag_) * v;
  add_head(slot_b, std::min(b.length_mm, head), rj, rjd);
  // (A plain zone, or a chain's: the walk covered it whole, over motion items only.)
  if (lag_ == 0 && !a.arc && !b.arc && !chained && walked >= 1 && walked <= kRezoneWalk &&
      first + walked == index_a + 1 && zone_start == zone_from && zone_from >= buf_[first].s0_mm) {
    last_zone_ = {true, index_a, a.end_mm(), v, r_hi, r_top, floor, e, s, walk, walked, chain_mm};
  }
  if (lag_ > 0 && head > b.length_mm) carry(a.end_mm() + head, rj);
  if (first > index_a) return;
  resigma(first, index_a);
}

}  // namespace cncore::motion
