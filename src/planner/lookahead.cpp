#include "planner/lookahead.hpp"

#include <algorithm>

namespace cncore::planner {

Lookahead::Lookahead(std::size_t slots, double or_max)
    : or_max_(or_max),
      points_(slots),
      state_(slots, State::kEmpty),
      w_(slots),
      r_(slots),
      geo_(slots),
      feed_(slots),
      release_(slots) {}

double Lookahead::insert(std::size_t slot, CapPoint p, double s_cmd) {
  clear(slot);
  // Late arrival: keep r = c − v·span ≥ s_cmd so that no earlier step can have jumped past r.
  const double scale = p.feed ? or_max_ : 1.0;
  if (p.span_cycles > 0 && p.c_mm - p.value * scale * p.span_cycles < s_cmd) {
    p.value = std::max(0.0, (p.c_mm - s_cmd) / (scale * p.span_cycles));
  }
  points_[slot] = p;
  const Range rg = range_of(p, or_max_);
  if (rg.w <= s_cmd) {
    enter_range(slot);
  } else {
    state_[slot] = State::kApproaching;
    w_.set(slot, rg.w);
    r_.set(slot, rg.r);
  }
  return p.value;
}

void Lookahead::enter_range(std::size_t slot) {
  const CapPoint& p = points_[slot];
  state_[slot] = State::kInRange;
  w_.set(slot, MinTree::kEmpty);
  r_.set(slot, MinTree::kEmpty);
  (p.feed ? feed_ : geo_).set(slot, p.value);
  release_.set(slot, p.release_mm);
}

void Lookahead::clear(std::size_t slot) {
  // Only the trees the point's state has it in (insert and enter_range leave the others
  // empty): two tree updates instead of five, for every point of every block.
  switch (state_[slot]) {
    case State::kEmpty:
      return;
    case State::kApproaching:
      w_.set(slot, MinTree::kEmpty);
      r_.set(slot, MinTree::kEmpty);
      break;
    case State::kInRange:
      (points_[slot].feed ? feed_ : geo_).set(slot, MinTree::kEmpty);
      release_.set(slot, MinTree::kEmpty);
      break;
  }
  state_[slot] = State::kEmpty;
}

double Lookahead::limit(double s_cmd, double s_tool, double or_ratio) {
  // Points whose range the commanded position has entered (w ≤ s).
  while (w_.min() <= s_cmd) enter_range(w_.argmin());
  // Points the tool has passed: their cap no longer applies.
  while (release_.min() <= s_tool) clear(release_.argmin());
  const double approaching = r_.min() - s_cmd;
  return std::min({approaching, geo_.min(), or_ratio * feed_.min()});
}

double Lookahead::reference_limit(double s_cmd, double s_tool, double or_ratio) const {
  double ul = MinTree::kEmpty;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (state_[i] == State::kEmpty) continue;
    const CapPoint& p = points_[i];
    if (p.release_mm <= s_tool) continue;  // the tool has passed it
    const Range rg = range_of(p, or_max_);
    if (s_cmd < rg.w) {
      ul = std::min(ul, rg.r - s_cmd);
    } else {
      ul = std::min(ul, p.feed ? or_ratio * p.value : p.value);
    }
  }
  return ul;
}

}  // namespace cncore::planner
