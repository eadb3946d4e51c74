// How much the tangent varies within one cycle's travel before a joint, for the joint's passing
// speed on chains of segments shorter than a step (a polyline fillet from CAM: 1 mm radius in
// 10 µm chords at F 6 000 went round at 100 mm/s, 4 078 mm/s² normal on a 2 000 limit).
//
// Two consecutive chords d1 = p(s) − p(s − u1), d2 = p(s + u2) − p(s) of a path with unit
// tangent e(σ): with m = min(u1, u2),
//     d2 − d1 = ∫₀^m (e(x) − e(x − m)) dx (x from s to s + m) + the rest of the longer step,
// whose length is |u2 − u1|. Each e(x) − e(x − m) compares two tangents within m ≤ V of each
// other, so per axis it is at most the spread max − min of e_i over the window (j − V, j] of
// the last joint j in [x − m, x], and both steps around that joint are ≤ its cap V (the joint
// cap's range [j − V, j + V)). So if at every joint
//     V·spread_i(j − V, j] ≤ a_i   and   V·|spread| ≤ Amax·τ²,
// the turn alone keeps the limits (the single-corner rule Vg·|S − E| ≤ Amax·τ² is the case of
// one corner in the window, spread_i = |S_i − E_i|), and the speed change beside it,
// |u2 − u1|·|e_i|, is the acc/dec type's (its joint zones take the spread too). Spread, not
// the sum of the turns: on a straight line cut into pieces with rounded coordinates the turns
// add up while the tangent only wobbles (stress_test ×100: 10× slower with the sum).
//
// The spread over the longest window (the largest step) is kept by monotone queues of the
// items' tangent ranges (O(1) per block amortised); where it binds, a walk back over the items
// finds the exact window.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/geometry.hpp"
#include "planner/buffer.hpp"
#include "planner/segment.hpp"

namespace cncore::planner {

// The tangent's range over a window: per axis its spread (max − min of the unit tangent's
// component) and largest magnitude, and the spread as a whole (|spread|).
struct Turn {
  std::array<double, kMaxAxes> axis{};
  std::array<double, kMaxAxes> top{};
  double total = 0;
};

class TurnWindow {
 public:
  // capacity: the buffer's (items in a window never exceed it); window_mm: the largest step.
  TurnWindow(std::size_t capacity, double window_mm);

  // Item `s` (a motion segment just pushed) continues the path across a joint (joint) or
  // starts after a stop or as the first one.
  void on_segment(const Segment& s, bool joint);

  // The largest passing speed ≤ vg_pc at the joint between items index_a and index_b (b just
  // pushed) whose window meets the limits with the turn alone; `turn` receives the range over
  // that window. The speed found is kept as the joint's cap: a later joint's window spans a
  // pair of steps only where it is below every cap inside.
  double chain_speed_pc(const SegmentBuffer& buf, std::uint64_t index_a, std::uint64_t index_b,
                        double vg_pc, const Limits& limits, Turn& turn);

 private:
  struct Entry {
    // NOLINTNEXTLINE(modernize-use-equals-default): = default would be zeroed by resize()
    Entry() {}  // (left uninitialised: see the constructor)
    Entry(double e, double v) : end_mm(e), value(v) {}
    double end_mm, value;
  };
  // A fixed ring used as a double-ended queue (monotone: the front is the window's extreme).
  struct Queue {
    std::vector<Entry> ring;
    std::size_t head = 0, size = 0;
    const Entry& front() const { return ring[head]; }
    // (Ring indices by compare, not `%`: a division per call, a dozen calls per block.)
    std::size_t at(std::size_t k) const {
      const std::size_t i = head + k;
      return i >= ring.size() ? i - ring.size() : i;
    }
    const Entry& back() const { return ring[at(size - 1)]; }
    void pop_front() {
      head = head + 1 == ring.size() ? 0 : head + 1;
      --size;
    }
    void pop_back() { --size; }
    void push_back(const Entry& e) { ring[at(size++)] = e; }
  };
  // Consecutive items whose tangents stay within kMergeSpread of each other (a line cut into
  // pieces, with rounded coordinates) form one run: the walk back steps over runs, not items.
  struct Run {
    // NOLINTNEXTLINE(modernize-use-equals-default): = default would be zeroed by resize()
    Run() {}  // (left uninitialised: see the constructor)
    Run(double s0, double end, const std::array<double, kMaxAxes>& l,
        const std::array<double, kMaxAxes>& h, bool is_line)
        : s0_mm(s0),
          end_mm(end),
          lo(l),
          hi(h),
          cap_inside(std::numeric_limits<double>::infinity()),
          cap_end(std::numeric_limits<double>::infinity()),
          line(is_line) {}
    double s0_mm, end_mm;
    std::array<double, kMaxAxes> lo, hi;
    double cap_inside;  // the lowest cap of the joints between its items
    double cap_end;     // the cap of the joint at its end
    bool line;          // of lines only (an arc is a run of its own)
  };
  double find_speed(const SegmentBuffer& buf, std::uint64_t index_a, std::uint64_t index_b,
                    double vg_pc, const Limits& limits, Turn& turn) const;
  void prune(double from_mm);
  void clear();

  double window_mm_;
  std::array<Queue, kMaxAxes> hi_, lo_;  // per axis: decreasing maxima, increasing minima
  bool saturated_ = false;               // more items in the window than the queues hold: no bound
  double chain_s0_mm_ = 0;               // where the path continues without a stop from
  std::vector<Run> runs_;                // ring, newest last
  std::size_t run_head_ = 0, run_count_ = 0;
  bool joint_inside_ = false;  // the last joint lies inside the newest run
  std::size_t run_slot(std::size_t back) const {
    const std::size_t i = run_head_ + run_count_ - 1 - back;
    return i >= runs_.size() ? i - runs_.size() : i;
  }
  Run& run(std::size_t back) { return runs_[run_slot(back)]; }
  const Run& run(std::size_t back) const { return runs_[run_slot(back)]; }
};

// The range of the unit tangent's components over segment s (lines: one direction; arcs: the
// end directions widened by how far a sinusoid of the axis' share bulges between them).
void tangent_range(const Segment& s, std::array<double, kMaxAxes>& lo,
                   std::array<double, kMaxAxes>& hi);

}  // namespace cncore::planner
