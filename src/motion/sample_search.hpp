// A sample search ahead of the tool (design in docs/lookahead.md, "The search type"). The
// look-ahead's zones must hold for every placement of the samples; on a staircase of alternating
// micro-corners (a circle of rounded short chords) that costs ~15 % against the time-optimal bound.
// This stage instead searches over where the samples land: a beam of states (s_prev, s), one cycle
// at a time, under the trajectory checker's own rules, run ahead of the tool. The cycle only reads
// committed samples.
//
//   push(segment) ──▶ window ──▶ advance(): beam at the front cycle F
//                                   │ lineages coalesce, or a commit is forced after L cycles
//                                   ▼
//   pop() ◀── committed samples (a fixed ring); each committed state has a greedy brake to rest
//
// Safety: a state is committed only if the greedy brake (the smallest feasible step every
// cycle) brings it to rest. If the beam dies (no state can continue), the tool takes that brake
// from the newest committed state and the search starts again from rest: the output always
// keeps the rules. Every buffer is sized at construction: advance() and pop() do not allocate.
//
// Rules of a step from s to s2 (every limit scaled by limit_factor, in mm per cycle or cycle²):
//   - |d2 − d1| ≤ a on the path (tangential), d ≥ 0, and the motion starts at rest;
//   - the step of the first sample at or past a joint ≤ the joint's Vg (the checker's: both
//     shapes' limits and Amax·τ/(2 sin(θ/2)));
//   - every step ≤ the speed limit (F × the override, the feed or rapid rate, √(R·Amax) on an
//     arc) of each segment it touches;
//   - normal: √(l1·l2)·|d̂2 − d̂1| ≤ a over consecutive XYZ chords; per-axis speed and
//     acceleration by finite differences; the resultant |Δ²P| ≤ a when the limits bound it;
//   - stops (exact stop, dwell, waiting event, the end): a sample lands exactly on the stop point
//     with a step ≤ a, none passes it, and the plan waits there for resume();
//   - the window's end while more may come: a wall no sample reaches.
// The override (restart()), feed hold (brake_now()), stops and a stop requested at a segment
// end while the tool moves (stop_at()) are handled here; the acc/dec type "search"
// (search_accdec.hpp) wires them to the kernel. Not done: the filters (jerk stage, post
// filter), rotary-only segments, and a hand-back to the acceleration type at speed.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/block.hpp"
#include "core/geometry.hpp"
#include "planner/segment.hpp"

namespace cncore::motion {

struct SampleSearchOptions {
  std::size_t window_segments = 8192;  // segments held ahead of the committed samples
  std::size_t per_bin = 1;             // K: states kept per speed bin (and class of the guide)
  double bins_per_a = 2;               // B: speed bins per a (bin width a/B)
  std::size_t grid = 17;               // G: uniform candidate steps in [d − a, d + a]
  std::size_t joints_per_step = 32;    // joint candidates per expansion (more are not tried)
  std::size_t max_lag_cycles = 128;    // L: commits lag the front by at most this (+ 8)
  std::size_t output_cycles = 1024;    // committed samples waiting for pop()
  double limit_factor = 0.999;         // every limit scaled by this (the checker's margin kept)
  int bisect = 14;                     // steps to the normal / per-axis rules' boundary
  std::size_t guide_joints = 16;       // joints ahead checked by the backward guide
};

struct SampleSearchStats {
  std::size_t cycles = 0;       // front cycles searched
  std::size_t max_beam = 0;     // most live states in one cycle
  std::size_t expanded = 0;     // states expanded (beam sizes summed)
  std::size_t forced = 0;       // forced commits (lag above L)
  std::size_t recoveries = 0;   // deaths met by the brake to rest
  std::size_t uncertified = 0;  // coalesced states whose brake failed (met like a death)
  std::size_t longest_brake = 0;
  std::size_t restarts = 0;  // restart() calls (override changes)
};

class SampleSearch {
 public:
  SampleSearch(const planner::Limits& limits, const SampleSearchOptions& options);

  // Room for another segment in the window.
  bool wants_segment() const;
  // Appends a motion segment with XYZ length > 0; its s0_mm must continue the previous one's
  // end. stop_after: the tool must stop at its end (exact stop). Returns false (and keeps
  // nothing) when the segment is not supported (see the file comment) or the window is full.
  bool push(const planner::Segment& segment, bool stop_after);
  // Appends an interpreted block: a motion block becomes a segment (zero-length ones are
  // dropped), an exact stop (G9, G61.1) or an event that waits (M0, M6 …) stops the tool, other
  // events are ignored. False for what is not supported (dwells, rotary-only moves) or a full
  // window.
  bool push(const Block& block);
  // No more segments: the last one ends in a stop.
  void end_of_program();
  // The tool must stop at the end of the last segment pushed (an exact stop, a dwell, an event
  // that waits). The search ends its plan there and waits for resume().
  void mark_stop();
  // At rest on a stop (at_stop()): plan on from there.
  void resume();
  bool at_stop() const { return at_stop_ || stop_at_start_; }

  // A stop requested at a segment end while the tool moves (the kernel's
  // request_stop_at_block_end). Bounded by the configuration: one brake of at most the output
  // reserve's cycles, or one pass over the stops ahead.
  // Where the greedy brake from the newest popped sample (the tool's) comes to rest.
  double brake_rest_mm();
  // The segment ending at s_mm (ahead of the tool, before every stop ahead but those at the
  // tool) ends in a stop: what was planned after the newest popped sample is planned again.
  // False when no segment ends there or it is a stop already.
  bool stop_at(double s_mm);
  // The stop of stop_at() is lifted: where the tool has not reached it, the plan goes on past it.
  void lift_stop();

  // From the newest popped sample, plan again with the feed override `ratio` (1 = 100 %): the
  // samples committed and not popped are dropped. After a decrease the old override stands for
  // `ramp_cycles` (the checker's allowance), by which time the speed is under the new one.
  void restart(double ratio, std::size_t ramp_cycles);
  // A cycle passed without a sample (the tool rests on a stop, at the end or in a feed hold):
  // the cycle count the override's ramp is timed by moves on.
  void idle();
  // Feed hold: drop what is planned and brake to rest from the newest popped sample (the
  // greedy brake), then plan on from rest.
  void brake_now();

  // Searches one more cycle at the front (planning time, not the cycle). Returns false when it
  // cannot: it waits for segments (the front stays a braking distance before the window's end
  // unless near_window_end: then its states brake for it, as for a stop they never reach), the
  // output ring is full, a stop or the end point is reached.
  bool advance(bool near_window_end = false);

  // The next committed sample (the cycle's side: O(1), no allocation). False when none waits.
  bool pop(AxisVec& position, std::uint32_t& line, double& s_mm);
  std::size_t ready() const { return out_count_; }
  // Every sample up to the end point has been committed.
  bool finished() const { return finished_; }
  // A recovery's brake failed (a bug: the state was certified by that very brake).
  bool failed() const { return failed_; }
  const SampleSearchStats& stats() const { return stats_; }

 private:
  struct Node {
    double sp = 0, s = 0;   // previous and current sample (path mm)
    std::uint64_t seg = 0;  // segment holding s (global index)
    std::int32_t parent = -1;
  };
  struct Hist {
    double s;
    std::int32_t parent;
  };
  struct Cand {
    double s2;
    std::uint64_t seg2;
    int ok;  // 2 feasible, 1 feasible without the guide's sharp term, −1 not, 0 a static rule fails
  };
  struct Seg {
    planner::Segment geo;
    double feed = 0;       // its feed step at 100 % (mm/cycle, × limit_factor; ∞: none)
    double shape = 0;      // the shape's limit (feed or rapid rate, √(R·Amax)), × limit_factor
    double joint_cap = 0;  // largest step that crosses its end
    double eff = 0;        // joint cap for the backward guide (≤ joint_cap)
    bool stop = false;     // its end is a stop (exact stop, the end, or the window's end)
    bool hard_stop = false;  // an exact stop (stays one when the next segment arrives)
    double turn_cos = 1;     // cos of the turn at its end (1 until the next segment arrives)
  };
  struct Out {
    AxisVec p;
    std::uint32_t line;
    double s;
    // A committed state whose brake to rest is still to be found (when it is popped): its
    // previous sample, segment and cycle.
    bool pending = false;
    double sp = 0;
    std::uint64_t seg = 0, cycle = 0;
  };

  const Seg& seg(std::uint64_t i) const { return segs_[i & seg_mask_]; }
  Seg& seg(std::uint64_t i) { return segs_[i & seg_mask_]; }
  double joint_s(std::uint64_t i) const { return seg(i).geo.end_mm(); }
  std::uint64_t seg_of(double s, std::uint64_t hint) const;
  AxisVec point(double s, std::uint64_t segment) const;
  double brake_distance(double d, double c) const;
  double brake_limit(double c, double room) const;
  // Largest step inside segment g at override ratio r.
  static double cap(const Seg& g, double r) { return std::min(g.feed * r, g.shape); }
  double ratio_at(std::uint64_t cycle) const;
  double terminal() const;
  void reached_terminal();
  void restart_at_rest();
  double shape_cap(const planner::Segment& s) const;
  // Segment j is followed by segment j + 1 without a stop: its joint's cap and turn.
  void join(std::uint64_t j);
  double corner_cap(const planner::Segment& a, const planner::Segment& b) const;
  double eff_of(std::uint64_t j) const;
  void update_eff(std::uint64_t last);
  void refresh_eff(double upto_mm);
  int can_brake(double s, double d, std::uint64_t segment) const;
  bool step_ok(double s, double d_in, std::uint64_t segment, double s2, std::uint64_t& seg2) const;
  // What the dynamic rules need of a node's last step, computed once per expansion.
  struct Prev {
    AxisVec p1, c1;  // the sample and the step into it
    Vec3 u1;         // that step's unit direction (zero if it is empty)
    double l1 = 0;   // its length
  };
  static Prev prev_of(const AxisVec& p0, const AxisVec& p1);
  bool dynamics_ok(const Prev& q, const AxisVec& p2) const;
  std::size_t landings(const Node& n, double& lo, double& hi);
  Cand boundary(const Node& n, const Prev& q, const Cand& good, const Cand& bad, int level,
                bool guided) const;
  void expand(const Node& n, std::size_t& count, bool guided = true);
  bool smallest_step(const Node& n, Cand& out);
  std::size_t brake_to_rest(Node n, std::uint64_t cycle, bool record);
  void offer(const Node& child, std::size_t cls);
  void commit_lineage(std::uint64_t cycle, std::size_t i);
  void commit_pending(const Node& n);
  void recover();
  void retire();
  void force_commit();
  void find_coalescence();
  std::size_t ancestor(std::size_t i, std::uint64_t cycle) const;
  void emit(const Node& n, std::uint64_t cycle, bool pending = false);
  void from_tool();
  Hist& hist(std::uint64_t cycle, std::size_t i) {
    return hist_[(cycle % hist_rows_) * beam_cap_ + i];
  }
  const Hist& hist(std::uint64_t cycle, std::size_t i) const {
    return hist_[(cycle % hist_rows_) * beam_cap_ + i];
  }

  planner::Limits lim_;
  SampleSearchOptions opt_;
  double a_ = 0, normal_ = 0, resultant_ = 0;
  std::array<double, kMaxAxes> axis_a_{}, axis_v_{};
  double max_step_ = 0, reach_mm_ = 0, bin_w_ = 0;
  double eff_horizon_mm_ = 0;  // a joint's effective cap depends on the caps this far ahead
  std::size_t nbins_ = 0, beam_cap_ = 0, hist_rows_ = 0, cand_cap_ = 0;

  std::vector<Seg> segs_;  // a ring of a power of two slots
  std::uint64_t seg_mask_ = 0;
  std::uint64_t seg_base_ = 0, seg_end_ = 0;  // [base, end) held
  // Effective caps are current (this override's) for segments [seg_base_, eff_fresh_); after
  // an override change the ones beyond are made current as the front comes near them.
  std::uint64_t eff_fresh_ = 0;
  bool program_ended_ = false;

  std::vector<Node> beam_, bins_;                    // live states; per bin the K farthest children
  std::vector<std::size_t> bin_n_;                   // children kept per bin
  std::vector<double> cand_s_;                       // one expansion's candidate landings
  std::vector<Cand> cands_;                          // … judged, then the feasible ones
  std::vector<Hist> hist_;                           // ring of rows: hist_rows_ × beam_cap_
  std::vector<std::uint32_t> mark_, idx_a_, idx_b_;  // coalescence scratch
  std::uint32_t stamp_ = 0;
  std::vector<Node> trace_;  // a lineage, front to commit point

  std::uint64_t front_ = 0;      // cycle of the beam
  std::uint64_t committed_ = 0;  // newest committed cycle
  Node last_commit_{};           // its state (sp, s, seg)
  std::vector<Out> out_;
  std::size_t out_head_ = 0, out_count_ = 0;
  std::size_t out_reserve_ = 0;  // free output kept for a forced commit or a recovery's brake
  bool finished_ = false, failed_ = false, at_stop_ = false;
  bool stop_at_start_ = false;         // a stop (dwell, event) came before the first segment
  std::vector<std::uint64_t> hard_q_;  // segments ending in a stop, ahead of the tool
  std::size_t hard_head_ = 0, hard_n_ = 0;
  static constexpr std::uint64_t kNoSegment = ~std::uint64_t{0};
  std::uint64_t asked_ = kNoSegment;  // the segment stop_at() made end in a stop
  double or_ = 1;                     // planned override
  // Overrides replaced by a decrease, each standing until its cycle (the checker's ramp).
  struct Allowance {
    double ratio;
    std::uint64_t until;
  };
  std::array<Allowance, 16> allow_{};
  std::size_t allow_n_ = 0;
  double ratio_ = 1;               // override of the steps being judged (ratio_at their cycle)
  std::uint64_t guide_cycle_ = 0;  // cycle of the states the guide judges
  double popped_s_ = 0, popped_sp_ = 0;  // the newest popped sample and the one before
  std::uint64_t popped_n_ = 0;
  SampleSearchStats stats_;
};

}  // namespace cncore::motion
