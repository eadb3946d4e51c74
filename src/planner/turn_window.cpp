#include "planner/turn_window.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace cncore::planner {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Items walked back at most when the window over the largest step binds (then exact).
constexpr std::size_t kWalk = 512;
// Ring sizes: queue entries and runs within the largest step beyond this saturate (no bound
// from the rings until the chain ends; the joints are then held to the wide range's speed).
constexpr std::size_t kRing = 4096;
// Items whose tangent ranges stay within this of each other per axis share a run.
constexpr double kMergeSpread = 1e-9;

// The largest speed whose turn over a window of this range keeps the limits (1 % kept for the
// chords' second-order terms).
double turn_limit(const Turn& t, const Limits& limits) {
  constexpr double kShare = 0.99;
  double v = kInf;
  if (t.total > 0) v = std::min(v, kShare * limits.amax_pc2 / t.total);
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!limits.axis_on[i] || limits.axis_amax_pc2[i] <= 0 || t.axis[i] <= 0) continue;
    v = std::min(v, kShare * limits.axis_amax_pc2[i] / t.axis[i]);
  }
  return v;
}

Turn make_turn(const std::array<double, kMaxAxes>& lo, const std::array<double, kMaxAxes>& hi) {
  Turn t;
  double sum2 = 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    t.axis[i] = std::max(0.0, hi[i] - lo[i]);
    t.top[i] = std::min(1.0, std::max(std::abs(lo[i]), std::abs(hi[i])));
    sum2 += t.axis[i] * t.axis[i];
  }
  t.total = std::sqrt(sum2);
  return t;
}

}  // namespace

void tangent_range(const Segment& s, std::array<double, kMaxAxes>& lo,
                   std::array<double, kMaxAxes>& hi) {
  const AxisVec e0 = s.start_direction(), e1 = s.end_direction();
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    lo[i] = std::min(e0[i], e1[i]);
    hi[i] = std::max(e0[i], e1[i]);
  }
  if (!s.arc) return;
  // Along the arc the plane components are a sinusoid of amplitude ≤ h_i (the axis' share of
  // the plane): over a sweep Φ it bulges past the nearer end by ≤ h_i·(1 − cos(Φ/2)).
  const double sweep = std::abs(s.sweep_rad);
  for (std::size_t i = 0; i < 3; ++i) {
    const double h = std::hypot(component(s.e1, i), component(s.e2, i));
    const double bulge = sweep >= 2 * std::numbers::pi ? 2 * h : h * (1 - std::cos(0.5 * sweep));
    lo[i] -= bulge;
    hi[i] += bulge;
  }
}

TurnWindow::TurnWindow(std::size_t capacity, double window_mm)
    : window_mm_(window_mm), runs_(std::min(capacity + 2, kRing)) {
  // (Entries and runs are not initialised: the pages are touched only as the rings fill.)
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    hi_[i].ring.resize(std::min(capacity + 2, kRing));
    lo_[i].ring.resize(std::min(capacity + 2, kRing));
  }
}

void TurnWindow::clear() {
  for (std::size_t i = 0; i < kMaxAxes; ++i) hi_[i].size = lo_[i].size = 0;
  saturated_ = false;
  run_head_ = run_count_ = 0;
}

void TurnWindow::prune(double from_mm) {
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    while (hi_[i].size > 0 && hi_[i].front().end_mm <= from_mm) hi_[i].pop_front();
    while (lo_[i].size > 0 && lo_[i].front().end_mm <= from_mm) lo_[i].pop_front();
  }
  // Runs wholly before every later window (the newest one always stays).
  while (run_count_ > 1 && runs_[run_head_].end_mm <= from_mm) {
    run_head_ = run_head_ + 1 == runs_.size() ? 0 : run_head_ + 1;
    --run_count_;
  }
}

void TurnWindow::on_segment(const Segment& s, bool joint) {
  if (!joint) {
    clear();
    chain_s0_mm_ = s.s0_mm;
  }
  // Windows end at joints at or after s's start: items ending a window's length before it
  // are in none of them.
  prune(s.s0_mm - window_mm_);
  std::array<double, kMaxAxes> lo, hi;
  tangent_range(s, lo, hi);
  const double end = s.end_mm();
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    Queue& qh = hi_[i];
    while (qh.size > 0 && qh.back().value <= hi[i]) qh.pop_back();
    Queue& ql = lo_[i];
    while (ql.size > 0 && ql.back().value >= lo[i]) ql.pop_back();
    // (Full: more items within the largest step than the buffer holds; no bound from here on
    // until the chain ends.)
    if (qh.size == qh.ring.size() || ql.size == ql.ring.size()) {
      saturated_ = true;
      continue;
    }
    qh.push_back({end, hi[i]});
    ql.push_back({end, lo[i]});
  }
  // The item joins the newest run when the tangent stays within kMergeSpread of it.
  bool merge = joint && run_count_ > 0;
  if (merge) {
    const Run& r = run(0);
    for (std::size_t i = 0; i < kMaxAxes && merge; ++i) {
      merge = std::max(r.hi[i], hi[i]) - std::min(r.lo[i], lo[i]) <= kMergeSpread;
    }
  }
  joint_inside_ = merge;
  if (merge) {
    Run& r = run(0);
    r.end_mm = end;
    r.line = r.line && !s.arc;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      r.lo[i] = std::min(r.lo[i], lo[i]);
      r.hi[i] = std::max(r.hi[i], hi[i]);
    }
    return;
  }
  if (run_count_ == runs_.size()) {
    // Full: the oldest run is dropped, and with it the walk's knowledge of the chain's start.
    run_head_ = run_head_ + 1 == runs_.size() ? 0 : run_head_ + 1;
    --run_count_;
    saturated_ = true;
  }
  ++run_count_;
  run(0) = Run(s.s0_mm, end, lo, hi, !s.arc);
}

double TurnWindow::chain_speed_pc(const SegmentBuffer& buf, std::uint64_t index_a,
                                  std::uint64_t index_b, double vg_pc, const Limits& limits,
                                  Turn& turn) {
  turn = Turn{};
  const double v = find_speed(buf, index_a, index_b, vg_pc, limits, turn);
  // This joint: inside the newest run, or at the end of the one before it.
  if (joint_inside_) {
    run(0).cap_inside = std::min(run(0).cap_inside, v);
  } else if (run_count_ > 1) {
    run(1).cap_end = v;
  }
  return v;
}

double TurnWindow::find_speed(const SegmentBuffer& buf, std::uint64_t index_a,
                              std::uint64_t index_b, double vg_pc, const Limits& limits,
                              Turn& turn) const {
  if (!(vg_pc > 0)) return vg_pc;
  const Segment& a = buf[index_a];
  const Segment& b = buf[index_b];
  // a at least vg long: the window holds this corner alone (and a's arc, which the corner's
  // own rule and zone count, the turning v·κ added to it), so vg is the single-corner rule's.
  if (a.length_mm >= vg_pc) return vg_pc;
  const double j = b.s0_mm;
  // The range over the largest step's window (a bound for every shorter one).
  Turn wide;
  if (saturated_) {
    wide.axis.fill(2.0);
    wide.top.fill(1.0);
    wide.total = 2 * std::sqrt(static_cast<double>(kMaxAxes));
  } else {
    std::array<double, kMaxAxes> lo, hi;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      hi[i] = hi_[i].size > 0 ? hi_[i].front().value : 0.0;
      lo[i] = lo_[i].size > 0 ? lo_[i].front().value : 0.0;
    }
    wide = make_turn(lo, hi);
  }
  // Only the corner itself in it: its own rule (planner::joint_speed_pc) is exact.
  const AxisVec e = a.end_direction(), s = b.start_direction();
  double own2 = 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) own2 += (s[i] - e[i]) * (s[i] - e[i]);
  if (wide.total <= std::sqrt(own2) * (1 + 1e-9) + 1e-12) return vg_pc;
  const double g_wide = turn_limit(wide, limits);
  // Walk back from the joint over the runs. The runs R0 (the newest, holding b) …
  // R hold the windows (j − m, j] with m in (j − end_R, j − s0_R]; such a window only
  // constrains V when a pair of steps ≤ V can span it: m ≤ V and m ≤ the cap of every other
  // joint in it (the steps around each are ≤ its cap; of a run only partly in the window just
  // its end joint is known to be inside). m·spread(m) grows with m: the first m that violates
  // it bounds V. A window of two runs of lines holds one corner, whose own rule and zone
  // (planner::joint_speed_pc, the acc/dec's) already cover every pair across it: no bound,
  // and no chain for the zone (`turn` stays empty).
  double v = vg_pc;
  double vmin = kInf;  // the lowest cap of the other joints in the window so far
  // Windows end at j: of b only its start direction S is in them.
  std::array<double, kMaxAxes> lo, hi;
  for (std::size_t i = 0; i < kMaxAxes; ++i) lo[i] = hi[i] = s[i];
  double far = 0;  // the longest window walked
  bool done = false;
  bool lines = true;  // every run so far is one of lines
  // (Runs ending a window's length W before the newest item are pruned: running out of runs
  // means every longer window is longer than any step.)
  std::size_t r = 0;
  for (; r < run_count_; ++r) {
    if (r > kWalk) break;
    const Run& x = run(r);
    if (r == 0 && x.s0_mm >= j) continue;  // b's own run: S is in already
    lines = lines && x.line;
    if (r > 0) {
      vmin = std::min({vmin, x.cap_end, run(r - 1).cap_inside});
    }
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      lo[i] = std::min(lo[i], x.lo[i]);
      hi[i] = std::max(hi[i], x.hi[i]);
    }
    const double near = std::max(0.0, j - x.end_mm);
    far = j - x.s0_mm;
    if (far <= 0) continue;  // R0 = b alone: its start direction is in every window
    const double reach = std::min({far, vmin, v});
    if (reach <= near) {
      done = true;  // no pair spans a longer window
      break;
    }
    if (r <= 1 && lines) {  // one corner at most
      if (x.s0_mm <= chain_s0_mm_) {
        done = true;
        break;
      }
      continue;
    }
    const Turn t = make_turn(lo, hi);
    const double g = turn_limit(t, limits);
    if (g < reach) {
      v = std::max(near, g);
      if (v > near) turn = t;
      done = true;
      break;
    }
    turn = t;
    if (x.s0_mm <= chain_s0_mm_) {
      done = true;  // the chain starts here: no longer window
      break;
    }
  }
  if (r == run_count_ && !saturated_) done = true;
  // Walked only part of it: the longer windows have at most the wide range.
  if (!done && g_wide < v) {
    v = std::max(std::min(v, far), g_wide);
    turn = wide;
  }
  return v;
}

}  // namespace cncore::planner
