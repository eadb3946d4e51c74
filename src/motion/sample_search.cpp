// The sample search: see sample_search.hpp for what it does, docs/lookahead.md for why, and
// bench/bound/sampled_reference.cpp (cncore-sref) for the whole-program version whose figures
// this one reproduces with fixed buffers.
#include "motion/sample_search.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace cncore::motion {

namespace {
constexpr double kWindow = 1e-5;  // mm before a joint where no sample lands (checker's snap)
constexpr double kRound = 1e-9;   // mm of rounding allowed on a step's range
constexpr std::size_t kCoalesceEvery = 8;  // cycles between searches for the commit point
constexpr double kInf = std::numeric_limits<double>::infinity();
// The beam keeps two classes of states, each K per speed bin: those that pass the guide with
// its sharp-corner term and those that pass it only without (see can_brake()).
constexpr std::size_t kClasses = 2;
constexpr double kFoldCos = -0.5;  // cos of a turn of 120°: a fold of the path onto itself
// A sharp corner: |S − E| > 0.5 (θ ≈ 29°), i.e. cos θ < 1 − 0.5²/2 (|S − E|² = 2 − 2·cos θ).
constexpr double kSharpCos = 0.875;
}  // namespace

SampleSearch::SampleSearch(const planner::Limits& limits, const SampleSearchOptions& options)
    : lim_(limits), opt_(options) {
  const double m = opt_.limit_factor;
  a_ = m * lim_.amax_pc2;
  normal_ = a_;
  resultant_ = lim_.bound_resultant ? a_ : 0.0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim_.axis_on[i]) continue;
    if (lim_.axis_amax_pc2[i] > 0) axis_a_[i] = m * lim_.axis_amax_pc2[i];
    if (lim_.axis_vmax_pc[i] > 0) axis_v_[i] = m * lim_.axis_vmax_pc[i];
  }
  max_step_ = m * std::max(lim_.vmax_pc, lim_.rapid_pc);
  // The front stays this far before a window end that is not the program's: there the guide
  // never sees the window's temporary stop, and neither does the brake of a committed state.
  reach_mm_ = brake_distance(max_step_, 0) + 2 * max_step_;
  eff_horizon_mm_ = reach_mm_;
  bin_w_ = a_ / opt_.bins_per_a;
  nbins_ = static_cast<std::size_t>(max_step_ / bin_w_) + 2;
  beam_cap_ = kClasses * nbins_ * opt_.per_bin;
  hist_rows_ = opt_.max_lag_cycles + 2 * kCoalesceEvery;
  cand_cap_ = opt_.grid + 1 + 4 * opt_.joints_per_step;
  // The brake from a state at the top speed takes max_step/a cycles plus a few at the caps.
  const auto brake_cycles = static_cast<std::size_t>(max_step_ / a_) + 64;
  const std::size_t out_cap = std::max(opt_.output_cycles, 2 * (hist_rows_ + brake_cycles));

  // A power of two, so that a segment's slot is a mask, not a division (it was ~10 % of the
  // search, in every rule that walks the joints); the window holds window_segments of them.
  segs_.resize(std::bit_ceil(std::max<std::size_t>(opt_.window_segments, 1)));
  seg_mask_ = segs_.size() - 1;
  beam_.reserve(beam_cap_);
  bins_.resize(beam_cap_);
  bin_n_.assign(kClasses * nbins_, 0);
  cand_s_.resize(cand_cap_);
  cands_.resize(5 * cand_cap_);  // the base ones, and two boundaries per pair and direction
  hist_.resize(hist_rows_ * beam_cap_);
  mark_.assign(beam_cap_, 0);
  idx_a_.resize(beam_cap_);
  idx_b_.resize(beam_cap_);
  trace_.resize(hist_rows_ + 1);
  out_.resize(out_cap);
  hard_q_.resize(opt_.window_segments);
  out_reserve_ = hist_rows_ + brake_cycles;
}

bool SampleSearch::wants_segment() const {
  return seg_end_ - seg_base_ < opt_.window_segments && !program_ended_;
}

bool SampleSearch::push(const planner::Segment& segment, bool stop_after) {
  if (!wants_segment() || segment.kind != planner::ItemKind::kMotion || segment.length_mm <= 0)
    return false;
  const Vec3 chord = segment.end.xyz() - segment.start.xyz();
  if (!segment.arc && norm(chord) <= 0) return false;  // rotary-only: not supported
  if (seg_end_ > 0 && std::abs(segment.s0_mm - joint_s(seg_end_ - 1)) > 1e-9) return false;
  const std::uint64_t idx = seg_end_;
  Seg& g = seg(idx);
  g.geo = segment;
  const double m = opt_.limit_factor;
  g.shape = m * shape_cap(segment);
  g.feed = segment.feed_pc > 0 ? m * segment.feed_pc : kInf;
  g.joint_cap = a_;  // the window's end: a stop until the next segment arrives
  g.stop = true;
  g.hard_stop = false;
  g.turn_cos = 1;
  if (idx > 0) {
    Seg& prev = seg(idx - 1);
    if (!prev.hard_stop) {
      prev.joint_cap = m * corner_cap(prev.geo, g.geo);
      const Vec3 e = prev.geo.end_direction().xyz(), s = g.geo.start_direction().xyz();
      const double ne = norm(e), ns = norm(s);
      prev.turn_cos = ne > 0 && ns > 0 ? dot(e, s) / (ne * ns) : 1.0;
      prev.stop = false;
    }
  }
  const bool fresh = eff_fresh_ >= seg_end_;
  ++seg_end_;
  update_eff(idx);
  if (fresh) eff_fresh_ = seg_end_;
  if (stop_after) mark_stop();
  if (idx == 0) {
    // The tool rests at the first segment's start: cycle 0.
    const double s0 = segment.s0_mm;
    beam_.assign(1, Node{s0, s0, 0, 0});
    hist(0, 0) = {s0, -1};
    last_commit_ = beam_[0];
    popped_s_ = popped_sp_ = s0;
    emit(beam_[0], 0);
  }
  return true;
}

// The checker's speed limit of a segment's shape: the feed or rapid rate, and √(R·Amax) on an
// arc (R the smaller radius of a spiral). The planner's Vb is lower: it keeps room for the moving
// average's ramp and the per-axis limits, which the search checks on the samples themselves.
double SampleSearch::shape_cap(const planner::Segment& s) const {
  double v = s.rapid ? lim_.rapid_pc : lim_.vmax_pc;
  if (s.arc) v = std::min(v, std::sqrt(std::min(s.r0, s.r1) * lim_.amax_pc2));
  return v;
}

// The checker's passing speed of a joint: both shapes' limits and the turn within one cycle,
// Vg = Amax·τ/(2 sin(θ/2)) = Amax·τ/|S − E| with S, E the unit tangents.
double SampleSearch::corner_cap(const planner::Segment& a, const planner::Segment& b) const {
  const Vec3 e = a.end_direction().xyz(), s = b.start_direction().xyz();
  const double ne = norm(e), ns = norm(s);
  double v = std::min(shape_cap(a), shape_cap(b));
  if (ne > 0 && ns > 0) {
    const double turn = norm((1.0 / ns) * s - (1.0 / ne) * e);
    if (turn > 1e-12) v = std::min(v, lim_.amax_pc2 / turn);
  }
  return v;
}

bool SampleSearch::push(const Block& block) {
  if (block.kind == BlockKind::kDwell) return false;
  if (block.kind == BlockKind::kAux) {
    if (block.aux_waits) mark_stop();
    return true;
  }
  if (!wants_segment()) return false;
  planner::Segment s = planner::make_motion_segment(block, lim_);
  if (s.length_mm <= 0) return true;
  s.s0_mm = seg_end_ > 0 ? joint_s(seg_end_ - 1) : 0.0;
  return push(s, block.path_mode == PathMode::kExactStop);
}

void SampleSearch::end_of_program() {
  program_ended_ = true;
}

// Shortest distance from a sample reached with step d to the last sample before a joint that
// must be crossed with a step ≤ c, the steps shrinking by a per cycle at most: the landings of
// d − a, d − 2a, …, while they are above c:
//   Σ_{i=1}^{m−1} (d − i·a) = (m−1)·d − a·m·(m−1)/2,  m = ⌈(d − c)/a⌉.
double SampleSearch::brake_distance(double d, double c) const {
  // Up to kRound, as the rules: d = c + a exactly (the cap's step plus a) read d − a > c by ulps
  // and cost a braking step the rules do not ask for.
  if (d - a_ <= c + kRound) return 0;
  const double m1 = std::ceil((d - c - kRound) / a_) - 1;
  return m1 * d - a_ * m1 * (m1 + 1) / 2;
}

// The largest step d with brake_distance(d, c) < room (room > 0). With c' = c + kRound the
// distance is 0 up to d = c' + a and, for d − c' in (k·a, (k+1)·a], k·d − a·k·(k+1)/2: rising
// in d, with a jump of c' where k steps up. Its value at the top of interval k is
// k·c' + a·k·(k+1)/2; the first k where that reaches room, from (a/2)·k² + (c' + a/2)·k = room,
// holds the answer: d < (room + a·k·(k+1)/2)/k there, and never below the interval's foot
// c' + k·a (the jump). The closed form then moves by ulps to the largest double below the
// bound (a bisection of 60 steps before: most of the search's time on a window of 10 000
// short segments, walked back each time one arrives).
double SampleSearch::brake_limit(double c, double room) const {
  const double c1 = c + kRound;
  const double b = c1 + a_ / 2;
  double k = std::max(1.0, std::ceil((std::sqrt(b * b + 2 * a_ * room) - b) / a_));
  while (k > 1 && (k - 1) * c1 + a_ * (k - 1) * k / 2 >= room) --k;
  while (k * c1 + a_ * k * (k + 1) / 2 < room) ++k;
  double d = std::max(c1 + k * a_, (room + a_ * k * (k + 1) / 2) / k);
  while (d > 0 && brake_distance(d, c) >= room) d = std::nextafter(d, 0.0);
  for (double up = std::nextafter(d, kInf); brake_distance(up, c) < room;
       up = std::nextafter(d, kInf))
    d = up;
  return d;
}

// The effective cap of joint j for the backward guide: a crossing step of joint j touches
// segment j, so it is below that segment's cap too, and after crossing j, joint j+1 must still
// be met (the largest d with brake_distance(d, eff_{j+1}) < room). Reads eff_{j+1}.
double SampleSearch::eff_of(std::uint64_t j) const {
  // A stop must be landed on exactly: the step after it is 0, so braking counts down to 0
  // there (with the cap a instead, a state at 1.9·a a few µm before the end passed the guide
  // and could only land by slowing to rest short of it and creeping on).
  const Seg& g = seg(j);
  if (g.stop) return 0.0;
  double eff = std::min(g.joint_cap, cap(g, or_));
  if (j + 1 < seg_end_) {
    // Landing on joint j with step x, the next step (inside segment j+1) is ≥ x − a: so x ≤
    // cap_{j+1} + a as well.
    eff = std::min(eff, cap(seg(j + 1), or_) + a_);
    const double next = seg(j + 1).eff;
    const double room = joint_s(j + 1) - joint_s(j);
    if (brake_distance(eff, next) >= room) eff = brake_limit(next, room);
  }
  return eff;
}

// A segment arrived: from the last one back while the effective caps change.
void SampleSearch::update_eff(std::uint64_t last) {
  seg(last).eff = eff_of(last);
  for (std::uint64_t j = last; j-- > seg_base_;) {
    const double eff = eff_of(j);
    if (eff == seg(j).eff && j + 1 < last) break;
    seg(j).eff = eff;
  }
}

// The override changed (restart()): every effective cap may change, but the guide reads only
// those within a braking distance of the front. The caps are made current up to `upto_mm` (a
// joint's cap depends only on the caps within eff_horizon_mm_ of it: a braking
// distance from the top speed and two steps), from a pass that starts twice that far ahead on the
// older caps, so a change of override costs one pass over ~3 horizons, not over the window
// (~30 ns a segment: 0.3 ms on a window of 10 000 segments, in the cycle of the change).
void SampleSearch::refresh_eff(double upto_mm) {
  eff_fresh_ = std::max(eff_fresh_, seg_base_);
  if (eff_fresh_ >= seg_end_ || joint_s(eff_fresh_) > upto_mm) return;
  const double h = eff_horizon_mm_;
  std::uint64_t last = eff_fresh_;
  while (last + 1 < seg_end_ && joint_s(last) < upto_mm + 2 * h) ++last;
  const bool to_end = last + 1 == seg_end_;
  if (to_end) seg(last).eff = eff_of(last);
  for (std::uint64_t j = last; j-- > eff_fresh_;) seg(j).eff = eff_of(j);
  if (to_end) {
    eff_fresh_ = seg_end_;
    return;
  }
  while (eff_fresh_ < last && joint_s(eff_fresh_) < joint_s(last) - h) ++eff_fresh_;
}

std::uint64_t SampleSearch::seg_of(double s, std::uint64_t hint) const {
  std::uint64_t j = std::clamp(hint, seg_base_, seg_end_ - 1);
  while (j + 1 < seg_end_ && s >= seg(j + 1).geo.s0_mm) ++j;
  while (j > seg_base_ && s < seg(j).geo.s0_mm) --j;
  return j;
}

AxisVec SampleSearch::point(double s, std::uint64_t segment) const {
  const planner::Segment& g = seg(segment).geo;
  return g.point_at(s - g.s0_mm);
}

// The guide: a necessary condition to meet the caps ahead from a sample at s reached with step
// d (each joint's effective cap on its own, exact for the tangential rule). 0: it fails; 1: it
// holds only without the sharp-corner term; 2: it holds with it.
int SampleSearch::can_brake(double s, double d, std::uint64_t segment) const {
  // After an override decrease: under the new cap when the ramp the checker allows ends.
  for (std::size_t i = 0; i < allow_n_; ++i) {
    const Allowance& w = allow_[i];
    if (guide_cycle_ > w.until) continue;
    const std::uint64_t k = w.until + 1;  // the first cycle without it
    if (d - static_cast<double>(k - guide_cycle_) * a_ > cap(seg(segment), ratio_at(k))) return 0;
  }
  int level = 2;
  const double free = brake_distance(d, 0);  // a joint farther than this never binds
  for (std::uint64_t j = segment, k = 0; j < seg_end_ && k < opt_.guide_joints; ++j, ++k) {
    const double js = joint_s(j);
    if (js <= s) continue;
    if (js - s > free) break;
    // A sharp corner: the step before the crossing is held near the cap too (the turn is shared
    // by the chords on both sides), so the braking ends one cap's step earlier. A heuristic, not
    // a necessary condition (the certification, not the guide, keeps the plan safe): it wins
    // where corners are far apart (a 5 mm zig-zag: 1.018 × the bound, 1.062 without) and loses
    // where they come every few cycles (zigzag_0.002: 1.074, 1.049 without), so the beam keeps
    // the states that fail only it as a class of their own.
    const Seg& g = seg(j);
    const double need = brake_distance(d, g.eff);
    if (need >= js - s) return 0;
    if (g.turn_cos < kSharpCos && need + g.eff >= js - s) level = 1;
  }
  return level;
}

// Static rules of a step from s (in `segment`, reached by a step d_in) to s2: joints crossed,
// stops, segment caps, the window before a joint and folds. Writes the landing segment (a
// landing on a joint is held by the segment after it).
bool SampleSearch::step_ok(double s, double d_in, std::uint64_t segment, double s2,
                           std::uint64_t& seg2) const {
  const double d = s2 - s;
  if (d < 0) return false;
  double cap = this->cap(seg(segment), ratio_);
  std::uint64_t j = segment;
  for (; j < seg_end_; ++j) {
    const Seg& g = seg(j);
    const double js = g.geo.end_mm();
    if (js <= s) continue;
    if (s2 < js) {
      if (s2 > js - kWindow) return false;  // the checker might count the joint as reached
      break;
    }
    // The window's end while more may come: a wall, never reached (a landing there could not
    // know the corner after it).
    if (g.stop && !g.hard_stop && !(program_ended_ && j + 1 == seg_end_)) return false;
    cap = std::min(cap, g.joint_cap);  // crossed (or landed on) joint j
    if (g.stop && s2 > js) return false;
    // A fold (a turn of more than 120°): the sample x = js − s before it also lies near the
    // segment after it, where the checker may read it, (p − J)·S = x·(−c) past the joint, if
    // that needs less speed around the sample: max(d_in + y, d − y) < max(d_in, d) with
    // y = x·(1 − c). Then the crossing reads d − y, and the step after it, allowed d + a,
    // exceeds the acceleration by y/τ² (a rest 15 nm before a reversal that a late block
    // revealed: 2 030 mm/s² on 2 000). With d ≤ d_in + y that reading is never the cheaper one.
    if (s2 > js && g.turn_cos < kFoldCos && d > d_in + (js - s) * (1 - g.turn_cos) - kRound)
      return false;
    if (s2 == js) {
      ++j;
      break;
    }
    if (j + 1 < seg_end_) cap = std::min(cap, this->cap(seg(j + 1), ratio_));
    if (d > cap + kRound) return false;  // (s + cap − s: ulps of s)
  }
  if (d > cap + kRound) return false;  // (s + cap − s: ulps of s)
  seg2 = seg_of(s2, std::min(j, seg_end_ - 1));
  return true;
}

SampleSearch::Prev SampleSearch::prev_of(const AxisVec& p0, const AxisVec& p1) {
  Prev q{p1, p1 - p0, {}, 0};
  const Vec3 d1 = q.c1.xyz();
  q.l1 = norm(d1);
  if (q.l1 > 0) q.u1 = (1.0 / q.l1) * d1;
  return q;
}

bool SampleSearch::dynamics_ok(const Prev& q, const AxisVec& p2) const {
  // Each limit up to kRound: a step that brakes by exactly a along an axis whose limit is Amax
  // reads a second difference of a ± ulps; compared strictly, braking at the full rate failed
  // there, and the beam braked by the grid's next step, a/8 short, every cycle (a 90° corner
  // on the built-in machine: 273 cycles where the acceleration type needs 250).
  const AxisVec c2 = p2 - q.p1;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (axis_v_[i] > 0 && std::abs(c2[i]) > axis_v_[i] + kRound) return false;
    if (axis_a_[i] > 0 && std::abs(c2[i] - q.c1[i]) > axis_a_[i] + kRound) return false;
  }
  const Vec3 d2 = c2.xyz();
  // Normal: the checker's a_n·τ² = √(l1·l2)·|d̂2 − d̂1| ≤ n, whose square is 2·(l1·l2 − d1·d2) =
  // 2·l1·(l2 − d̂1·d2) ≤ n², i.e. l2 ≤ t = d̂1·d2 + n²/(2·l1), i.e. t ≥ 0 and |d2|² ≤ t²: no
  // square root (the four of the plain form were most of the search's time). Nearly parallel
  // steps cancel to ulps of |d2| (~10⁻¹⁷ mm), far below kRound.
  if (q.l1 > 0) {
    const double n = normal_ + kRound;
    const double t = dot(q.u1, d2) + n * n / (2 * q.l1);
    if (t < 0 || dot(d2, d2) > t * t) return false;
  }
  return resultant_ <= 0 || norm(d2 - q.c1.xyz()) <= resultant_ + kRound;
}

// The candidate landings of state n into cand_s_[0, return), sorted and unique: a grid over
// [d − a, d + a] (lo, hi: the step's range), every joint in reach (on it, just before it, and
// the largest step the caps crossed so far allow).
std::size_t SampleSearch::landings(const Node& n, double& lo, double& hi) {
  const double s = n.s, d = n.s - n.sp;
  lo = std::max(0.0, d - a_);
  hi = d + a_;
  // Just past a fold crossed by the last step, x = s − js: the checker reads the sample on the
  // segment before the fold first, y = x·(1 − c) short of ours, and keeps that reading unless
  // ours needs less speed: max(d, d2) < max(d − y, d2 + y), i.e. d2 > d − y. (Read there, the
  // step into it was d − y: 2 971 → 947 nm/cycle on a 1.08 µm reversal, 2 024 mm/s².)
  if (n.seg > seg_base_) {
    const Seg& f = seg(n.seg - 1);
    const double js = f.geo.end_mm();
    if (f.turn_cos < kFoldCos && n.sp < js && s > js)
      lo = std::max(lo, d - (s - js) * (1 - f.turn_cos) + kRound);
  }
  std::size_t nc = 0;
  for (std::size_t i = 0; i < opt_.grid; ++i) {
    const double x =
        opt_.grid > 1 ? lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(opt_.grid - 1)
                      : hi;
    cand_s_[nc++] = s + x;
  }
  // The largest step the caps allow, as far as it goes: without it a grid that misses the
  // feed's step by a fraction of a leaves the tool below the feed on a long move.
  double cum = cap(seg(n.seg), ratio_);
  if (cum >= lo) cand_s_[nc++] = s + std::min(cum, hi);
  std::size_t joints = 0;
  for (std::uint64_t j = n.seg; j < seg_end_ && joints < opt_.joints_per_step; ++j) {
    const Seg& g = seg(j);
    const double js = g.geo.end_mm();
    if (js <= s) continue;
    if (js > s + hi) break;
    ++joints;
    if (js >= s + lo - kWindow) {
      cand_s_[nc++] = js;
      cand_s_[nc++] = js - kWindow;
    }
    cum = std::min(cum, g.joint_cap);
    if (s + cum >= js) cand_s_[nc++] = s + std::min(cum, hi);
    if (g.stop) break;
    if (j + 1 < seg_end_) cum = std::min(cum, cap(seg(j + 1), ratio_));  // past the joint
    if (s + cum > js && cum >= lo) cand_s_[nc++] = s + std::min(cum, hi);
  }
  std::sort(cand_s_.begin(), cand_s_.begin() + static_cast<std::ptrdiff_t>(nc));
  return static_cast<std::size_t>(
      std::unique(cand_s_.begin(), cand_s_.begin() + static_cast<std::ptrdiff_t>(nc)) -
      cand_s_.begin());
}

// The boundary of the rules between a feasible landing `good` and a rejected one `bad` of the
// step from n (bisection): the largest guide level ≥ `level` found nearest `bad`.
SampleSearch::Cand SampleSearch::boundary(const Node& n, const Prev& q, const Cand& good,
                                          const Cand& bad, int level, bool guided) const {
  const double s = n.s, d = n.s - n.sp;
  Cand g = good;
  double b = bad.s2;
  for (int it = 0; it < opt_.bisect; ++it) {
    const double mid = 0.5 * (g.s2 + b);
    std::uint64_t mseg = 0;
    const int lv = step_ok(s, d, n.seg, mid, mseg) && dynamics_ok(q, point(mid, mseg))
                       ? (guided ? can_brake(mid, mid - s, mseg) : 2)
                       : 0;
    if (lv >= level) {
      g = {mid, mseg, lv};
    } else {
      b = mid;
    }
  }
  return g;
}

// The feasible next landings of state n into cands_[0, count): the landings above, and the
// boundary of the dynamic rules and the guide between a feasible and a rejected candidate
// (bisection). The guide's boundary is the braking curve to the next cap: without it the grid
// brakes up to a/4 early every cycle.
void SampleSearch::expand(const Node& n, std::size_t& count, bool guided) {
  const double s = n.s, d = n.s - n.sp;
  const Prev q = prev_of(point(n.sp, seg_of(n.sp, n.seg)), point(s, n.seg));
  double lo = 0, hi = 0;
  const std::size_t nc = landings(n, lo, hi);
  std::size_t ne = 0;
  for (std::size_t i = 0; i < nc; ++i) {
    const double s2 = cand_s_[i];
    const double d2 = s2 - s;
    if (d2 < lo - kRound || d2 > hi + kRound) continue;  // s + x − s: ulps of s
    Cand c{s2, n.seg, 0};
    if (step_ok(s, d, n.seg, s2, c.seg2)) {  // (else 0: never bisected against)
      const int level = !dynamics_ok(q, point(s2, c.seg2)) ? 0
                        : guided                           ? can_brake(s2, d2, c.seg2)
                                                           : 2;
      c.ok = level > 0 ? level : -1;
    }
    cands_[ne++] = c;
  }
  const std::size_t base = ne;
  for (std::size_t i = 0; i + 1 < base; ++i) {
    for (int dir = 0; dir < 2; ++dir) {
      const Cand& good = cands_[dir == 0 ? i : i + 1];
      const Cand& bad = cands_[dir == 0 ? i + 1 : i];
      // The boundary of each level the good candidate holds and the bad one does not.
      for (int level = 1; level <= 2; ++level) {
        if (good.ok < level || bad.ok == 0 || bad.ok >= level) continue;
        const Cand g = boundary(n, q, good, bad, level, guided);
        if (g.s2 != good.s2) cands_[ne++] = g;
      }
    }
  }
  count = 0;
  for (std::size_t i = 0; i < ne; ++i)
    if (cands_[i].ok >= 1) cands_[count++] = cands_[i];
}

// The smallest of expand(n, ·, false)'s feasible landings, judging the candidates from the
// smallest up: the first feasible one, or its boundary with the rejected one before it (every
// other boundary lies above). One or two candidates judged where expand judges ~20 and bisects
// their boundaries: the certification's brake was most of the search's worst cycles.
bool SampleSearch::smallest_step(const Node& n, Cand& out) {
  const double s = n.s, d = n.s - n.sp;
  const Prev q = prev_of(point(n.sp, seg_of(n.sp, n.seg)), point(s, n.seg));
  double lo = 0, hi = 0;
  const std::size_t nc = landings(n, lo, hi);
  Cand before{0, 0, 0};  // the rejected candidate below (0: none, or a static rule failed)
  for (std::size_t i = 0; i < nc; ++i) {
    const double s2 = cand_s_[i];
    const double d2 = s2 - s;
    if (d2 < lo - kRound || d2 > hi + kRound) continue;  // as expand
    Cand c{s2, n.seg, 0};
    if (step_ok(s, d, n.seg, s2, c.seg2)) c.ok = dynamics_ok(q, point(s2, c.seg2)) ? 2 : -1;
    if (c.ok > 0) {
      out = before.ok == -1 ? boundary(n, q, c, before, 1, false) : c;
      return true;
    }
    before = c;
  }
  return false;
}

// The greedy brake: the smallest feasible step every cycle until the tool rests (step 0, or
// the end point reached with a step ≤ a). Returns the cycles taken, 0 if it fails. With
// `record`, each of its samples is committed.
std::size_t SampleSearch::brake_to_rest(Node n, std::uint64_t cycle, bool record) {
  const double end = terminal();
  for (std::size_t k = 1; k < out_reserve_; ++k) {
    ratio_ = ratio_at(cycle + k);
    Cand best{};
    // The rules alone: a brake that comes to rest is a certificate.
    if (!smallest_step(n, best)) return 0;
    const double d2 = best.s2 - n.s;
    n = Node{n.s, best.s2, best.seg2, -1};
    if (record) {
      emit(n, committed_ + 1);
      last_commit_ = n;
      ++committed_;
    }
    if (d2 == 0 || (n.s == end && d2 <= a_)) return k;
  }
  return 0;
}

// Keeps a child if it is among the K farthest of its speed bin (ties: the smaller previous
// sample), dropping exact duplicates.
void SampleSearch::offer(const Node& c, std::size_t cls) {
  const std::size_t b =
      cls * nbins_ + std::min(nbins_ - 1, static_cast<std::size_t>((c.s - c.sp) / bin_w_));
  Node* bin = &bins_[b * opt_.per_bin];
  std::size_t& nb = bin_n_[b];
  auto better = [](const Node& x, const Node& y) { return x.s != y.s ? x.s > y.s : x.sp < y.sp; };
  for (std::size_t i = 0; i < nb; ++i)
    if (std::abs(bin[i].s - c.s) < 1e-12 && std::abs(bin[i].sp - c.sp) < 1e-12) return;
  std::size_t pos = nb;
  while (pos > 0 && better(c, bin[pos - 1])) --pos;
  if (pos >= opt_.per_bin) return;
  const std::size_t last = std::min(nb, opt_.per_bin - 1);
  for (std::size_t i = last; i > pos; --i) bin[i] = bin[i - 1];
  bin[pos] = c;
  nb = std::min(nb + 1, opt_.per_bin);
}

void SampleSearch::emit(const Node& n, std::uint64_t cycle, bool pending) {
  // A sample on a joint belongs to the segment it arrived by (its block's line).
  std::uint64_t line_seg = n.seg;
  if (line_seg > seg_base_ && n.s == seg(line_seg).geo.s0_mm) --line_seg;
  Out& o = out_[(out_head_ + out_count_) % out_.size()];
  o = {point(n.s, n.seg), seg(line_seg).geo.line, n.s, pending, n.sp, n.seg, cycle};
  ++out_count_;
}

// The newest popped sample (the tool's) becomes the newest committed state.
void SampleSearch::from_tool() {
  committed_ = popped_n_ > 0 ? popped_n_ - 1 : 0;
  last_commit_ = Node{popped_sp_, popped_s_, seg_of(popped_s_, last_commit_.seg), -1};
}

bool SampleSearch::pop(AxisVec& position, std::uint32_t& line, double& s_mm) {
  if (out_count_ == 0) return false;
  if (out_[out_head_].pending) {
    // Certified as it is handed out, not when its lineage is committed: one brake per cycle
    // instead of up to L in the cycle a lineage coalesces (the search's worst cycles).
    const Out& o = out_[out_head_];
    const std::size_t k = brake_to_rest(Node{o.sp, o.s, o.seg, -1}, o.cycle, false);
    if (k == 0) {
      // Met like a death, from the tool's sample (certified when it was popped): what was
      // planned after it goes.
      ++stats_.uncertified;
      out_count_ = 0;
      from_tool();
      at_stop_ = finished_ = false;
      recover();
      if (out_count_ == 0) return false;
    } else {
      stats_.longest_brake = std::max(stats_.longest_brake, k);
      out_[out_head_].pending = false;
    }
  }
  const Out& o = out_[out_head_];
  position = o.p;
  line = o.line;
  s_mm = o.s;
  popped_sp_ = popped_n_ > 0 ? popped_s_ : o.s;
  popped_s_ = o.s;
  ++popped_n_;
  out_head_ = (out_head_ + 1) % out_.size();
  --out_count_;
  return true;
}

// Commits the state n (the cycle after committed_); pop() certifies it (its greedy brake to
// rest) before handing it out.
void SampleSearch::commit_pending(const Node& n) {
  ++committed_;
  last_commit_ = n;
  emit(n, committed_, true);
}

// The lineage of entry i of row `cycle`, from committed_ + 1 up to `cycle`, is committed state
// by state (pop() certifies each before handing it out).
void SampleSearch::commit_lineage(std::uint64_t cycle, std::size_t i) {
  const auto len = static_cast<std::size_t>(cycle - committed_);
  for (std::size_t k = len; k-- > 0;) {
    const Hist& h = hist(committed_ + 1 + k, i);
    trace_[k] = Node{0, h.s, 0, static_cast<std::int32_t>(i)};
    i = static_cast<std::size_t>(h.parent);
  }
  for (std::size_t k = 0; k < len; ++k) {
    Node n{last_commit_.s, trace_[k].s, 0, -1};
    n.seg = seg_of(n.s, last_commit_.seg);
    commit_pending(n);
  }
  retire();
}

void SampleSearch::retire() {
  // Behind the tool (the newest popped sample): a restart starts from there.
  const double behind = std::min(last_commit_.sp, popped_sp_);
  while (seg_base_ + 1 < seg_end_ && seg(seg_base_).geo.end_mm() < behind) ++seg_base_;
}

// The newest cycle from which every live state descends, by walking the live states' ancestors
// back one row at a time (distinct indices marked with a stamp).
void SampleSearch::find_coalescence() {
  std::size_t n = beam_.size();
  for (std::size_t i = 0; i < n; ++i) idx_a_[i] = static_cast<std::uint32_t>(i);
  for (std::uint64_t c = front_; c > committed_; --c) {
    if (n == 1) {
      commit_lineage(c, idx_a_[0]);
      return;
    }
    ++stamp_;
    std::size_t m = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const auto p = static_cast<std::uint32_t>(hist(c, idx_a_[i]).parent);
      if (mark_[p] == stamp_) continue;
      mark_[p] = stamp_;
      idx_b_[m++] = p;
    }
    std::swap(idx_a_, idx_b_);
    n = m;
  }
}

std::size_t SampleSearch::ancestor(std::size_t i, std::uint64_t cycle) const {
  for (std::uint64_t c = front_; c > cycle; --c) i = static_cast<std::size_t>(hist(c, i).parent);
  return i;
}

// The commits lag the front by more than L: keep only the states that share, L/2 cycles back,
// the ancestor of the farthest state whose ancestor there brakes to rest.
void SampleSearch::force_commit() {
  ++stats_.forced;
  const std::uint64_t c0 = front_ - opt_.max_lag_cycles / 2;
  const std::size_t n = beam_.size();
  for (std::size_t i = 0; i < n; ++i) idx_a_[i] = static_cast<std::uint32_t>(i);
  std::sort(idx_a_.begin(), idx_a_.begin() + static_cast<std::ptrdiff_t>(n),
            [&](std::uint32_t x, std::uint32_t y) { return beam_[x].s > beam_[y].s; });
  std::size_t target = beam_cap_;
  for (std::size_t k = 0; k < n && target == beam_cap_; ++k) {
    const std::size_t t = ancestor(idx_a_[k], c0);
    const Hist& h = hist(c0, t);
    const double sp = hist(c0 - 1, static_cast<std::size_t>(h.parent)).s;
    const Node st{sp, h.s, seg_of(h.s, last_commit_.seg), -1};
    if (brake_to_rest(st, c0, false) > 0) target = t;
  }
  if (target == beam_cap_) {
    recover();
    return;
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (ancestor(i, c0) != target) continue;
    hist(front_, kept) = hist(front_, i);
    beam_[kept] = beam_[i];
    beam_[kept].parent = static_cast<std::int32_t>(kept);
    ++kept;
  }
  beam_.resize(kept);
  find_coalescence();
}

// The beam died, a forced commit found no lineage that brakes to rest, or a hold: the tool
// brakes to rest from the newest committed state that certifies, and the search starts again
// from rest.
void SampleSearch::recover() {
  ++stats_.recoveries;
  // The newest committed state may not be certified yet (pop() certifies): the newest that is
  // brakes, and what was committed after it goes (pop() still certifies those before it).
  while (out_count_ > 0) {
    Out& o = out_[(out_head_ + out_count_ - 1) % out_.size()];
    if (!o.pending) break;
    if (brake_to_rest(Node{o.sp, o.s, o.seg, -1}, o.cycle, false) > 0) {
      o.pending = false;
      break;
    }
    ++stats_.uncertified;
    if (--out_count_ == 0) {
      from_tool();
    } else {
      const Out& b = out_[(out_head_ + out_count_ - 1) % out_.size()];
      committed_ = b.cycle;
      last_commit_ = Node{b.sp, b.s, b.seg, -1};
    }
  }
  if (brake_to_rest(last_commit_, committed_, true) == 0) {
    failed_ = true;  // cannot happen: the state was certified by this very brake
    return;
  }
  front_ = committed_;
  if (last_commit_.s == terminal()) {
    reached_terminal();
    return;
  }
  restart_at_rest();
}

void SampleSearch::restart_at_rest() {
  const double s = last_commit_.s;
  last_commit_.sp = s;
  beam_.assign(1, Node{s, s, last_commit_.seg, 0});
  hist(front_, 0) = {s, -1};
  retire();
}

double SampleSearch::terminal() const {
  if (hard_n_ > 0) return joint_s(hard_q_[hard_head_]);
  return program_ended_ && seg_end_ > 0 ? joint_s(seg_end_ - 1) : kInf;
}

void SampleSearch::reached_terminal() {
  if (program_ended_ && last_commit_.s == joint_s(seg_end_ - 1)) {
    finished_ = true;
    return;
  }
  // One sample at rest on the stop: the tool has stopped there (the kernel handles the event
  // then), and the plan after it starts from rest, not from the landing step.
  at_stop_ = true;
  last_commit_.sp = last_commit_.s;
  emit(last_commit_, committed_ + 1);
  front_ = ++committed_;
}

void SampleSearch::mark_stop() {
  if (seg_end_ == 0) {
    stop_at_start_ = true;  // a stop before any motion: wait at the start for resume()
    return;
  }
  const std::uint64_t last = seg_end_ - 1;
  Seg& l = seg(last);
  if (l.hard_stop) return;
  l.hard_stop = true;
  hard_q_[(hard_head_ + hard_n_) % hard_q_.size()] = last;
  ++hard_n_;
}

void SampleSearch::resume() {
  if (stop_at_start_) {
    stop_at_start_ = false;
    return;
  }
  if (!at_stop_) return;
  at_stop_ = false;
  while (hard_n_ > 0 && joint_s(hard_q_[hard_head_]) <= last_commit_.s) {
    hard_head_ = (hard_head_ + 1) % hard_q_.size();
    --hard_n_;
  }
  front_ = committed_;
  restart_at_rest();
}

double SampleSearch::ratio_at(std::uint64_t cycle) const {
  double r = or_;
  for (std::size_t i = 0; i < allow_n_; ++i)
    if (cycle <= allow_[i].until) r = std::max(r, allow_[i].ratio);
  return r;
}

void SampleSearch::restart(double ratio, std::size_t ramp_cycles) {
  ++stats_.restarts;
  const std::uint64_t c = popped_n_ > 0 ? popped_n_ - 1 : 0;
  // The checker judges a sample by the largest override among the samples of the last ramp:
  // each override a decrease replaces stands until `ramp_cycles` after its last sample.
  std::size_t n = 0;
  for (std::size_t i = 0; i < allow_n_; ++i)
    if (allow_[i].until > c && allow_[i].ratio > ratio) allow_[n++] = allow_[i];
  allow_n_ = n;
  if (ramp_cycles > 0 && or_ > ratio) {
    if (allow_n_ == allow_.size()) {
      // Full: the one that expires first goes (less allowance: the plan brakes sooner).
      std::size_t first = 0;
      for (std::size_t i = 1; i < allow_n_; ++i)
        if (allow_[i].until < allow_[first].until) first = i;
      allow_[first] = allow_[--allow_n_];
    }
    allow_[allow_n_++] = {or_, c + ramp_cycles};
  }
  or_ = ratio;
  eff_fresh_ = seg_base_;  // refresh_eff() makes them current ahead of the front
  // At rest on a stop or at the end, with nothing left to pop: the new override applies from
  // the resume (planning now would move the tool while the kernel handles the stop's event).
  if ((at_stop() || finished_) && out_count_ == 0) return;
  out_count_ = 0;
  committed_ = front_ = c;
  last_commit_ = Node{popped_sp_, popped_s_, seg_of(popped_s_, last_commit_.seg), 0};
  beam_.assign(1, last_commit_);
  hist(front_, 0) = {popped_s_, -1};
  finished_ = false;
  at_stop_ = false;
}

void SampleSearch::idle() {
  // Only at rest with nothing planned ahead: the root state just moves to the next cycle.
  if (out_count_ != 0 || front_ != committed_ || last_commit_.sp != last_commit_.s) return;
  ++popped_n_;
  front_ = committed_ = popped_n_ - 1;
  popped_sp_ = popped_s_;
  if (!beam_.empty()) {
    hist(front_, 0) = {last_commit_.s, -1};
    beam_.assign(1, Node{last_commit_.s, last_commit_.s, last_commit_.seg, 0});
  }
}

void SampleSearch::brake_now() {
  restart(or_, 0);
  recover();
}

bool SampleSearch::advance(bool near_window_end) {
  if (finished_ || failed_ || at_stop() || seg_end_ == 0) return false;
  if (out_.size() - out_count_ < out_reserve_) return false;
  double far = 0;
  for (const Node& n : beam_) far = std::max(far, n.s);
  const double window_end = joint_s(seg_end_ - 1);
  const double end = terminal();
  refresh_eff(far + reach_mm_);
  // Without a stop ahead the front keeps a braking distance from the window's end.
  if (end == kInf && !near_window_end && far + reach_mm_ >= window_end) return false;
  ratio_ = ratio_at(front_ + 1);
  guide_cycle_ = front_ + 1;

  std::fill(bin_n_.begin(), bin_n_.end(), 0);
  std::int64_t done = -1;
  for (std::size_t bi = 0; bi < beam_.size() && done < 0; ++bi) {
    const Node nd = beam_[bi];
    std::size_t count = 0;
    expand(nd, count);
    for (std::size_t i = 0; i < count; ++i) {
      const Cand& c = cands_[i];
      const double d2 = c.s2 - nd.s;
      if (c.s2 == end) {
        if (d2 <= a_) {
          done = static_cast<std::int64_t>(bi);
          break;
        }
        continue;
      }
      offer(Node{nd.s, c.s2, c.seg2, static_cast<std::int32_t>(bi)}, c.ok == 2 ? 0 : 1);
    }
  }
  stats_.expanded += beam_.size();
  ++stats_.cycles;
  if (done >= 0) {
    // The end point or a stop: commit the lineage to it (it ends at rest: no brake needed).
    auto i = static_cast<std::size_t>(done);
    const auto len = static_cast<std::size_t>(front_ - committed_);
    for (std::size_t k = len; k-- > 0;) {
      const Hist& h = hist(committed_ + 1 + k, i);
      trace_[k] = Node{0, h.s, 0, 0};
      i = static_cast<std::size_t>(h.parent);
    }
    for (std::size_t k = 0; k < len; ++k) {
      last_commit_ = Node{last_commit_.s, trace_[k].s, seg_of(trace_[k].s, last_commit_.seg), -1};
      emit(last_commit_, committed_ + 1 + k);
    }
    last_commit_ = Node{last_commit_.s, end, seg_of(end, last_commit_.seg), -1};
    emit(last_commit_, committed_ + 1 + len);
    committed_ = front_ = front_ + 1;
    reached_terminal();
    return true;
  }
  std::size_t kept = 0;
  for (const std::size_t nb : bin_n_) kept += nb;
  if (kept == 0) {
    recover();
    return true;
  }
  ++front_;
  beam_.clear();
  for (std::size_t b = 0; b < bin_n_.size(); ++b) {
    for (std::size_t k = 0; k < bin_n_[b]; ++k) {
      const Node& c = bins_[b * opt_.per_bin + k];
      hist(front_, beam_.size()) = {c.s, c.parent};
      beam_.push_back(c);
      beam_.back().parent = static_cast<std::int32_t>(beam_.size() - 1);
    }
  }
  stats_.max_beam = std::max(stats_.max_beam, beam_.size());
  if (front_ - committed_ > opt_.max_lag_cycles) {
    force_commit();
  } else if (front_ % kCoalesceEvery == 0) {
    find_coalescence();
  }
  return true;
}

}  // namespace cncore::motion
