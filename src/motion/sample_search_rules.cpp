// The sample search's rules of one step and the expansion of a state: the guide (can_brake()),
// the static and dynamic rules, the candidate landings and their boundaries, the greedy brake.
#include <algorithm>
#include <cmath>
#include <limits>

#include "motion/sample_search.hpp"
#include "motion/sample_search_common.hpp"

namespace cncore::motion {

using namespace sample_search_common;  // NOLINT(google-build-using-namespace)

namespace {
constexpr double kWindow = 1e-5;   // mm before a joint where no sample lands (checker's snap)
constexpr double kFoldCos = -0.5;  // cos of a turn of 120°: a fold of the path onto itself
// A sharp corner: |S − E| > 0.5 (θ ≈ 29°), i.e. cos θ < 1 − 0.5²/2 (|S − E|² = 2 − 2·cos θ).
constexpr double kSharpCos = 0.875;
}  // namespace

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

}  // namespace cncore::motion
