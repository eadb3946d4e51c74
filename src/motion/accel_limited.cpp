// Acceleration-limited acc/dec before interpolation: the design and the block side (arrival of
// segments and joints, retirement).
//
// The derivation is split over the files that compute it:
//   1.–5., 8.  below: caps, σ, the backward pass in closed form, the cycle, feed caps and the
//              override, the jerk stage and the post filter;
//   6., 14.    accel_limited_late.cpp: blocks arriving while the tool brakes for the window's end,
//              a stop requested at a block end;
//   7., 13.    accel_limited_zones.cpp: joint zones, sized when the joint arrives and again for the
//              next joint's cap;
//   9., 11., 12. accel_limited_corners.cpp: the cycle after a capped corner, centred corners, rises
//              across one joint;
//   10.        accel_limited_bounds.cpp: braking on an arc with what the speed leaves.
// The cap pools and key trees are in accel_limited_caps.cpp, σ and the acceleration ratio r in
// accel_limited_sigma.cpp, the cycle itself in accel_limited_step.cpp.
//
// Units: path positions s in mm, the step u (the distance moved in one cycle, i.e. the speed in
// mm/cycle), accelerations in mm/cycle². A0 = Amax·τ² is the path acceleration limit.
//
// 1. Caps. Every speed limit of the look-ahead window is a *cap* (V, [c, e)): every cycle whose
//    step starts in [c, e), and every step that lands at or after c, is ≤ V.
//      - segment speed cap: V = Vb (shape, per-axis speed), [c, e) = the segment [s0, end);
//      - feed cap: V = F (times the runtime override OR), [s0, end);
//      - joint cap at a corner at path position j: V = Vg, [j − Vg, j + Vg). Not just the step
//        that crosses j: the step before it and the step after it are ≤ Vg too, so the cycle
//        that turns the corner is not also a cycle of speed change (the checker measures the
//        direction change from two consecutive chords: with chords Vg and Vg + A0 the measured
//        normal acceleration is √(1 + A0/Vg) times the corner's, up to √3 at a reversal).
//    Consecutive segments with the same cap share one cap (its e is moved on), so a fine CAM
//    path pays no per-segment work beyond one tree update per block.
//    Stops (the end of the window, the end of the program, dwell and waiting M-codes) come in
//    every cycle as CycleInput::stop_mm.
//
// 2. Variable acceleration, σ. A segment may allow less than A0: a line whose axis share d_i
//    times A0 exceeds axis i's limit a_i (A_seg = min(A0, a_i/d_i)), and an arc where the normal
//    acceleration v²/ρ and the tangential one share an axis (|a_axis| ≤ √(a_t² + a_n²) times the
//    axis share of the arc plane; with the resultant option bounded by Amax). On an arc we allow
//    a_n ≤ min(v_top²/ρ, 0.95·g) (v_top the highest speed the arc can be run at, g the tightest
//    axis limit over its share), so Vb = √(ρ·a_n), and a_t = min(A0, √(g² − a_n²)).
//    With r = A_seg/A0 ∈ (0, 1] per segment, define the acceleration-weighted path coordinate
//        σ(s) = ∫ r ds        (σ advances r·L over a segment of length L).
//    Braking at A_seg along s is braking at A0 along σ: d(v²)/dσ = 2·A_seg/r = 2·A0. So a speed
//    v at σ_s can still be brought down to V at σ_c iff   v² + 2·A0·σ_s ≤ V² + 2·A0·σ_c = K.
//    K is fixed when the cap arrives: it depends neither on s nor on the current state.
//
// 3. Backward pass in closed form. The braking constraint of every cap ahead is
//        v² + 2·A0·σ(s) ≤ K_i,   K_i = V_i² + 2·A0·σ(c_i),
//    so all caps ahead act through min_i K_i — a minimum over a sliding window (caps enter at
//    the back as blocks arrive and retire as the tool passes them). Here: tournament trees over
//    the caps' ids (planner::MinTree, O(log n) per cap, O(1) to read); no backward pass over
//    the window and no walk per cycle. The lowest r over a step's span (4.) is a range minimum
//    over the buffer slots (two more trees), so a step over many tiny segments costs O(log n).
//    Discrete form: a step x from s lands at q = s + x with σ(q) ≤ σ(s) + x (r ≤ 1), so
//        x² + 2·A0·(σ(s) + x) ≤ K   ⇔   x ≤ B(K, s) = √(A0² + K − 2·A0·σ(s)) − A0.
//    (i) A step that lands at or after c has σ(q) ≥ σ(c), hence x² ≤ V²: it meets V.
//    (ii) Following the bound is always possible: let x_k = B(K, s_k) exactly, R_k = K − 2A0σ_k
//        = x_k² + 2A0·x_k. The step moves σ by r·x_k, so R_{k+1} = x_k² + 2A0·x_k·(1 − r) and
//        x_{k+1} = √(A0² + R_{k+1}) − A0 ≥ x_k − r·A0 (square both sides: A0²(1−r)² ≤ A0²).
//        A step below the bound leaves more room, so the next bound is ≥ (this step) − r·A0:
//        the deceleration it asks for never exceeds the segment's A_seg = r·A0. The minimum of
//        several such bounds has the same property.
//    (iii) A cap is *active* (its plain V applies) for steps starting in [e_c, e), e_c its
//        entry; before e_c it acts through its K. At the point with σ(c) − σ(p) = V the bound
//        is exactly V (√(A0² + V² + 2·A0·V) − A0 = V, and in the lattice form below
//        √((V − A0/2)² + 2·A0·V) − A0/2 = V), so e_c is that point (entry_mm(); ≤ c − V as
//        r ≤ 1): switching to V there never needs a deceleration step, and from there every
//        step ≤ V meets the cap. (At c the bound is √(A0² + V²) − A0, 0.09·V for V = 0.3·A0:
//        with e_c = c the tool crawled towards a small cap in a zone of low r, 2.6 → 0.4
//        µm/cycle over 10 cycles before a 68° corner of cap 1.8 on line-contouring-xz.) On an
//        arc where 10. applies e_c stays at c (c − V for a lattice key): 10.'s curve ends at the
//        first entry, and the later, lower one leaves it more (arc_time 4.102 → 4.092 s).
//    Stops use the exact lattice form instead (V = 0 would never be reached with (ii)):
//        (x + A0/2)² ≤ A0²/4 + 2·A0·(σ(stop) − σ(s)).
//    Following it the steps are x, x − A0, …, A0 with the last step landing exactly on the
//    stop (the sum of A0 + 2A0 + … + n·A0 = n(n+1)A0/2 is exactly the right side's distance);
//    with r < 1 the decrement is ≤ r·A0 ((1/2 − r)² ≤ 1/4). The step that reaches the stop is
//    clipped to land on it (≤ A0: P4's arrival at ≤ Amax·τ), so the last sample is the stop.
//    Near the stop the landing step in real distance (x, x − a, …, landing exactly) and the
//    tail cap of 6. take a = A0 × the lowest r (with the joint zones, 7.) from the tool up to
//    the stop: that minimum only rises as the tool moves on and both bounds rise with a, so
//    following them never asks for more than a at once (with the r over the next step's reach
//    only, a short low-r segment before the stop came into reach at once: 3 698 mm/s² on a
//    2 000 axis; with the segments' r without the zones, the pair across a corner just before
//    the stop slowed by more than its zone leaves beside the turn: Y 2 018.7 on a 2 000 axis
//    0.05 mm before an exact stop, X 1 475.6 on a 1 400 axis 0.03 mm before the program's
//    end). A block arriving while the tool brakes for the window's end, whose r or joint zone
//    would lower these bounds at once below the last step, is held (6., check_stop()).
//
//    Caps of V ≥ A0 (and corner caps ≥ A0/2 on long segments with r ≥ 1/2) use the lattice
//    key instead, K = (V − A0/2)² + 2·A0·σ(c), x ≤ √(K − 2·A0·σ(s)) − A0/2: following it the steps
//    are exactly x, x − A0, …, and a step landing at or after c has (x − A0/2)² ≤ (V − A0/2)², so
//    x ≤ V. Its bound is V at c − V and may reach 0 just before c when V < A0 (the last lattice
//    step can be larger than V and then lands short of c), so such a cap is active from c − V
//    at the latest (e_c, (iii)).
//
// 4. Forward pass = the cycle:  u = min(u_prev + r·A0, caps active, B(min K), stop bound), r the
// lowest
//    over where the step can go (segments and joint zones, 7.). At a capped corner the zone's r
//    is what a speed change may use next to the turn at Vg (7.), so the speed may rise there
//    too: a rule that held it while any corner cap was active pinned it at V_t = A0/2 on
//    paths whose corner caps overlap (circles of 0.03 mm chords: 1 mm/s for 95 s).
//    Where the pair at the tool lies on one line (the last step started on it and this one,
//    even with the line's own r·A0 more, cannot leave it; no filter), the sample at the tool is
//    a plain speed change along the line: the rise is the line's own r·A0, not the lower r of
//    a joint zone ahead in the reach (7.'s pairs have their sample within V of the joint).
//    line-contouring-xz 22.193 → 22.048 s, cam-short-segments 7.215 → 7.154, braid_cut2d
//    20.076 → 19.884.
//
// 5. Feed caps and the override. A feed cap's V is OR·F and OR may change at any cycle, so its
//    key K = (OR·F)² + 2A0σ(c) depends on OR. We keep one key tree per override *level*
//    OR_j = j·Δ (Δ = 0.1 up to 400 %): a feed cap enters every level tree with the key for OR_j;
//    the cycle reads the tree of the highest level ≤ OR. K grows with OR, so that key is never
//    looser than the exact one: the braking target is OR_j·F ≤ OR·F (exact at 100 %, and at
//    every multiple of 10 %). Work: a feed cap costs one update of all levels when it arrives
//    and when it is activated (only where the feed changes: equal feeds share a cap, and
//    extending a cap to the next segment moves its position, not its tree leaves); the level
//    trees are stored node-major (planner::MinTreeRows: one path of 41-wide nodes per update)
//    over a pool of feed-cap ids, not over every cap slot; the cycle reads one root. An override
//    increase only raises the limits (the geometric caps and the stops, which keep every braking
//    distance, are OR-independent); an override decrease lowers the feed limit, and the tool then
//    decelerates at A_seg until it is below it (u ≥ u_prev − r·A0 for the feed part), which the
//    spec and the checker allow for one ramp. Without a filter at least at σ's mean r over the
//    step just taken, r̄: the keys of the level before allowed that step, so they allow it less
//    r̄·A0 now (3. (ii)), and r (the next reach's, 4.) may be below r̄ in a joint zone, whose
//    decreases σ runs at their own r (7.): decelerating at r·A0 there fell behind them. On an arc
//    whose r was set by the normal acceleration at its top speed, it decelerates at min(A0,
//    √((0.98·g)² − (u²/ρ)²)) for the current step u instead (more as u falls; inside the tool's
//    segment, no joint zone within reach, and not with a filter after this type, whose r carry (8.)
//    assumes r).
//
// 8. Jerk stage and post filter. With a jerk limit the tool's step is the moving average of the
//    last T2 commanded steps (T2 = ⌈2·Amax/(Jmax·τ)⌉, planner::make_limits): its acceleration is
//    (u_k − u_{k−T2})/T2, within what the commanded steps use, and its jerk
//    (a_k − a_{k−T2})/T2 ≤ 2·A0/T2 ≤ Jmax·τ³ — tangential jerk; the tool stays on the path, the
//    filter runs on the path position. The post-interpolation filter (Tp cycles, kernel) averages
//    the axis positions after it; its corner rounding v·(Tp + 1)·sin θ/8 ≤ tolerance holds when
//    the speed is ≤ the corner's Vg (planner::joint_speed_pc) for the Tp cycles around the corner.
//    Both average the commanded motion over at most lag = T2 + Tp cycles (the steps a late
//    block must respect, 6.). How far that reaches along the path: the jerk stage's output
//    position is the mean of the last T2 commanded positions x_0 < … < x_{T2−1}, its step the
//    mean of the commanded steps that start there. Let every commanded step that starts in
//    [c − W, e + W) or lands at or after c − W be ≤ V, W = (T2 − 1)/2·V. An output step that
//    starts in [c, e) (mean ≥ c) has x_0 ≥ c − W: else the positions from the first one at or
//    after c − W on rise by ≤ V a cycle from below c − W + V, and the mean stays below
//    c − W + (T2 − 1)/2·V = c. Likewise x_{T2−1} < e + W. So it averages only steps ≤ V. Its
//    acceleration averages the step changes over one commanded step more: (T2 + 1)/2·V. The
//    post filter averages axis positions off the path; it keeps its whole Tp·V. So, with
//    cap_lag = (T2 − 1)/2 + Tp and reach_lag = (T2 + 1)/2 + Tp (a reach of T2 + Tp for both ran
//    zigzag_0.002 at T2 = 4 in 34.54 s, these in 26.54):
//      - every cap reaches cap_lag·V further on both sides, a corner
//        [j − (1 + cap_lag)·Vg, j + (1 + cap_lag)·Vg);
//      - a joint zone (7.) spans [j − (2 + reach_lag)·V, j + (1 + reach_lag)·V] (past b into the
//        segments after it through a carried head zone);
//      - the output at p averages the commanded accelerations up to reach_lag·v ahead of p, so
//        a segment with r < 1 carries its r over the next reach_lag·v_top mm (a head zone of the
//        later segments; v_top the highest step allowed so far).
//    A block arriving late (6.), whose widened caps would start behind the commanded position
//    over steps already in the filter, is held until the tool has stopped at its start and the
//    filter has emptied: no cap then starts behind a step the filter still averages
//    (accel_late_test.cpp: corners of 30–179°, slower feeds and arcs arriving at every point of
//    the braking ramp, random programs with random arrival cycles; T2 = 4–200, Tp = 8–16).
//
#include "motion/accel_limited.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/accel_limited_common.hpp"

namespace cncore::motion {

using namespace accel_limited_common;  // NOLINT(google-build-using-namespace)
using planner::ItemKind;
using planner::MinTree;
using planner::Segment;

namespace {
constexpr double kArcNormalShare = 0.95;  // a_n ≤ 0.95·g on arcs where the axes couple
}  // namespace

AccelLimitedAccDec::AccelLimitedAccDec(const planner::SegmentBuffer& buffer,
                                       const planner::Limits& limits, double or_max,
                                       bool check_reference_walk)
    : buf_(buffer),
      lim_(limits),
      a0_(limits.amax_pc2),
      or_max_(std::max(1.0, or_max)),
      level_step_(or_max_ <= 4.0 ? 0.1 : or_max_ / 40.0),
      // 41 levels: 0 … 400 % by 10 %, or 40 equal steps up to a higher ORmax.
      levels_(std::min(kMaxLevels,
                       static_cast<std::size_t>(std::floor(or_max_ / level_step_ + 1e-9)) + 1)),
      sigma0_(buffer.capacity(), 0.0),
      ratio_(buffer.capacity(), 1.0),
      vcap_(buffer.capacity(), 0.0),
      len_mm_(buffer.capacity(), 0.0),
      head_mm_(buffer.capacity(), 0.0),
      head_r_(buffer.capacity(), 1.0),
      tail_mm_(buffer.capacity(), 0.0),
      tail_r_(buffer.capacity(), 1.0),
      head_rd_(buffer.capacity(), 1.0),
      tail_rd_(buffer.capacity(), 1.0),
      s0_mm_(buffer.capacity(), 0.0),
      pieces_(buffer.capacity(), SigmaPieces{}),
      arc_g_(buffer.capacity(), 0.0),
      arc_rho_(buffer.capacity(), 0.0),
      lin_r_(buffer.capacity(), 1.0),
      pool_(buffer.capacity() + kOverflow),
      caps_(3 * pool_, Cap{}),
      state_(3 * pool_, State::kEmpty),
      owner_(3 * (buffer.capacity() + kOverflow), kNone),
      where_(3 * pool_, kNone),
      free_(3 * pool_),
      entry_(3 * pool_),
      key_geo_(3 * pool_),
      key_lattice_(3 * pool_),
      active_geo_(3 * pool_),
      active_feed_(3 * pool_),
      release_(3 * pool_),
      key_feed_(pool_, levels_),
      feed_v_(pool_, 0.0),
      feed_k_(pool_, kInf),
      overflow_(3 * buffer.capacity()),
      r_zone_(buffer.capacity()),
      check_(check_reference_walk),
      jerk_(limits.t2_cycles > 1 ? limits.t2_cycles : 1),
      jerk_on_(limits.t2_cycles > 1),
      lag_(jerk_cycles(limits) + post_cycles(limits)),
      reach_lag_((jerk_on_ ? 0.5 * (jerk_cycles(limits) + 1) : 0.0) + post_cycles(limits)),
      cap_lag_(reach_lag_ - (jerk_on_ ? 1.0 : 0.0)) {
  // Free ids, lowest on top.
  for (std::size_t k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < pool_; ++i) {
      free_[k * pool_ + i] = static_cast<std::uint32_t>(k * pool_ + pool_ - 1 - i);
    }
    free_n_[k] = pool_;
  }
  tail_cap_pc_ = a0_;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (lim_.axis_on[i] && lim_.axis_amax_pc2[i] > 0) {
      tail_cap_pc_ = std::min(tail_cap_pc_, lim_.axis_amax_pc2[i]);
    }
  }
  tail_cap_pc_ *= 0.5;
  recent_.assign(std::max<std::size_t>(1, static_cast<std::size_t>(lag_)), 0.0);
  // At most three caps per buffer slot wait for a hold's release: no allocation when they come.
  pending_.reserve(3 * buffer.capacity());
}

double AccelLimitedAccDec::segment_accel_pc2(std::uint64_t index) const {
  return a0_ * ratio_[buf_.slot(index)];
}

// Size: a segment's arrival in one pass: its r and caps, the carried head zones, the late-block
// test, then the caps' insertion or extension; the late test must see the caps before they are
// attached, so the parts share the new caps' values.
void AccelLimitedAccDec::on_segment(std::uint64_t index, const Segment& s) {
  const std::size_t slot = buf_.slot(index);
  const AxisVec delta = s.end - s.start;
  double r = 1;
  double vcap = s.vb_pc;
  // Per-axis acceleration along the direction: d_i·A ≤ a_i (lines; on arcs the linear axes
  // outside the plane and the rotary axes move linearly too).
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    // On a helix the axis along the arc's normal rises linearly: its share is rise/L.
    const double d = s.arc && i < 3 ? std::abs(s.rise_mm * component(s.n, i)) / s.length_mm
                                    : std::abs(delta[i]) / s.length_mm;
    if (d > 1e-12) r = std::min(r, lim_.axis_amax_pc2[i] / (d * a0_));
  }
  lin_r_[slot] = std::max(r, 1e-6);
  arc_g_[slot] = 0;
  if (s.arc) {
    // Normal and tangential acceleration share the axes of the arc plane: an axis sees at most
    // √(a_t² + a_n²)·h_i (h_i its share of the plane).
    double g = kInf;
    for (std::size_t i = 0; i < 3; ++i) {
      if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
      const double h = std::hypot(component(s.e1, i), component(s.e2, i));
      if (h > 1e-9) g = std::min(g, lim_.axis_amax_pc2[i] / h);
    }
    if (lim_.bound_resultant) g = std::min(g, a0_);
    if (g < std::sqrt(2.0) * a0_) {
      const double v_top = std::min(s.vb_pc, s.feed_pc * or_max_);
      const double an = std::min(v_top * v_top / s.rho_mm, kArcNormalShare * g);
      vcap = std::min(vcap, std::sqrt(an * s.rho_mm));
      r = std::min(r, std::min(a0_, std::sqrt(std::max(0.0, g * g - an * an))) / a0_);
      arc_g_[slot] = g;
      arc_rho_[slot] = s.rho_mm;
    }
  }
  r = std::max(r, 1e-6);
  ratio_[slot] = r;
  vcap_[slot] = vcap;
  len_mm_[slot] = s.length_mm;
  s0_mm_[slot] = s.s0_mm;
  head_mm_[slot] = tail_mm_[slot] = 0;
  head_r_[slot] = tail_r_[slot] = 1;
  head_rd_[slot] = tail_rd_[slot] = 1;
  refresh_pieces(slot);
  // Head zones reaching here from earlier segments (8.); expired ones are dropped.
  for (std::size_t k = 0; k < n_carries_;) {
    if (carries_[k].until_mm <= s.s0_mm) {
      carries_[k] = carries_[--n_carries_];
      continue;
    }
    add_head(slot, carries_[k].until_mm - s.s0_mm, carries_[k].r, carries_[k].r);
    ++k;
  }
  if (lag_ > 0) {
    vtop_pc_ = std::max(vtop_pc_, std::min(vcap, s.feed_pc * or_max_));
    // The output at p averages the commanded accelerations up to reach_lag·v ahead of it (8.):
    // a commanded step may use only the lowest r of the reach_lag·v behind it.
    if (r < 1) carry(s.end_mm() + reach_lag_ * vtop_pc_, r);
  }

  const bool contiguous = have_prev_ && prev_end_mm_ == s.s0_mm;
  // A joint (the kernel calls on_joint next) unless an event that stops lies between.
  bool joint = contiguous && prev_index_ >= buf_.begin_index() &&
               buf_[prev_index_].kind == ItemKind::kMotion;
  for (std::uint64_t k = prev_index_ + 1; joint && k < index; ++k) joint = !buf_[k].barrier;
  // A block arriving late (6.): a cap it brings that would slow the commanded position below
  // its step at once (or, active at once, below the steps still in the filter) holds it.
  late_check_ = false;
  if (!late_hold_) {
    // Every cap it brings starts at or after s0 − (2 + reach_lag)·v_hi: joint caps
    // (1 + cap_lag)·Vg before the joint, a lattice cap's entry V before that, and Vg ≤ the
    // faster side's cap (8.). From c − p ≥ d/r_lo on, σ(c) − σ_p ≥ d = u²/(2·A0) + u + A0, and
    // both key forms (3.) give a bound ≥ u there.
    const double v_hi =
        std::max({vcap, s.feed_pc * or_max_, have_prev_ ? vcap_[buf_.slot(prev_index_)] : 0.0});
    // (With this block's own r and the lowest its joint's zone may have, kZoneFloor of the
    // lower r at the joint (7.): the stop's landing bounds use them, far from d/r_lo on they
    // are ≥ u as well, 3.)
    const double r_prev = have_prev_ ? ratio_[buf_.slot(prev_index_)] : 1.0;
    const double r_lo =
        std::max(1e-6, std::min({1.0, r_zone_.min(), r, kZoneFloor * std::min(r, r_prev)}));
    const double near_mm =
        (2 + reach_lag_) * v_hi + (step_ * step_ / (2 * a0_) + step_ + a0_) / r_lo;
    if (pos_mm_ + near_mm >= s.s0_mm) {
      late_m_ = step_;
      for (const double x : recent_) late_m_ = std::max(late_m_, x);
      late_check_ = late_m_ > 0;
      late_at_mm_ = s.s0_mm;
    }
  }
  n_late_range_ = 0;
  if (late_check_) {
    late_sigma_p_ = sigma_at(pos_mm_);
    const double v[2] = {vcap, s.feed_pc};
    const double reach_k[2] = {cap_lag_ * vcap, cap_lag_ * s.feed_pc * or_max_};
    for (std::size_t k = 0; k < 2; ++k) {
      // The same limit as the previous segment extends its cap: nothing new (see below).
      const std::size_t from = 3 * buf_.slot(prev_index_) + k;
      if (contiguous && owner_[from] != kNone && caps_[owner_[from]].v == v[k]) continue;
      const double c = s.s0_mm - reach_k[k];
      late_range_[n_late_range_++] = {c,      s.end_mm() + reach_k[k], v[k], 0,
                                      k == 1, k == 0 && vcap >= a0_};
    }
    // With this block's end as the window's new stop, an r of its own lowers the stop's
    // bounds (found: a 0.1 mm helix at r = 0.29 arriving while the tool braked on a line,
    // T2 = 4: the commanded step fell by 2.02·A0 in one cycle, 2 126 mm/s² after the jerk
    // stage); its joint's zone is tested in joint_zones().
    if (r < 1) check_stop(s.end_mm(), s.s0_mm, r);
    // At a joint, joint_zones() tests them with the σ its zone will leave.
    if (!joint && !late_hold_) check_late(s.s0_mm, 0, 1, nullptr);
  }
  if (joint) joint_zones(prev_index_, slot, s);
  update_r(index);
  sigma0_[slot] = sigma_total_;
  sigma_total_ += seg_sigma(slot, s.length_mm);
  // With a filter after this type (8.) a cap reaches cap_lag·V further on both sides (a feed
  // cap's speed is up to OR_max·F).
  const double reach[2] = {cap_lag_ * vcap, cap_lag_ * s.feed_pc * or_max_};
  auto widened = [&](double v, bool feed, bool lattice, double r_reach) {
    Cap cap{s.s0_mm - r_reach, s.end_mm() + r_reach, v, sigma0_[slot], feed, lattice};
    if (r_reach > 0) cap.sigma_c = sigma_at(cap.c_mm);
    return cap;
  };
  const Cap caps[2] = {widened(vcap, false, vcap >= a0_, reach[0]),
                       widened(s.feed_pc, true, false, reach[1])};
  for (std::size_t k = 0; k < 2; ++k) {
    const std::size_t to = 3 * slot + k;
    if (contiguous) {
      const std::size_t from = 3 * buf_.slot(prev_index_) + k;
      if (owner_[from] != kNone && caps_[owner_[from]].v == caps[k].v) {
        // Same limit as the previous segment: extend its cap (moved to this slot so that the
        // buffer can retire the earlier segments; its keys and entry do not change).
        clear(to);
        move(from, to);
        const std::size_t g = owner_[to];
        caps_[g].e_mm = s.end_mm() + reach[k];
        // An active cap keeps its earlier release position in release_ (≤ e): step() moves it
        // on when the tool gets there, once per window's length instead of one tree update per
        // block (an extended cap is the tree's minimum, so each update walked to the root).
        if (state_[g] != State::kActive && pos_mm_ >= caps_[g].entry) activate(g);
        continue;
      }
    }
    insert(to, caps[k]);
  }
  have_prev_ = true;
  prev_index_ = index;
  prev_end_mm_ = s.end_mm();
}

void AccelLimitedAccDec::insert_joint_cap(std::size_t slot_a, std::size_t slot_b, double joint_mm,
                                          double len_a, double vg) {
  // σ(j − Vg), exact (inside a directly, before a by a search of the buffer): a key with a σ
  // lower than the true σ(c) would make the bound reach 0 before c (a stall) where r < 1.
  // The cap covers the step before and after the joint, and cap_lag·Vg more with a filter (8.).
  const double w = vg * (1 + cap_lag_);
  const double c_mm = joint_mm - w;
  const double sigma_c =
      w <= len_a ? sigma0_[slot_a] + seg_sigma(slot_a, len_a - w) : sigma_at(c_mm);
  // Lattice form where it cannot stall before the cap takes over (see 3.): V ≥ A0, or V ≥ A0/2
  // with mean r ≥ 1/2 over [c − V, c] (the bound is 0 at (V − V²/A0)/(2·r) ≤ V/2 before c).
  bool lattice = vg >= a0_;
  if (!lattice && vg >= 0.5 * a0_) lattice = sigma_c - sigma_at(c_mm - vg) >= 0.5 * vg;
  // Kept in b's slot: the range reaches into b (and past it when b is short), and b stays in
  // the buffer anyway while the tool is in it; in a's slot, a full small buffer could wait for
  // a block that cannot arrive before a is retired.
  insert(3 * slot_b + 2, Cap{c_mm, joint_mm + w, vg, sigma_c, false, lattice});
}

void AccelLimitedAccDec::on_joint(std::uint64_t index_a, const Segment& a, const Segment& b) {
  const std::size_t sa = buf_.slot(index_a);
  const std::size_t sb = buf_.slot(buf_.end_index() - 1);
  // Without a joint cap the steps next to the joint are bounded by the faster side's cap (the
  // step after the joint starts in b): the corner is passed at up to the larger of both.
  const double around = std::max(vcap_[sa], vcap_[sb]);
  // The corner alone (no slow-corner stop rule: that belongs to the moving average).
  // (joint_zones() computed the corner's speed for this same joint when b arrived.)
  const double corner =
      zone_index_a_ == index_a ? zone_joint_pc_ : planner::joint_speed_pc(a, b, lim_, false);
  double vg = std::min(corner, around);
  // Lowered where the turn leaves too little of the axis budget for the speed change (7.).
  if (zone_index_a_ == index_a) vg = std::min(vg, zone_vg_);
  // The directions at the joint, as joint_zones() computed them for it (the same doubles).
  const bool zoned = zone_index_a_ == index_a;
  const AxisVec a_end = zoned ? zone_e_ : a.end_direction();
  const AxisVec b_start = zoned ? zone_s_ : b.start_direction();
  const bool chained = prev_.valid && prev_.index_b == index_a;
  // A segment shorter than one step lets one cycle turn two corners at once (from the end of
  // the segment before a to the start of b; after another short one, three). Either the speed
  // stays ≤ a's length (no step skips a) or the combined turn is allowed (as in the moving
  // average type). Only where the combined turn allows less than the caps already in force.
  if (chained && a.length_mm < vg) {
    const double pair = planner::turn_speed_pc(prev_.end_dir, b_start, lim_);
    double both = pair < 0.999 * std::min(prev_.vg, vg) ? pair : kInf;
    // The chain's turn beside the speed change its zone allows (joint_zones(), 7.).
    if (zone_index_a_ == index_a && zone_chain_vg_ < 0.999 * prev_.vg) {
      both = std::min(both, zone_chain_vg_);
    }
    if (prev_.short_a) {
      const double triple = planner::turn_speed_pc(prev_.end_dir2, b_start, lim_);
      if (triple < 0.999 * std::min({prev_.vg2, prev_.vg, vg})) both = std::min(both, triple);
    }
    if (both < kInf) {
      const double cap = std::max(a.length_mm, both);
      vg = std::min(vg, cap);
      if (cap < prev_.vg) {
        // The joint before a (at a's start) gets the same cap.
        const std::size_t sx = buf_.slot(prev_.index_a);
        if (buf_.begin_index() <= prev_.index_a) {
          insert_joint_cap(sx, sa, a.s0_mm, buf_[prev_.index_a].length_mm, cap);
        }
        prev_.vg = cap;
      }
    }
  }
  const AxisVec before = chained ? prev_.end_dir : a_end;
  const double vg_before = chained ? prev_.vg : kInf;
  prev_ = {true,
           index_a,
           buf_.end_index() - 1,
           a_end,
           before,
           vg,
           vg_before,
           a.length_mm < vg,
           zoned ? zone_a_start_ : a.start_direction(),
           a.length_mm,
           a.arc && a.rho_mm > 0 ? a.length_mm / a.rho_mm : 0.0};
  // A turn in the same cycle as a speed change: the joint zones (7.) keep both within every
  // axis limit (at a capped corner the cap is lowered until the zone's floor fits beside it).
  if (!(vg < 0.999 * around)) return;  // the segments' own caps already hold there
  insert_joint_cap(sa, sb, a.end_mm(), a.length_mm, vg);
}

void AccelLimitedAccDec::on_retire(std::uint64_t index) {
  const std::size_t slot = buf_.slot(index);
  const std::size_t s = 3 * slot;
  clear(s);
  clear(s + 1);
  clear(s + 2);
  // The slot may next hold an event (no on_segment): no r there. Every leaf ≥ 1 means "no
  // limit" to r_span() (rates are ≤ 1), so a leaf of 1 is left as it is: the usual retirement
  // writes nothing to the tree.
  if (r_zone_.at(slot) < 1) r_zone_.set(slot, MinTree::kEmpty);
}

bool AccelLimitedAccDec::detach(std::uint64_t index) {
  // The caps of a segment the tool has passed are active ones (their range started behind the
  // tool) whose range reaches past it: a joint cap [j − Vg, j + Vg) over segments shorter than
  // Vg, or any cap widened by cap_lag·V with a filter (8.). They move to the overflow positions
  // of their kind (3·(capacity + i) + k, so that pos % 3 still tells a joint cap), kept as a set
  // where none dominates another (lower V and later end); a cap dominated by one there is
  // dropped, and with all kOverflow taken it merges with the one of the nearest V as
  // (min V, max e): stricter than each, so every cap still holds. (A single merged position
  // ran a 103 mm helix at the 1 mm/s of a 1 µm F60 line before it: a rapid's feed cap, widened
  // by 200 cycles × 2 × 0.25 mm to 100 mm, took line's V; T2 = 200, lookahead 8, G61.)
  const std::size_t s = 3 * buf_.slot(index);
  for (std::size_t k = 0; k < 3; ++k) {
    if (pos_state(s + k) == State::kApproaching) return false;
  }
  for (std::size_t k = 0; k < 3; ++k) {
    if (pos_state(s + k) != State::kActive) continue;
    const Cap cap = caps_[owner_[s + k]];
    constexpr std::size_t kNoPos = ~std::size_t{0};
    std::size_t free_pos = kNoPos;
    std::size_t nearest = kNoPos;
    double nearest_ratio = -1;
    bool dominated = false;
    for (std::size_t i = 0; i < kOverflow; ++i) {
      const std::size_t o = overflow_ + 3 * i + k;
      if (pos_state(o) != State::kActive) {
        free_pos = o;
        continue;
      }
      const Cap& x = caps_[owner_[o]];
      if (x.v <= cap.v && x.e_mm >= cap.e_mm) {
        dominated = true;
        break;
      }
      if (cap.v <= x.v && cap.e_mm >= x.e_mm) {
        clear(o);
        free_pos = o;
        continue;
      }
      const double ratio = std::min(x.v, cap.v) / std::max(x.v, cap.v);
      if (ratio > nearest_ratio) {
        nearest_ratio = ratio;
        nearest = o;
      }
    }
    if (dominated) {
      clear(s + k);
    } else if (free_pos != kNoPos) {
      move(s + k, free_pos);  // active, its trees unchanged
    } else {
      clear(s + k);
      const std::size_t g = owner_[nearest];
      Cap& merged = caps_[g];
      merged.v = std::min(merged.v, cap.v);
      merged.e_mm = std::max(merged.e_mm, cap.e_mm);
      (merged.feed ? active_feed_ : active_geo_).set(g, merged.v);
      release_.set(g, merged.e_mm);
    }
  }
  return true;
}

}  // namespace cncore::motion
