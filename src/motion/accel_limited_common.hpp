// What the files of the acceleration-limited acc/dec type share (accel_limited*.cpp): the
// constants every part of the derivation uses and the closed forms more than one of them needs.
// Internal to src/motion: not part of the stage's public header.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>

#include "planner/segment.hpp"

namespace cncore::motion::accel_limited_common {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
// The filters after this type (8.): the jerk stage's T2 and the post filter's Tp, 0 when off.
inline double jerk_cycles(const planner::Limits& l) {
  return l.t2_cycles > 1 ? l.t2_cycles : 0.0;
}
inline double post_cycles(const planner::Limits& l) {
  return l.post_filter() ? l.post_cycles : 0.0;
}
inline constexpr double kRecoverShare =
    0.98;  // √(a_t² + a_n²) ≤ 0.98·g slowing down on an arc (5.)
// Joint zones (7.): the speed change allowed at a joint is at least this share of the segments'
// (below it, the corner's passing speed is lowered instead).
inline constexpr double kZoneFloor = 0.25;
inline constexpr std::size_t kZoneWalk = 16;  // segments a joint zone may reach back over

// The largest step x from which the tool can still stop exactly at distance d with steps that
// shrink by at most a per cycle: x + (x − a) + (x − 2a) + … (positive terms, the last one ≤ a
// landing on the stop) ≤ d. With m the largest integer with a·m(m+1)/2 ≤ d this is
// x = d/(m+1) + a·m/2 (d ≤ a: x = d, the landing step). Following it the steps are exactly
// x, x − a, x − 2a, …: f(x) = x + f(x − a), so after the step the rest is f(x − a).
inline double landing_step(double d, double a) {
  if (d <= a) return d;
  double m = std::floor((std::sqrt(8 * d / a + 1) - 1) / 2);
  while (m > 0 && a * m * (m + 1) / 2 > d) m -= 1;
  while (a * (m + 1) * (m + 2) / 2 <= d) m += 1;
  return d / (m + 1) + a * m / 2;
}

// A bound b = √X − c is left out of a minimum when X ≥ above(t + c) = (t + c)²·(1 + kSkipMargin):
// then √X − c ≥ t + (t + c)·kSkipMargin/2 exactly, far above the few roundings of either side.
inline constexpr double kSkipMargin = 1e-9;

inline double above(double x) {
  return x * x * (1 + kSkipMargin);
}

}  // namespace cncore::motion::accel_limited_common
