// cncore-sref: an achievable sampled reference trajectory, searched cycle by cycle.
//   cncore-sref PROGRAM.ngc -o TRAJ.csv [--machine FILE.toml] [--per-bin K] [--bins-per-a B]
//               [--grid G] [--limit-factor M] [--bisect N] [--guide-joints J] [-v]
//               [--trace FROM --trace-to TO] [--certify] [--max-lag L] [--recover]
//               [--seed-trajectory T.csv] [--module]
// Prints one line "cycles=… time_s=… bound_s=… ratio=… …" (ratio: time over cncore-bound's
// bound); with --certify, --max-lag or --recover a second one (below). The trajectory has one row
// per cycle from the start (t = 0) to the arrival on the end point (no trailing rest sample). Check
// it with `cncore-trajcheck PROGRAM TRAJ.csv`. Typical cost: K=8, B=4, G=9 takes 5 s on a 10
// 000-segment, 11 000-cycle program; the time grows about linearly with K·B and with G. Memory
// stays small (dead lineages are dropped).
//
// Why: the continuous time-optimal bound (cncore-bound) passes every corner in zero time at
// Vg = Amax·τ/(2 sin(θ/2)). A sampled trajectory is judged differently by the checker
// (tests/support/trajectory_checker.cpp, check_trajectory): what is limited at a joint is the
// *step that crosses it*, and the dynamics are finite differences of the samples. Whether any
// sampled trajectory reaches a given multiple of the bound is therefore not obvious. This tool
// searches for one with as few cycles as it can find; a result that passes cncore-trajcheck is
// an achievable cycle time (an upper bound on the sampled optimum, never a lower bound).
//
// The rules (those of check_trajectory, every limit scaled by M = --limit-factor, 0.999 by
// default, so that the result passes the checker with its own 0.5 % margin untouched):
//   - samples every τ, each exactly on the programmed path (position = arc length s; the point is
//     PathSegment::point_at((s − s0)/length), which is how the checker measures progress);
//   - path speed v[k] = (s[k] − s[k−1])/τ: the step d[k] = s[k] − s[k−1] ≥ 0;
//   - tangential: |d[k+1] − d[k]| ≤ M·Amax·τ² (and d[0] = 0: the motion starts at rest);
//   - joint j (end of segment j): the step of the first sample at or past it is at most
//     M·Vg_j·τ, Vg_j = min(shape limits of both segments, Amax·τ/(2 sin(θ/2)));
//   - speed: every step at most M·τ·(feed or rapid rate, √(R·Amax) on arcs) of each segment it
//     touches (the checker uses the landing segment; all touched is stricter);
//   - normal: √(l1·l2)·|d̂2 − d̂1| ≤ M·Amax·τ² for consecutive XYZ chords d1, d2;
//   - per axis: |second difference| ≤ M·A_i·τ², |first difference| ≤ M·V_i·τ (configured axes);
//     resultant |d2 − d1| ≤ M·Ares·τ² when the limits have one;
//   - stops (exact stop, M-code waits, the end): a sample lands exactly on the stop point with a
//     step ≤ M·Amax·τ², and no step passes it. Dwells are not supported.
// A sample never lands in the last δ = 1e-5 mm before a joint: there the checker could count
// the joint as reached by that sample or by the next one (its snap distance).
//
// Method: beam search over cycles. A state is (s_prev, s): the last two samples. Each state
// expands to next steps in [d − a, d + a] (a = M·Amax·τ²): a uniform grid of G steps, plus the
// exact boundary values (landing exactly on each joint in reach, just before it, the largest
// step each crossed joint's cap allows), plus, between a feasible and an infeasible candidate,
// the boundary of the normal / per-axis rules found by bisection. Children that cannot brake in
// time for the caps ahead are dropped (the backward guide below), the rest are binned by step
// (width a/B) and each bin keeps its K farthest states. The first cycle in which a state lands
// on the end point at rest is the result; the trajectory is rebuilt from the parents.
//
// Backward guide (a necessary condition, so it never drops a feasible state): a state with step
// d that must cross a joint at distance D ahead with a step ≤ C brakes at best by a per cycle,
// so the landings before the crossing step cover at least
//   brake_distance(d, C) = Σ_{i=1}^{m−1} (d − i·a),  m = ⌈(d − C)/a⌉,
// which must be < D. C_j is joint j's effective cap: its own cap, its segment's, and the largest
// crossing step from which joint j+1 can still be met (computed once, backwards from the end;
// checked for the next joints of every state, each on its own).
//
// --certify asks what a planner that ran this search ahead of the tool could hand the cycle
// (docs/lookahead.md, "The search type"). Every 64 cycles, the cycles whose
// history holds one state are *committed*: every live state descends from them, so a planner
// could give them to the cycle. Each committed state is then braked greedily (the smallest
// feasible step every cycle) until the tool rests; a state that comes to rest so has a safe
// continuation whatever the search finds later. The line reports how many committed states came
// to rest, the longest such brake and the longest lag of the commits behind the search's front.
// --max-lag L forces a commit once the commits lag the front by more than L cycles (checked every
// 64): the beam keeps only the states that share, L/2 cycles back, the ancestor of the farthest
// state whose ancestor there brakes to rest (with --certify). --recover meets a death (no state
// can continue) as a planner would: from the newest committed state that braked to rest, brake
// to rest again and search on from rest.
// --seed-trajectory T keeps the samples of T (e.g. the kernel's, without its merge stage) in the
// beam as one lineage, whatever the selection says: the result is never slower than T, and the
// search can leave T wherever it finds better (ends with --max-lag's forced commits and with a
// recovery).
// --module runs motion::SampleSearch instead (the planner's version: streaming, fixed buffers,
// certified and forced commits; --per-bin, --bins-per-a, --grid, --max-lag, --limit-factor,
// --bisect and --guide-joints apply) and prints its counters on the second line.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "bound.hpp"
#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "limits.hpp"
#include "motion/sample_search.hpp"
#include "path_geometry.hpp"
#include "planner/segment.hpp"
#include "program_blocks.hpp"
#include "trajectory.hpp"

namespace {

using cncore::AxisVec;
using cncore::kMaxAxes;
using cncore::Vec3;
using cncore::testing::Limits;
using cncore::testing::Path;
using cncore::testing::PathSegment;

constexpr double kWindow = 1e-5;  // mm before a joint where no sample lands (checker's snap)
constexpr double kRound = 1e-9;   // mm of rounding allowed on a step's range (far below margins)

struct Options {
  std::size_t per_bin = 8;                   // K: states kept per speed bin
  double bins_per_a = 4;                     // B: speed bins per a (bin width a/B)
  std::size_t grid = 9;                      // G: uniform candidate steps in [d − a, d + a]
  double factor = 0.999;                     // M: every limit scaled by this
  int bisect = 14;                           // bisection steps for the normal / per-axis boundary
  std::size_t guide_joints = 16;             // joints ahead checked by the backward guide
  std::size_t trace_from = 0, trace_to = 0;  // cycles with a diagnostic line on stderr
  bool certify = false;                      // brake every committed state to rest (greedy)
  std::size_t max_lag = 0;                   // force a commit when the lag exceeds this (0: never)
  bool recover = false;  // on a death, brake to rest from the newest committed state, restart
};

// Every limit as a length per cycle (mm per τ or per τ²), already scaled by M.
struct Rules {
  double a = 0;                           // tangential step change
  double normal = 0;                      // √(l1·l2)·|d̂2 − d̂1|
  double resultant = 0;                   // |d2 − d1| (0: not checked)
  std::array<double, kMaxAxes> axis_a{};  // per-axis second difference (0: none)
  std::array<double, kMaxAxes> axis_v{};  // per-axis first difference (0: none)
};

struct Joint {
  double s = 0;    // arc length of the joint (end of segment j)
  double cap = 0;  // largest step that may cross it
  double eff = 0;  // effective cap for the backward guide (≤ cap)
  bool stop = false;
};

class Problem {
 public:
  Problem(const Path& path, const Limits& lim, const Options& opt) : path_(path), opt_(opt) {
    const double tau = lim.period_s;
    const double m = opt.factor;
    const double amax = lim.max_accel_mm_s2;
    rules_.a = m * amax * tau * tau;
    rules_.normal = rules_.a;
    rules_.resultant =
        lim.max_resultant_accel_mm_s2 > 0 ? m * lim.max_resultant_accel_mm_s2 * tau * tau : 0.0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      rules_.axis_a[i] = m * lim.axis_accel_mm_s2[i] * tau * tau;
      rules_.axis_v[i] = m * lim.axis_speed_mm_min[i] / 60.0 * tau;
    }
    const auto& segs = path.segments;
    const std::size_t n = segs.size();
    // The checker's shape limit and speed limit of a segment (override 100 %).
    auto shape_limit = [&](const PathSegment& sg) {
      double vb = sg.rapid ? lim.rapid_mm_s() : lim.feed_mm_s();
      if (sg.arc) vb = std::min(vb, std::sqrt(sg.radius_mm() * amax));
      return vb;
    };
    seg_cap_.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      const PathSegment& sg = segs[j];
      if (sg.length_mm <= 1e-12)
        throw std::runtime_error("segment without XYZ motion (line " + std::to_string(sg.line) +
                                 "): not supported");
      if (sg.dwell_after_s > 0)
        throw std::runtime_error("dwell after line " + std::to_string(sg.line) + ": not supported");
      double v = shape_limit(sg);
      if (!sg.rapid) v = std::min(v, sg.feed_mm_min > 0 ? sg.feed_mm_min / 60.0 : lim.feed_mm_s());
      seg_cap_[j] = m * v * tau;
      max_step_ = std::max(max_step_, seg_cap_[j]);
    }
    joints_.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      Joint& jt = joints_[j];
      jt.s = j + 1 < n ? segs[j + 1].s0_mm : path.length_mm;
      jt.stop = segs[j].stop_after || j + 1 == n;
      if (jt.stop) {
        jt.cap = rules_.a;  // the checker: speed at a stop ≤ Amax·τ
      } else {
        const double theta = cncore::testing::corner_angle_rad(segs[j], segs[j + 1]);
        double vg = std::min(shape_limit(segs[j]), shape_limit(segs[j + 1]));
        if (theta > 1e-12) vg = std::min(vg, amax * tau / (2 * std::sin(theta / 2)));
        jt.cap = m * vg * tau;
      }
    }
    // Effective caps, backwards (see the file comment). A crossing step of joint j also touches
    // segment j, so it is below that segment's cap too; after crossing j (landing at or past
    // it) joint j+1 must still be met.
    for (std::size_t j = n; j-- > 0;) {
      Joint& jt = joints_[j];
      jt.eff = std::min(jt.cap, seg_cap_[j]);
      if (j + 1 < n) {
        const Joint& nx = joints_[j + 1];
        const double room = nx.s - jt.s;
        if (brake_distance(jt.eff, nx.eff) >= room) {
          double lo = 0, hi = jt.eff;  // largest d with brake_distance(d, C) < room
          for (int it = 0; it < 60; ++it) {
            const double mid = 0.5 * (lo + hi);
            (brake_distance(mid, nx.eff) < room ? lo : hi) = mid;
          }
          jt.eff = lo;
        }
      }
    }
  }

  // Shortest distance from a sample reached with step d to the last sample before a joint that
  // must be crossed with a step ≤ c, the steps shrinking by a per cycle at most: the landings of
  // d − a, d − 2a, …, while they are above c (exact for the tangential rule and the cap).
  double brake_distance(double d, double c) const {
    const double a = rules_.a;
    if (d - a <= c) return 0;
    const double m1 = std::ceil((d - c) / a) - 1;  // steps before the crossing one
    return m1 * d - a * m1 * (m1 + 1) / 2;
  }

  const Rules& rules() const { return rules_; }
  const std::vector<Joint>& joints() const { return joints_; }
  double max_step() const { return max_step_; }
  double length() const { return path_.length_mm; }
  std::size_t segments() const { return path_.segments.size(); }

  // Segment holding arc length s: s0 ≤ s < s0 + length (the last one holds its end), searched
  // from a hint in either direction.
  std::size_t seg_of(double s, std::size_t hint) const {
    const auto& segs = path_.segments;
    std::size_t j = std::min(hint, segs.size() - 1);
    while (j + 1 < segs.size() && s >= segs[j + 1].s0_mm) ++j;
    while (j > 0 && s < segs[j].s0_mm) --j;
    return j;
  }
  AxisVec point(double s, std::size_t seg) const {
    const PathSegment& sg = path_.segments[seg];
    const double u = std::clamp((s - sg.s0_mm) / sg.length_mm, 0.0, 1.0);
    return sg.point_at(u);
  }
  std::uint32_t line(std::size_t seg) const { return path_.segments[seg].line; }

  // Dynamic rules of the three samples p0, p1, p2 (normal, per-axis, resultant, axis speed).
  bool dynamics_ok(const AxisVec& p0, const AxisVec& p1, const AxisVec& p2) const {
    const AxisVec c1 = p1 - p0, c2 = p2 - p1;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      if (rules_.axis_v[i] > 0 && std::abs(c2[i]) > rules_.axis_v[i]) return false;
      if (rules_.axis_a[i] > 0 && std::abs(c2[i] - c1[i]) > rules_.axis_a[i]) return false;
    }
    const Vec3 d1 = c1.xyz(), d2 = c2.xyz();
    const double l1 = cncore::norm(d1), l2 = cncore::norm(d2);
    if (l1 > 0 && l2 > 0) {
      const double an = std::sqrt(l1 * l2) * cncore::norm((1.0 / l2) * d2 - (1.0 / l1) * d1);
      if (an > rules_.normal) return false;
    }
    if (rules_.resultant > 0 && cncore::norm(d2 - d1) > rules_.resultant) return false;
    return true;
  }

  // Necessary condition to meet the caps ahead from a sample at s reached with step d (each
  // joint's effective cap checked on its own, exactly for the tangential rule).
  bool can_brake(double s, double d, std::size_t seg) const {
    const double free = brake_distance(d, 0);  // a joint farther than this never binds
    // First joint strictly after s: by seg_of's convention, the end of segment seg.
    for (std::size_t j = seg, k = 0; j < joints_.size() && k < opt_.guide_joints; ++j, ++k) {
      const Joint& jt = joints_[j];
      if (jt.s <= s) continue;
      if (jt.s - s > free) break;
      if (brake_distance(d, jt.eff) >= jt.s - s) return false;
    }
    return true;
  }

  // Static rules of a step from s (in segment seg) landing at s2: joints crossed, stops,
  // segment caps and the window before a joint. Writes the landing segment.
  bool step_ok(double s, std::size_t seg, double s2, std::size_t& seg2) const {
    const double d = s2 - s;
    if (d < 0) return false;
    double cap = seg_cap_[seg];
    std::size_t j = seg;
    for (; j < joints_.size(); ++j) {
      const Joint& jt = joints_[j];
      if (jt.s <= s) continue;
      if (s2 < jt.s) {
        if (s2 > jt.s - kWindow) return false;  // might count as reaching it: avoid
        break;
      }
      // Crossed (or landed on) joint j.
      cap = std::min(cap, jt.cap);
      if (jt.stop && s2 > jt.s) return false;  // passing a stop point
      if (s2 == jt.s) {
        ++j;
        break;
      }
      if (j + 1 < seg_cap_.size()) cap = std::min(cap, seg_cap_[j + 1]);
      if (d > cap) return false;
    }
    if (d > cap) return false;
    seg2 = std::min(j, joints_.size() - 1);
    // Landing exactly on joint j−1 is held by segment j (seg_of's convention).
    seg2 = seg_of(s2, seg2);
    return true;
  }

 private:
  const Path& path_;
  Options opt_;
  Rules rules_;
  std::vector<Joint> joints_;
  std::vector<double> seg_cap_;
  double max_step_ = 0;
};

struct Node {
  double sp = 0;  // previous sample
  double s = 0;   // current sample
  std::uint32_t seg = 0;
  std::int32_t parent = -1;
};

struct Hist {
  double s;
  std::int32_t parent;
};

// Drops the history entries that no state of the beam descends from (lineages coalesce within
// a few hundred cycles, so this keeps the memory near one path plus a recent window). The last
// cycle is the beam itself and is kept whole, index for index.
void compact(std::vector<std::vector<Hist>>& history) {
  const std::size_t n = history.size();
  if (n < 2) return;
  std::vector<std::vector<char>> live(n);
  live[n - 1].assign(history[n - 1].size(), 1);
  for (std::size_t c = n - 1; c-- > 0;) {
    live[c].assign(history[c].size(), 0);
    for (std::size_t i = 0; i < history[c + 1].size(); ++i)
      if (live[c + 1][i] && history[c + 1][i].parent >= 0)
        live[c][static_cast<std::size_t>(history[c + 1][i].parent)] = 1;
  }
  std::vector<std::int32_t> remap;
  for (std::size_t c = 0; c + 1 < n; ++c) {
    remap.assign(history[c].size(), -1);
    std::vector<Hist> kept;
    for (std::size_t i = 0; i < history[c].size(); ++i) {
      if (!live[c][i]) continue;
      remap[i] = static_cast<std::int32_t>(kept.size());
      kept.push_back(history[c][i]);
    }
    history[c] = std::move(kept);
    for (Hist& h : history[c + 1])
      if (h.parent >= 0) h.parent = remap[static_cast<std::size_t>(h.parent)];
  }
}

struct Eval {
  double s2;
  std::size_t seg2;
  int ok;  // 1 ok, 0 static rule fails, −1 dynamic rule fails
};

// The landings a state may step to next: the candidates of the file comment, each judged by the
// rules, plus the dynamic rules' boundaries found by bisection. Only feasible ones (ok == 1).
class Expander {
 public:
  Expander(const Problem& pb, const Options& opt) : pb_(pb), opt_(opt) {}

  void expand(const Node& nd, std::vector<Eval>& out) {
    const Problem& pb = pb_;
    const Options& opt = opt_;
    const double a = pb.rules().a;
    const auto& joints = pb.joints();
    std::vector<double>& cand = cand_;
    std::vector<Eval>& evals = evals_;
    const double s = nd.s, d = nd.s - nd.sp;
    const std::size_t seg = nd.seg;
    const AxisVec p0 = pb.point(nd.sp, pb.seg_of(nd.sp, seg));
    const AxisVec p1 = pb.point(s, seg);
    const double lo = std::max(0.0, d - a), hi = d + a;
    // Candidate landings: grid, then every joint in reach (on it, just before it, and the
    // largest step the caps crossed so far allow).
    cand.clear();
    for (std::size_t i = 0; i < opt.grid; ++i) {
      const double x =
          opt.grid > 1 ? lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(opt.grid - 1)
                       : hi;
      cand.push_back(s + x);
    }
    double cum = std::numeric_limits<double>::infinity();
    for (std::size_t j = seg; j < joints.size(); ++j) {
      const Joint& jt = joints[j];
      if (jt.s <= s) continue;
      if (jt.s > s + hi) break;
      if (jt.s >= s + lo - kWindow) {
        cand.push_back(jt.s);
        cand.push_back(jt.s - kWindow);
      }
      cum = std::min(cum, jt.cap);
      if (s + cum >= jt.s) cand.push_back(s + std::min(cum, hi));
      if (jt.stop) break;
    }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    evals.clear();
    for (const double s2 : cand) {
      const double d2 = s2 - s;
      // Rounding: s + x − s differs from x by some ulps of s (1e-13 mm at 500 mm).
      if (d2 < lo - kRound || d2 > hi + kRound) continue;
      Eval e{s2, seg, 0};
      if (pb.step_ok(s, seg, s2, e.seg2))
        e.ok = pb.dynamics_ok(p0, p1, pb.point(s2, e.seg2)) ? 1 : -1;
      evals.push_back(e);
    }
    // Boundaries of the dynamic rules: bisect between a feasible candidate and an adjacent one
    // that only the dynamic rules reject.
    const std::size_t ne = evals.size();
    for (std::size_t i = 0; i + 1 < ne; ++i) {
      for (int dir = 0; dir < 2; ++dir) {
        const Eval& good = evals[dir == 0 ? i : i + 1];
        const Eval& bad = evals[dir == 0 ? i + 1 : i];
        if (good.ok != 1 || bad.ok != -1) continue;
        double g = good.s2, b = bad.s2;
        std::size_t gseg = good.seg2;
        for (int it = 0; it < opt.bisect; ++it) {
          const double mid = 0.5 * (g + b);
          std::size_t mseg = 0;
          if (pb.step_ok(s, seg, mid, mseg) && pb.dynamics_ok(p0, p1, pb.point(mid, mseg))) {
            g = mid;
            gseg = mseg;
          } else {
            b = mid;
          }
        }
        if (g != good.s2) evals.push_back({g, gseg, 1});
      }
    }
    out.clear();
    for (const Eval& e : evals)
      if (e.ok == 1) out.push_back(e);
  }

 private:
  const Problem& pb_;
  const Options& opt_;
  std::vector<double> cand_;
  std::vector<Eval> evals_;
};

struct Result {
  std::vector<double> s;  // sample positions, s[0] = 0, s.back() = length
  std::size_t max_beam = 0;
  std::size_t expanded = 0;
  // --certify: committed states (all live states descend from them), how many the greedy brake
  // brought to rest, its longest brake in cycles, and the longest commit lag behind the front.
  std::size_t committed = 0, certified = 0, longest_brake = 0, longest_lag = 0;
  std::size_t first_uncertified = 0;  // cycle of the first state the greedy brake lost (0: none)
  std::size_t forced = 0;             // --max-lag: states dropped to force a commit
  std::size_t recoveries = 0;         // --recover: deaths met by braking to rest
  std::size_t last_certified = 0;     // newest committed cycle whose state braked to rest
};

// Greedy bail-out: from a state, take the smallest feasible step every cycle until the tool
// rests (step 0, or the end point reached as the checker's stop). A state it brings to rest has
// a safe continuation whatever the search does next. Returns the cycles taken, 0 if it fails.
std::size_t brake_to_rest(Expander& ex, const Problem& pb, Node n, std::vector<Eval>& evals,
                          std::vector<Node>* path = nullptr) {
  const double a = pb.rules().a;
  for (std::size_t k = 1; k < 100000; ++k) {
    ex.expand(n, evals);
    const Eval* best = nullptr;
    for (const Eval& e : evals)
      if (!best || e.s2 < best->s2) best = &e;
    if (!best) return 0;
    const double d2 = best->s2 - n.s;
    n = {n.s, best->s2, static_cast<std::uint32_t>(best->seg2), -1};
    if (path) path->push_back(n);
    if (d2 == 0 || (best->s2 == pb.length() && d2 <= a)) return k;
  }
  return 0;
}

// seed: arc lengths of a trajectory that keeps the rules (the kernel's, --seed-trajectory), kept
// in the beam as one lineage whatever the selection says; nullptr or empty: none.
Result search(const Problem& pb, const Options& opt, bool verbose,
              const std::vector<double>* seed) {
  const Rules& r = pb.rules();
  const double a = r.a;
  const double bin_w = a / opt.bins_per_a;
  const auto nbins = static_cast<std::size_t>(pb.max_step() / bin_w) + 2;
  const double end = pb.length();

  std::vector<Node> beam{{0.0, 0.0, 0, -1}}, children;
  std::vector<std::vector<Hist>> history;
  history.push_back({{0.0, -1}});
  Expander ex(pb, opt);
  std::vector<Eval> evals;
  std::vector<std::uint32_t> order;
  Result res;
  std::size_t commit_seg = 0;  // segment of the last committed sample (seg_of's hint)
  bool seed_on = seed != nullptr && seed->size() > 1;
  std::size_t seed_idx = 0, seed_seg = 0;  // the seed's state in the beam, its segment
  const auto t0 = std::chrono::steady_clock::now();

  for (std::size_t cycle = 1;; ++cycle) {
    children.clear();
    std::size_t guided = 0;  // children dropped by the backward guide
    const auto parent_of = [](std::size_t bi) { return static_cast<std::int32_t>(bi); };
    std::int32_t done = -1;
    for (std::size_t bi = 0; bi < beam.size() && done < 0; ++bi) {
      const Node& nd = beam[bi];
      const double s = nd.s;
      ex.expand(nd, evals);
      for (const Eval& e : evals) {
        const double d2 = e.s2 - s;
        if (e.s2 == end) {
          if (d2 <= a) {
            children.push_back({s, e.s2, static_cast<std::uint32_t>(e.seg2), parent_of(bi)});
            done = static_cast<std::int32_t>(children.size() - 1);
            break;
          }
          continue;
        }
        if (!pb.can_brake(e.s2, d2, e.seg2)) {
          ++guided;
          continue;
        }
        children.push_back({s, e.s2, static_cast<std::uint32_t>(e.seg2), parent_of(bi)});
      }
    }
    std::size_t seed_child = children.size();  // none
    if (seed_on && done < 0 && cycle < seed->size()) {
      const double s_seed = (*seed)[cycle];
      seed_seg = pb.seg_of(s_seed, seed_seg);
      children.push_back({(*seed)[cycle - 1], s_seed, static_cast<std::uint32_t>(seed_seg),
                          static_cast<std::int32_t>(seed_idx)});
      seed_child = children.size() - 1;
      if (s_seed == end) done = static_cast<std::int32_t>(seed_child);
    } else if (seed_on && done < 0) {
      seed_on = false;  // the seed ended without reaching the end point
    }
    res.expanded += beam.size();
    if (done >= 0) {
      // Rebuild the samples from the parents.
      res.s.assign(cycle + 1, 0.0);
      res.s[cycle] = end;
      std::int32_t p = children[static_cast<std::size_t>(done)].parent;
      for (std::size_t c = cycle; c-- > 0;) {
        const Hist& h = history[c][static_cast<std::size_t>(p)];
        res.s[c] = h.s;
        p = h.parent;
      }
      return res;
    }
    if (children.empty() && opt.recover && res.last_certified > 0) {
      // Recovery, as a planner ahead of the tool would do it: the tool has at most reached the
      // newest committed state that brakes to rest (--certify); from there it brakes to rest
      // greedily, and the search starts again from rest.
      const std::size_t c = res.last_certified;
      history.resize(c + 1);
      Node st{history[c - 1][0].s, history[c][0].s, 0, -1};
      st.seg = static_cast<std::uint32_t>(pb.seg_of(st.s, pb.seg_of(st.sp, 0)));
      std::vector<Node> path;
      std::vector<Eval> scratch;
      if (brake_to_rest(ex, pb, st, scratch, &path) == 0)
        throw std::runtime_error("beam died at cycle " + std::to_string(cycle) +
                                 " and its certified state did not brake to rest again");
      for (const Node& n : path) history.push_back({{n.s, 0}});
      ++res.recoveries;
      seed_on = false;
      res.committed = res.last_certified = history.size() - 1;
      const Node& last = path.back();
      if (last.s == end) {
        res.s.resize(history.size());
        for (std::size_t k = 0; k < history.size(); ++k) res.s[k] = history[k][0].s;
        return res;
      }
      beam.assign(1, {last.s, last.s, last.seg, 0});
      cycle = history.size() - 1;
      continue;
    }
    if (children.empty())
      throw std::runtime_error("beam died at cycle " + std::to_string(cycle) +
                               " (no state can continue)");
    // Selection: per speed bin the K farthest distinct states.
    order.resize(children.size());
    std::iota(order.begin(), order.end(), 0u);
    auto bin = [&](const Node& n) {
      return std::min(nbins - 1, static_cast<std::size_t>((n.s - n.sp) / bin_w));
    };
    std::sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
      const Node& nx = children[x];
      const Node& ny = children[y];
      const std::size_t bx = bin(nx), by = bin(ny);
      if (bx != by) return bx < by;
      if (nx.s != ny.s) return nx.s > ny.s;
      return nx.sp < ny.sp;
    });
    beam.clear();
    std::vector<Hist> hist;
    std::size_t cur_bin = nbins, kept = 0;
    bool seed_kept = false;
    auto keep = [&](const Node& c) {
      hist.push_back({c.s, c.parent});
      Node n = c;
      n.parent = static_cast<std::int32_t>(hist.size() - 1);
      beam.push_back(n);
    };
    for (const std::uint32_t ci : order) {
      const Node& c = children[ci];
      const std::size_t bc = bin(c);
      if (bc != cur_bin) {
        cur_bin = bc;
        kept = 0;
      }
      if (kept >= opt.per_bin) continue;
      if (kept > 0) {
        const Node& last = beam.back();
        if (std::abs(last.s - c.s) < 1e-12 && std::abs(last.sp - c.sp) < 1e-12) continue;
      }
      ++kept;
      if (ci == seed_child) {
        seed_kept = true;
        seed_idx = beam.size();
      }
      keep(c);
    }
    if (seed_on && seed_child < children.size() && !seed_kept) {
      seed_idx = beam.size();
      keep(children[seed_child]);
    }
    history.push_back(std::move(hist));
    if (cycle % 64 == 0) {
      compact(history);
      if (opt.max_lag > 0 && cycle - res.committed > opt.max_lag) {
        // Forced commit: keep only the states that share the farthest state's ancestor
        // max_lag/2 cycles back (the beam is the history's last cycle, index for index).
        const std::size_t c0 = cycle - opt.max_lag / 2;
        auto ancestor = [&](std::size_t i) {
          for (std::size_t c = history.size() - 1; c > c0; --c)
            i = static_cast<std::size_t>(history[c][i].parent);
          return i;
        };
        // The farthest state whose ancestor there brakes to rest (with --certify; else the
        // farthest).
        std::vector<std::size_t> by_s(beam.size());
        std::iota(by_s.begin(), by_s.end(), std::size_t{0});
        std::sort(by_s.begin(), by_s.end(),
                  [&](std::size_t x, std::size_t y) { return beam[x].s > beam[y].s; });
        std::size_t target = ancestor(by_s[0]);
        if (opt.certify) {
          std::vector<Eval> scratch;
          for (const std::size_t i : by_s) {
            const std::size_t t = ancestor(i);
            const auto tp = static_cast<std::size_t>(history[c0][t].parent);
            Node st{history[c0 - 1][tp].s, history[c0][t].s, 0, -1};
            st.seg = static_cast<std::uint32_t>(pb.seg_of(st.s, commit_seg));
            if (brake_to_rest(ex, pb, st, scratch) > 0) {
              target = t;
              break;
            }
          }
        }
        std::vector<Node> kept_beam;
        std::vector<Hist> kept_hist;
        for (std::size_t i = 0; i < beam.size(); ++i) {
          if (ancestor(i) != target) continue;
          kept_hist.push_back(history.back()[i]);
          kept_beam.push_back(beam[i]);
          kept_beam.back().parent = static_cast<std::int32_t>(kept_hist.size() - 1);
        }
        res.forced += beam.size() - kept_beam.size();
        seed_on = false;  // (the seed's lineage may be gone)
        beam = std::move(kept_beam);
        history.back() = std::move(kept_hist);
        compact(history);
      }
      // Cycles whose history holds one state are committed: every live state descends from it.
      std::vector<Eval> scratch;
      std::size_t c = res.committed + 1;
      for (; c < history.size() && history[c].size() == 1; ++c) {
        if (!opt.certify) continue;
        Node st{history[c - 1][0].s, history[c][0].s, 0, -1};
        commit_seg = pb.seg_of(st.s, commit_seg);
        st.seg = static_cast<std::uint32_t>(commit_seg);
        const std::size_t k = brake_to_rest(ex, pb, st, scratch);
        if (k > 0) {
          ++res.certified;
          res.last_certified = c;
          res.longest_brake = std::max(res.longest_brake, k);
        } else if (res.first_uncertified == 0) {
          res.first_uncertified = c;
        }
      }
      res.committed = c - 1;
      res.longest_lag = std::max(res.longest_lag, cycle - res.committed);
    }
    res.max_beam = std::max(res.max_beam, beam.size());
    if (cycle >= opt.trace_from && cycle < opt.trace_to) {
      // Diagnostics: the beam's spread of positions and steps, and the guide's drops.
      double far = 0, dmin = 1e9, dmax = 0, dfar = 0;
      for (const Node& n : beam) {
        if (n.s > far) {
          far = n.s;
          dfar = n.s - n.sp;
        }
        dmin = std::min(dmin, n.s - n.sp);
        dmax = std::max(dmax, n.s - n.sp);
      }
      std::fprintf(stderr,
                   "trace cycle %zu: beam %zu of %zu children (%zu dropped by the guide), "
                   "farthest %.6f mm step %.3f um, steps %.3f..%.3f um\n",
                   cycle, beam.size(), children.size(), guided, far, dfar * 1e3, dmin * 1e3,
                   dmax * 1e3);
    }
    if (verbose && cycle % 1000 == 0) {
      double far = 0;
      for (const Node& n : beam) far = std::max(far, n.s);
      const double el =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::fprintf(stderr, "cycle %zu: beam %zu, farthest %.4f of %.4f mm, %.1f s\n", cycle,
                   beam.size(), far, end, el);
    }
  }
}

// Arc length of every sample of a trajectory on the path: its projection, walking forward from
// the last one (the first segment within 2 nm: the CSV's 6 decimals). The samples must lie on
// the programmed pieces, so run the kernel without the merge stage ([motion]
// merge_tolerance_mm = 0: merged lines are up to 0.5 µm off the pieces, and re-projected they
// break the rules). A sample past a fold (a reversal) that lands beyond the one before is read
// on the way in: such programs are not supported. Samples after the end point are dropped.
std::vector<double> seed_positions(const Path& path, const cncore::testing::Trajectory& tr) {
  std::vector<double> s;
  std::size_t j = 0;
  double u = 0;
  for (const AxisVec& p : tr.pos) {
    bool hit = false;
    for (std::size_t jj = j; jj < path.segments.size() && jj < j + 4096; ++jj) {
      double d = 0;
      const double uu = path.segments[jj].project(p, jj == j ? u : 0.0, d);
      if (d <= 2e-6) {
        j = jj;
        u = uu;
        hit = true;
        break;
      }
    }
    if (!hit) {
      double best = 1e9;
      std::size_t bj = 0;
      for (std::size_t jj = 0; jj < path.segments.size(); ++jj) {
        double d = 0;
        path.segments[jj].project(p, 0.0, d);
        if (d < best) {
          best = d;
          bj = jj;
        }
      }
      throw std::runtime_error("seed sample " + std::to_string(s.size()) +
                               " is off the path (from segment " + std::to_string(j) + " u " +
                               std::to_string(u) + "; nearest segment " + std::to_string(bj) +
                               " at " + std::to_string(best * 1e3) + " um)");
    }
    const auto& sg = path.segments[j];
    s.push_back(j + 1 == path.segments.size() && u >= 1 ? path.length_mm
                                                        : sg.s0_mm + u * sg.length_mm);
    if (s.back() >= path.length_mm - 1e-5) {  // arrived (up to the CSV rounding)
      s.back() = path.length_mm;
      break;
    }
  }
  for (std::size_t k = 1; k < s.size(); ++k) s[k] = std::max(s[k], s[k - 1]);
  return s;
}

// The planner's search (motion::SampleSearch) over the blocks: samples as arc lengths, fed as a
// controller would (blocks while the window has room, every committed sample popped).
std::vector<double> module_search(const std::vector<cncore::Block>& blocks,
                                  const cncore::MachineConfig& machine, const Options& opt,
                                  cncore::motion::SampleSearchStats& stats) {
  cncore::motion::SampleSearchOptions o;
  o.per_bin = opt.per_bin;
  o.bins_per_a = opt.bins_per_a;
  o.grid = opt.grid;
  o.limit_factor = opt.factor;
  o.bisect = opt.bisect;
  o.guide_joints = opt.guide_joints;
  if (opt.max_lag > 0) o.max_lag_cycles = opt.max_lag;
  cncore::motion::SampleSearch ss(cncore::planner::make_limits(machine, false), o);
  std::vector<double> s;
  std::size_t next = 0;
  bool ended = false;
  AxisVec p;
  std::uint32_t line = 0;
  double sm = 0;
  while (!ss.finished()) {
    while (next < blocks.size() && ss.wants_segment())
      if (!ss.push(blocks[next++]))
        throw std::runtime_error("line " + std::to_string(blocks[next - 1].line) +
                                 ": not supported by the module");
    if (next == blocks.size() && !ended) {
      ss.end_of_program();
      ended = true;
    }
    if (ss.at_stop() && ss.ready() == 0) ss.resume();  // released at once
    const bool moved = ss.advance();
    std::size_t popped = 0;
    while (ss.pop(p, line, sm)) {
      s.push_back(sm);
      ++popped;
    }
    if (ss.failed()) throw std::runtime_error("the module's recovery failed");
    if (!moved && popped == 0 && !ss.finished() && (next == blocks.size() || !ss.wants_segment()))
      throw std::runtime_error("the module is stuck (window full)");
  }
  stats = ss.stats();
  return s;
}

int run(int argc, char** argv) {
  CLI::App app{"Search for a sampled trajectory with few cycles that passes the checker"};
  std::string program, machine_file, out, seed_file;
  Options opt;
  bool verbose = false, module = false;
  app.add_option("program", program, "part program (G-code)")->required();
  app.add_option("-o,--output", out, "trajectory CSV to write")->required();
  app.add_option("--machine", machine_file, "machine configuration (TOML); built-in if absent");
  app.add_option("--per-bin", opt.per_bin, "states kept per speed bin (K)")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--bins-per-a", opt.bins_per_a, "speed bins per Amax·τ² of step (B)")
      ->check(CLI::Range(0.01, 1000.0));
  app.add_option("--grid", opt.grid, "uniform candidate steps in [d − a, d + a] (G)")
      ->check(CLI::Range(1, 10000));
  app.add_option("--limit-factor", opt.factor, "every limit scaled by this (M)")
      ->check(CLI::Range(0.5, 1.0));
  app.add_option("--bisect", opt.bisect, "bisection steps at the normal / per-axis boundary")
      ->check(CLI::Range(0, 60));
  app.add_option("--guide-joints", opt.guide_joints,
                 "joints ahead of each state checked by the backward guide (0: no guide)");
  app.add_option("--trace", opt.trace_from, "first cycle with a diagnostic line on stderr");
  app.add_option("--trace-to", opt.trace_to, "end of the traced cycles (exclusive)");
  app.add_flag("--certify", opt.certify,
               "bring every committed state to rest by a greedy brake and count the failures");
  app.add_option("--max-lag", opt.max_lag,
                 "commit by force (keep the farthest state's lineage) once the commits lag the "
                 "front by more than this many cycles (checked every 64 cycles; 0: never)");
  app.add_flag("--recover", opt.recover,
               "when no state can continue, brake to rest from the newest committed state that "
               "--certify brought to rest and search again from rest (instead of failing)");
  app.add_option("--seed-trajectory", seed_file,
                 "a trajectory CSV that keeps the rules (e.g. `cncore run --trajectory`): its "
                 "samples stay in the beam as one lineage, so the result is never slower");
  app.add_flag("--module", module,
               "run motion::SampleSearch (the planner's streaming version) instead");
  app.add_flag("-v,--verbose", verbose, "progress every 1000 cycles on stderr");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    const cncore::MachineConfig machine = cncore::machine_config_or_default(machine_file);
    const Limits lim = cncore::testing::limits_from_config(machine);
    const auto blocks = cncore::testing::read_blocks(program, machine);
    const Path path = cncore::testing::build_path(blocks);
    if (path.empty()) throw std::runtime_error("no motion");
    const Problem pb(path, lim, opt);
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<double> seed;
    if (!seed_file.empty())
      seed = seed_positions(path, cncore::testing::load_trajectory_csv(seed_file));
    cncore::motion::SampleSearchStats mstats;
    Result res;
    if (module) {
      res.s = module_search(blocks, machine, opt, mstats);
      res.expanded = mstats.expanded;
      res.max_beam = mstats.max_beam;
    } else {
      res = search(pb, opt, verbose, &seed);
    }
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    // Trajectory CSV in the format of `cncore run --trajectory` (columns the loader reads).
    std::FILE* f = std::fopen(out.c_str(), "w");
    if (!f) throw std::runtime_error(out + ": cannot write");
    bool rotary = false;
    for (const auto& sg : path.segments)
      for (std::size_t i = cncore::kA; i < kMaxAxes; ++i) rotary |= sg.start[i] != sg.end[i];
    std::fprintf(f, rotary ? "t,line,x,y,z,a,b,c\n" : "t,line,x,y,z\n");
    std::size_t seg = 0;
    for (std::size_t k = 0; k < res.s.size(); ++k) {
      seg = pb.seg_of(res.s[k], seg);
      // A sample on a joint belongs to the segment it arrived by (line of that block).
      std::size_t line_seg = seg;
      if (k > 0 && seg > 0 && res.s[k] == path.segments[seg].s0_mm) line_seg = seg - 1;
      const AxisVec p = pb.point(res.s[k], seg);
      std::fprintf(f, "%.6f,%u,%.9f,%.9f,%.9f", static_cast<double>(k) * lim.period_s,
                   pb.line(line_seg), p[0], p[1], p[2]);
      if (rotary) std::fprintf(f, ",%.9f,%.9f,%.9f", p[3], p[4], p[5]);
      std::fprintf(f, "\n");
    }
    std::fclose(f);

    const double bound = cncore::bound::optimal_time_s(blocks, lim);
    const std::size_t cycles = res.s.size() - 1;
    const double t = static_cast<double>(cycles) * lim.period_s;
    const double per_cycle = 1.0 / static_cast<double>(std::max<std::size_t>(cycles, 1));
    std::printf(
        "cycles=%zu time_s=%.3f bound_s=%.4f ratio=%.4f segments=%zu length_mm=%.3f "
        "per_bin=%zu bins_per_a=%g grid=%zu factor=%g max_beam=%zu expanded=%zu search_s=%.1f "
        "states_per_cycle=%.1f us_per_cycle=%.1f\n",
        cycles, t, bound, bound > 0 ? t / bound : 0.0, pb.segments(), pb.length(), opt.per_bin,
        opt.bins_per_a, opt.grid, opt.factor, res.max_beam, res.expanded, secs,
        static_cast<double>(res.expanded) * per_cycle, 1e6 * secs * per_cycle);
    if (module)
      std::printf("module: forced=%zu recoveries=%zu uncertified=%zu longest_brake=%zu\n",
                  mstats.forced, mstats.recoveries, mstats.uncertified, mstats.longest_brake);
    else if (opt.certify || opt.max_lag > 0 || opt.recover)
      std::printf(
          "committed=%zu certified=%zu longest_brake=%zu longest_lag=%zu first_uncertified=%zu "
          "forced_drops=%zu recoveries=%zu\n",
          res.committed, res.certified, res.longest_brake, res.longest_lag, res.first_uncertified,
          res.forced, res.recoveries);
    return 0;
  } catch (const cncore::InputError& e) {
    std::fprintf(stderr, "%s\n", e.formatted().c_str());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cncore-sref: %s\n", e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (...) {  // (CLI11's setup; everything after parsing reports its own errors)
    std::fprintf(stderr, "cncore-sref: unexpected error\n");
    return 1;
  }
}
