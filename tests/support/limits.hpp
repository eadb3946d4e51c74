// Machine limits as the measurement tools see them (trajectory checker, time-optimal bound).
// Defaults are the built-in machine of spec 05; limits_from_config copies a MachineConfig.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>

#include "config/machine_config.hpp"
#include "core/geometry.hpp"

namespace cncore::testing {

struct Limits {
  double period_s = 0.001;         // τ
  double max_feed_mm_min = 10000;  // Vmax of feed moves (G1 G2 G3)
  double rapid_mm_min = 15000;     // Vmax of rapid moves (G0)
  double max_accel_mm_s2 = 2000;   // Amax, tangential and normal
  double max_jerk_mm_s3 = 0;       // 0: jerk not checked
  double max_override_pct = 200;   // highest override the operator can set
  // Per-axis limits (mm/min and mm/s², degrees for rotary axes); 0: no limit on that axis.
  std::array<double, kMaxAxes> axis_speed_mm_min{};
  std::array<double, kMaxAxes> axis_accel_mm_s2{};

  // Checker only.
  double path_tolerance_mm = 0.001;  // P1: distance to the programmed path
  double end_tolerance_mm = 1e-9;    // P4: last position vs programmed end
  double stop_tolerance_mm = 1e-6;   // P4: landing on an intermediate stop point
  double margin = 0.005;             // relative numeric margin on every limit (0.5 %)
  // Rounding q of the positions (the larger of this and Trajectory::position_resolution_mm,
  // which the CSV loader sets from the decimals); gives the absolute slacks: positions 3q,
  // speed 4q/τ, acceleration 8q/τ², jerk 16q/τ³.
  double position_resolution_mm = 1e-9;
  // P2 after a runtime override decrease: the speed may follow the limit that was in force up
  // to this long before (the acc/dec ramp). < 0: automatic, max(feed, rapid)/Amax (+ 2·Amax/Jmax,
  // the jerk stage's span, with a jerk limit; + the post filter's span) + 2τ.
  double override_ramp_s = -1;
  double post_filter_s = 0;               // span of the post-interpolation filter (0: none)
  bool override_applies_to_rapid = true;  // false: rapids always at most the rapid rate
  double max_resultant_accel_mm_s2 = 0;   // > 0: also check the resultant acceleration
  bool check_jerk = true;                 // only when max_jerk_mm_s3 > 0

  double feed_mm_s() const { return max_feed_mm_min / 60.0; }
  double rapid_mm_s() const { return rapid_mm_min / 60.0; }
  double ramp_s() const {
    if (override_ramp_s >= 0) return override_ramp_s;
    double r = std::max(max_feed_mm_min, rapid_mm_min) / 60.0 / max_accel_mm_s2 + 2 * period_s;
    if (max_jerk_mm_s3 > 0) r += 2 * max_accel_mm_s2 / max_jerk_mm_s3;
    return r + post_filter_s;
  }
};

// The limits of a machine configuration (header-only: reads fields, links nothing).
inline Limits limits_from_config(const MachineConfig& m) {
  Limits l;
  l.period_s = m.period_s;
  l.max_feed_mm_min = m.max_feed_mm_min;
  l.rapid_mm_min = m.rapid_mm_min;
  l.max_accel_mm_s2 = m.max_accel_mm_s2;
  l.max_jerk_mm_s3 = m.max_jerk_mm_s3;
  l.post_filter_s = m.post_filter_s;
  l.max_override_pct = m.max_override_pct;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!m.axes[i].enabled) continue;
    l.axis_speed_mm_min[i] = m.axes[i].max_speed_mm_min;
    l.axis_accel_mm_s2[i] = m.axes[i].max_accel_mm_s2;
  }
  if (m.post_filter_s > 0) l.path_tolerance_mm = m.contour_tolerance_mm;
  return l;
}

}  // namespace cncore::testing
