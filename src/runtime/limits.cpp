// The machine limits a sender may change at run time (Controller::set_limits).
#include <cmath>

#include "runtime/control.hpp"

namespace cncore::runtime {

MachineLimits limits_of(const MachineConfig& m) {
  MachineLimits l;
  l.contour_tolerance_mm = m.contour_tolerance_mm;
  l.home_latch_mm_min = m.servo.home_latch_mm_min;
  l.home_search_mm_min = m.servo.home_search_mm_min;
  l.home_pulloff_mm = m.servo.home_pulloff_mm;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    l.max_speed_mm_min[a] = m.axes[a].max_speed_mm_min;
    l.max_accel_mm_s2[a] = m.axes[a].max_accel_mm_s2;
    l.min_mm[a] = m.axes[a].min_mm;
    l.max_mm[a] = m.axes[a].max_mm;
  }
  return l;
}

void apply_limits(MachineConfig& m, const MachineLimits& l) {
  m.contour_tolerance_mm = l.contour_tolerance_mm;
  m.servo.home_latch_mm_min = l.home_latch_mm_min;
  m.servo.home_search_mm_min = l.home_search_mm_min;
  m.servo.home_pulloff_mm = l.home_pulloff_mm;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    m.axes[a].max_speed_mm_min = l.max_speed_mm_min[a];
    m.axes[a].max_accel_mm_s2 = l.max_accel_mm_s2[a];
    m.axes[a].min_mm = l.min_mm[a];
    m.axes[a].max_mm = l.max_mm[a];
  }
}

std::string limits_error(const MachineLimits& l, const MachineConfig& m) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(l.contour_tolerance_mm)) return "the contour tolerance must be > 0";
  if (!positive(l.home_latch_mm_min) || !positive(l.home_search_mm_min)) {
    return "the homing feeds must be > 0";
  }
  if (!std::isfinite(l.home_pulloff_mm) || l.home_pulloff_mm < 0) {
    return "the homing pull-off must be ≥ 0";
  }
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!m.axes[a].enabled) continue;
    const char axis = kAxisLetters[a];
    if (!positive(l.max_speed_mm_min[a]) || !positive(l.max_accel_mm_s2[a])) {
      return std::string("axis ") + axis + ": the speed and acceleration limits must be > 0";
    }
    if (!std::isfinite(l.min_mm[a]) || !std::isfinite(l.max_mm[a]) || l.min_mm[a] >= l.max_mm[a]) {
      return std::string("axis ") + axis + ": the travel's minimum must be below its maximum";
    }
  }
  return {};
}

}  // namespace cncore::runtime
