// The look-ahead upper limit Ul (spec 01, stage 4) over the end points ("cap points") of the
// execution-data buffer, in amortised O(log n) per block and O(1) per cycle, whatever the
// segment length. Path positions are along the commanded (pre-filter) path, in mm; speeds in
// mm per interpolation cycle.
//
// Which distance, and for how long (the argument that spec 01 asks for).
//   The acc/dec filter is a FIR filter of span M cycles (M = T for one moving average of T
//   cycles, T + T2 − 1 for two stages): the tool position s_f[t] is a weighted mean, weights ≥ 0
//   summing to 1, of the commanded positions s[t−M+1 … t], with mean delay (M − 1)/2.
//   An end point at position c with cap V gets the range start r = c − V·M and the constraint
//       U ≤ max(V, r − s)        while the tool has not passed c (s_f < c),
//   i.e. U ≤ r − s while s < w = r − V ("approaching": the step may not jump past r), and
//   U ≤ V once s ≥ w ("in range").
//   Claim: when s_f[t] ≥ c, every step U[t−M+1 … t] in the filter window is ≤ V, so the tool
//   speed (a mean of those steps) is ≤ V when it reaches c.
//   Proof: a step larger than V is only allowed from s < w, and it ends at ≤ r. Suppose
//   s[t−M] < r (some step of the window could be > V). Then s[t−M+k] ≤ r + (k−1)·V for
//   k = 1 … M, and the weighted mean is ≤ r + V·(M−1)/2 < r + V·M = c: the tool has not reached
//   c. So when it has, s[t−M] ≥ r and every later step was taken in range (≤ V).
//   Why the cap must last until the *filtered* position has passed c: releasing it when the
//   *commanded* position passes c lets the next block's fast steps into the window while the
//   tool is still before c (the window then mixes slow and fast steps and the tool crosses c
//   faster than V).
//   With a post-interpolation filter of Tp cycles the span is M + Tp and the cap lasts until
//   the tool has passed c + V·Tp: the tool's speed is then ≤ V for Tp cycles on both sides of
//   c, which bounds the corner rounding (see docs/lookahead.md).
//
// Feed caps (a change of programmed feed at a joint, cap min(F_a, F_b) scaled by the runtime
// override OR) use the same form with their range computed at the highest override ORmax, so
// no key depends on the runtime override: in range the cap is F·OR (the minimum over in-range
// feed caps is OR·min F, so the order never changes when OR does). Cost: the range of a feed
// cap starts up to (ORmax − OR)·F·M earlier than needed.
//
// Structure: four tournament trees over point slots (two per buffer slot: geometric cap and
// feed cap): W holds w of approaching points (the smallest w tells which point enters its
// range next), R holds r of approaching points (min r − s is the approaching limit), G holds
// V of in-range geometric caps and F holds F of in-range feed caps; Crel holds the release
// position of in-range points (the smallest tells which point the tool passes next). Each
// point moves approaching → in range → released exactly once: O(log n) per point.
// Ul = min(min R − s, min G, OR·min F).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "planner/huge_pages.hpp"
#include "planner/min_tree.hpp"

namespace cncore::planner {

struct CapPoint {
  double c_mm = 0;         // path position of the end point
  double value = 0;        // cap V (mm/cycle); for a feed cap the feed at 100 % override
  bool feed = false;       // feed cap: scaled by the runtime override
  double span_cycles = 0;  // M (+ Tp with the post filter)
  double release_mm = 0;   // the cap holds until the tool position reaches this (≥ c)
};

// Range start r and entry w of a point for the highest override or_max (1 for geometric caps).
struct Range {
  double r = 0, w = 0;
};
inline Range range_of(const CapPoint& p, double or_max) {
  const double v = p.feed ? p.value * or_max : p.value;
  const double r = p.c_mm - v * p.span_cycles;
  return {r, r - v};
}

class Lookahead {
 public:
  // slots: number of point slots (2 per buffer slot). or_max: highest override ratio.
  Lookahead(std::size_t slots, double or_max);

  // Adds the point of a slot. s_cmd: the current commanded position. If the commanded position
  // is already past the point's range start (the point arrived late, while the buffer's tail
  // was treated as a stop), the cap is lowered to (c − s_cmd)/span so that the argument above
  // still holds. Returns the cap actually stored.
  double insert(std::size_t slot, CapPoint p, double s_cmd);
  // Removes a slot's point whatever its state.
  void clear(std::size_t slot);
  bool live(std::size_t slot) const { return state_[slot] != State::kEmpty; }
  const CapPoint& point(std::size_t slot) const { return points_[slot]; }

  // One cycle: moves points that entered their range or were passed by the tool, and returns
  // Ul (mm/cycle; +infinity when no point limits). s_cmd never decreases, nor does s_tool.
  double limit(double s_cmd, double s_tool, double or_ratio);

  // The same limit by a plain walk over every live point (O(n); for tests).
  double reference_limit(double s_cmd, double s_tool, double or_ratio) const;

 private:
  enum class State : std::uint8_t { kEmpty, kApproaching, kInRange };
  void enter_range(std::size_t slot);

  double or_max_;
  std::vector<CapPoint, HugePageAllocator<CapPoint>> points_;
  std::vector<State, HugePageAllocator<State>> state_;
  MinTree w_, r_, geo_, feed_, release_;
};

}  // namespace cncore::planner
