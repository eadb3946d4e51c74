// The seed's acc/dec type: look-ahead upper limit → limiter → moving average of T cycles
// (optionally a second stage of T2 cycles for a jerk limit). Also runs the seed's conventional
// method (Mode::kStop): the input is blocked for the first cycles of every block, so the tool
// stops at every block end.
#pragma once

#include <cstdint>
#include <vector>

#include "motion/accdec.hpp"
#include "motion/kernel.hpp"
#include "planner/buffer.hpp"
#include "planner/lookahead.hpp"

namespace cncore::motion {

// Moving average over `len` cycles as a running sum in a fixed ring: O(1) per cycle.
class MovingAverage {
 public:
  explicit MovingAverage(std::uint32_t len)
      : ring_(len > 0 ? len : 1, 0.0), len_(static_cast<double>(ring_.size())) {}
  double push(double u) {
    const double old = ring_[pos_];
    ring_[pos_] = u;
    pos_ = pos_ + 1 == ring_.size() ? 0 : pos_ + 1;
    sum_ += u - old;
    nonzero_ += (u != 0 ? 1 : 0);
    nonzero_ -= (old != 0 ? 1 : 0);
    if (nonzero_ == 0) sum_ = 0;  // exact zero at rest (no rounding residue)
    // sum / 1 is sum exactly: a one-cycle stage (no jerk stage, T2 = 1) skips the division,
    // which sits on the chain from the commanded step to the sample in every cycle.
    const double out = single_ ? sum_ : sum_ / len_;
    return out > 0 ? out : 0;
  }
  bool at_rest() const { return nonzero_ == 0; }

 private:
  std::vector<double> ring_;
  double len_;                       // ring size as a double (no conversion per cycle)
  bool single_ = ring_.size() == 1;  // one cycle: the average is the sum itself
  std::size_t pos_ = 0;
  double sum_ = 0;
  std::uint32_t nonzero_ = 0;
};

class MovingAverageAccDec final : public AccDec {
 public:
  MovingAverageAccDec(const planner::SegmentBuffer& buffer, const planner::Limits& limits,
                      Mode mode, double or_max, bool check_reference_walk);

  void on_joint(std::uint64_t index_a, const planner::Segment& a,
                const planner::Segment& b) override;
  // The same with the joint's passing speed already computed by the caller:
  // vg == planner::joint_speed_pc(a, b, limits) (the kernel needs it first to decide on a stop).
  void on_joint(std::uint64_t index_a, const planner::Segment& a, const planner::Segment& b,
                double vg);
  bool holds(std::uint64_t index) const override;
  void on_retire(std::uint64_t index) override;
  void step(const CycleInput& in) override;
  // The filter brakes: the commanded position may stop at once, as it does at the buffer's end
  // when the next block is late (a step that drops to 0 leaves the filter at ≤ Vb/T per cycle).
  double stop_reach_mm() override { return cmd_mm_; }

  double tool_mm() const override { return tool_mm_; }
  double tool_speed_pc() const override { return tool_step_; }
  double commanded_mm() const override { return cmd_mm_; }
  bool at_rest() const override { return stage1_.at_rest() && stage2_.at_rest(); }

  std::uint64_t reference_mismatches() const { return mismatches_; }
  double last_limit_pc() const { return last_ul_; }

 private:
  const planner::Segment* advance_commanded();
  double shape_last_step(double u, double left) const;

  const planner::SegmentBuffer& buf_;
  planner::Limits lim_;
  Mode mode_;
  bool check_;
  planner::Lookahead la_;
  MovingAverage stage1_, stage2_;
  std::uint64_t cmd_idx_ = 0;           // buffer item under the commanded position
  std::uint64_t cmd_skip_ = 1;          // items it last moved by (the seek hint)
  std::uint64_t entered_ = UINT64_MAX;  // stop mode: the block whose start wait was done
  std::uint32_t wait_ = 0;              // stop mode: cycles the input is still blocked
  double cmd_mm_ = 0, tool_mm_ = 0, prev_tool_mm_ = 0, tool_step_ = 0;
  double last_ul_ = 0;
  // A stop is approached with a last commanded step between last_step_ and 2·last_step_ =
  // Amax·τ²·T/2, so the tool's last step before it stands still is ≤ Amax·τ²/2: it arrives at
  // ≤ Amax·τ/2, at most the passing speed Amax·τ/(2 sin θ/2) of any corner (stop mode stops at
  // joints that are corners), and its second-to-last sample is visibly short of the stop.
  double last_step_ = 0;
  std::uint64_t mismatches_ = 0;
  // The previous joint (a → b), for two corners within one cycle.
  struct PrevJoint {
    bool valid = false;
    std::uint64_t index_a = 0, index_b = 0;
    AxisVec end_dir;   // direction at the end of a
    AxisVec end_dir2;  // direction at the end of the segment before a
    double vg = 0;
    double vg2 = 0;        // cap of the joint before that one
    bool short_a = false;  // a is shorter than the passing speed (one cycle can skip it)
  } prev_;
};

}  // namespace cncore::motion
