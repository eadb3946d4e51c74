#include "motion/moving_average.hpp"

#include <algorithm>
#include <limits>

namespace cncore::motion {

using planner::CapPoint;
using planner::ItemKind;
using planner::Segment;

constexpr double kNoCap = std::numeric_limits<double>::infinity();

MovingAverageAccDec::MovingAverageAccDec(const planner::SegmentBuffer& buffer,
                                         const planner::Limits& limits, Mode mode, double or_max,
                                         bool check_reference_walk)
    : buf_(buffer),
      lim_(limits),
      mode_(mode),
      check_(check_reference_walk),
      la_(2 * buffer.capacity(), or_max),
      stage1_(limits.t_cycles),
      stage2_(limits.t2_cycles),
      last_step_(0.25 * limits.amax_pc2 * limits.t_cycles) {}

void MovingAverageAccDec::on_joint(std::uint64_t index_a, const Segment& a, const Segment& b) {
  if (mode_ != Mode::kLookahead) return;
  on_joint(index_a, a, b, planner::joint_speed_pc(a, b, lim_));
}

void MovingAverageAccDec::on_joint(std::uint64_t index_a, const Segment& a, const Segment& b,
                                   double vg) {
  if (mode_ != Mode::kLookahead) return;
  const std::size_t slot = buf_.slot(index_a);
  const double post = lim_.post_filter() ? lim_.post_cycles : 0.0;
  const double span = lim_.span_cycles() + post;
  const double c = a.end_mm();
  // vg: the geometric cap Vg (corner, arc, axis limits, contour tolerance), OR-independent.
  // A segment shorter than one cycle's travel lets one cycle turn two corners at once (the
  // direction changes from the end of the segment before it to the start of the one after).
  // Either the speed stays ≤ its length (no cycle skips it) or the combined turn is allowed.
  if (prev_.valid && prev_.index_b == index_a && a.length_mm < vg) {
    // After another short segment a cycle may cross three joints: the turn from the end of
    // the segment before that one counts too (longer chains of skipped segments: see docs).
    // Each combined turn is needed only if it allows less than the caps the tool already obeys
    // when it crosses those joints (a corner next to straight joints needs nothing more); 0.999
    // keeps rounding noise out.
    const double pair = planner::turn_speed_pc(prev_.end_dir, b.start_direction(), lim_);
    double both = pair < 0.999 * std::min(prev_.vg, vg) ? pair : kNoCap;
    if (prev_.short_a) {
      const double triple = planner::turn_speed_pc(prev_.end_dir2, b.start_direction(), lim_);
      if (triple < 0.999 * std::min({prev_.vg2, prev_.vg, vg})) both = std::min(both, triple);
    }
    if (both < kNoCap) {
      const double cap = std::max(a.length_mm, both);
      if (cap < vg) vg = cap;
      const std::size_t ps = buf_.slot(prev_.index_a);
      if (cap < prev_.vg && la_.live(2 * ps) && !la_.point(2 * ps).feed) {
        CapPoint p = la_.point(2 * ps);
        if (cap < p.value) {
          p.value = cap;
          p.release_mm = p.c_mm + cap * post;
          la_.insert(2 * ps, p, cmd_mm_);
        }
      }
    }
  }
  // A joint whose cap is not below the Vb of either side (same Vb, no corner to speak of)
  // limits nothing the limiter does not already: while the tool is in a block of a run of such
  // joints every commanded step is ≤ that common Vb, and the first joint where Vb or the
  // direction changes gets its own point. Leaving these out keeps fine straight or gently
  // curved paths (CAM) from paying tree updates for every segment.
  if (vg < std::max(a.vb_pc, b.vb_pc)) {
    vg = la_.insert(2 * slot, CapPoint{c, vg, false, span, c + vg * post}, cmd_mm_);
  }
  // prev_ ← {a → b}: field by field, in place (a whole-struct temporary of two AxisVecs costs a
  // store-forwarding stall on every block).
  const bool chained = prev_.valid && prev_.index_b == index_a;
  const AxisVec a_end = a.end_direction();
  prev_.end_dir2 = chained ? prev_.end_dir : a_end;
  prev_.vg2 = chained ? prev_.vg : kNoCap;
  prev_.valid = true;
  prev_.index_a = index_a;
  prev_.index_b = buf_.end_index() - 1;
  prev_.end_dir = a_end;
  prev_.vg = vg;
  prev_.short_a = a.length_mm < vg;
  // Feed cap: where the programmed feed changes, the lower of the two feeds holds from the
  // range start until the tool has passed the joint (so the tool is never faster than the
  // feed of the block it is in).
  if (a.feed_pc != b.feed_pc) {
    const double f = std::min(a.feed_pc, b.feed_pc);
    la_.insert(2 * slot + 1, CapPoint{c, f, true, static_cast<double>(lim_.span_cycles()), c},
               cmd_mm_);
  }
}

bool MovingAverageAccDec::holds(std::uint64_t index) const {
  const std::size_t slot = buf_.slot(index);
  return la_.live(2 * slot) || la_.live(2 * slot + 1);
}

void MovingAverageAccDec::on_retire(std::uint64_t index) {
  const std::size_t slot = buf_.slot(index);
  la_.clear(2 * slot);
  la_.clear(2 * slot + 1);
}

const Segment* MovingAverageAccDec::advance_commanded() {
  if (buf_.empty()) return nullptr;
  cmd_idx_ = std::max(cmd_idx_, buf_.begin_index());
  if (cmd_idx_ >= buf_.end_index()) return nullptr;
  // O(log k) for k items passed this cycle (tiny segments), not O(k); O(1) mostly, with the
  // last cycle's skip as the hint.
  const std::uint64_t from = cmd_idx_;
  cmd_idx_ = buf_.seek(from, cmd_mm_, UINT64_MAX, from + cmd_skip_);
  if (cmd_idx_ > from) cmd_skip_ = cmd_idx_ - from;
  const Segment& s = buf_[cmd_idx_];
  return s.kind == ItemKind::kMotion ? &s : nullptr;
}

// See last_step_: the step that reaches a stop `left` ahead is between last_step_ and
// 2·last_step_ (unless the whole way is shorter), and no step leaves less than last_step_.
double MovingAverageAccDec::shape_last_step(double u, double left) const {
  if (u <= 0) return 0;
  if (left <= 2 * last_step_) return std::min(u, left);
  if (u >= left || left - u < last_step_) return left - last_step_;
  return u;
}

void MovingAverageAccDec::step(const CycleInput& in) {
  const Segment* seg = advance_commanded();
  const double uc = (in.hold || seg == nullptr) ? 0.0 : seg->feed_pc * in.or_ratio;  // Uc = F·OR
  const double vb = seg != nullptr ? seg->vb_pc : 0.0;
  double u = 0;
  double next = cmd_mm_;
  if (mode_ == Mode::kLookahead) {
    // Caps are released one cycle after the tool passed their point (prev_tool_mm_): the cycle
    // that turns the corner and the first cycle of acceleration after it then fall in different
    // second differences, so a per-axis corner limit and the axis's ramp limit do not add up.
    const double ul = la_.limit(cmd_mm_, prev_tool_mm_, in.or_ratio);
    if (check_ && la_.reference_limit(cmd_mm_, prev_tool_mm_, in.or_ratio) != ul) ++mismatches_;
    last_ul_ = ul;
    const double to_stop = std::max(0.0, in.stop_mm - cmd_mm_);
    u = std::max(0.0, std::min({uc, vb, ul, to_stop}));  // the limiter: U = min(Uc, Ul, Vb)
    u = shape_last_step(u, to_stop);
    next = u >= to_stop ? in.stop_mm : cmd_mm_ + u;  // land exactly on a stop
  } else {
    // Conventional method: every block starts with `wait` cycles of blocked input, and the
    // commanded position stops at the block end, so the tool stops there.
    if (seg != nullptr && entered_ != cmd_idx_) {
      entered_ = cmd_idx_;
      wait_ = lim_.span_cycles() + (lim_.post_filter() ? lim_.post_cycles : 0);
    }
    if (wait_ > 0) {
      --wait_;
    } else if (seg != nullptr) {
      const double target = std::min(seg->end_mm(), in.stop_mm);
      const double left = std::max(0.0, target - cmd_mm_);
      u = shape_last_step(std::max(0.0, std::min({uc, vb, left})), left);
      next = u > 0 && u >= left ? target : cmd_mm_ + u;
    }
    last_ul_ = u;
  }
  cmd_mm_ = next;
  const double u1 = stage1_.push(u);
  const double u2 = stage2_.push(u1);
  tool_step_ = u2;
  prev_tool_mm_ = tool_mm_;
  tool_mm_ += u2;
  if (at_rest()) tool_mm_ = cmd_mm_;  // at rest the tool is exactly at the commanded position
}

}  // namespace cncore::motion
