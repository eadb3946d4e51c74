// The acc/dec type "search": the tool follows the samples of a search ahead of it
// (motion/sample_search.hpp) instead of a speed profile over the caps. It plans each cycle's
// sample under the checker's own rules and places the samples where a staircase of
// micro-corners cancels within a pair of steps, which the acceleration type's zones cannot.
//
// Not real-time: step() runs the search until a sample is committed (~20–40 µs a cycle on
// average, up to the commit lag's L cycles of search after an override change); a controller
// would run it in its planning thread. Without a jerk stage and a post filter only. See
// docs/lookahead.md, "The search type".
#pragma once

#include <cstddef>
#include <cstdint>

#include "motion/accdec.hpp"
#include "motion/sample_search.hpp"
#include "planner/segment.hpp"

namespace cncore::motion {

class SearchAccDec final : public AccDec {
 public:
  // window_segments: at least the kernel's buffer capacity (the search keeps its own copies).
  SearchAccDec(const planner::Limits& lim, std::size_t window_segments);

  void on_segment(std::uint64_t index, const planner::Segment& s) override;
  void on_joint(std::uint64_t /*index_a*/, const planner::Segment& /*a*/,
                const planner::Segment& /*b*/) override {}
  void on_barrier() override { search_.mark_stop(); }
  void on_end_of_program() override { search_.end_of_program(); }
  // The search keeps the segments it needs: the buffer may drop every item behind the tool.
  bool holds(std::uint64_t /*index*/) const override { return false; }
  void on_retire(std::uint64_t /*index*/) override {}

  void step(const CycleInput& in) override;
  // A stop requested at a block end: beyond the greedy brake's rest (SampleSearch).
  double stop_reach_mm() override { return search_.brake_rest_mm(); }
  void on_stop_request(double stop_mm) override { search_.stop_at(stop_mm); }
  void on_stop_release() override { search_.lift_stop(); }

  double tool_mm() const override { return tool_mm_; }
  double tool_speed_pc() const override { return step_pc_; }
  double commanded_mm() const override { return tool_mm_; }
  bool at_rest() const override { return step_pc_ == 0 && search_.ready() == 0; }

 private:
  SampleSearch search_;
  std::size_t ramp_cycles_ = 0;  // an override decrease's allowance (the checker's ramp)
  double ratio_ = 1;             // the override the search plans with
  bool hold_ = false;
  bool started_ = false;  // a segment has arrived
  bool stepped_ = false;  // step() has run
  double tool_mm_ = 0, step_pc_ = 0;
};

}  // namespace cncore::motion
