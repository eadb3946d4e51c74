// The scenario of the seed's three figures, with our plant: air, a medium cut, a light cut on
// which even the upper limit cannot reach the target load, a heavy cut (the depth jumps up at
// s = 120 mm), a light cut again, air. Shared by the tests and the figures tool.
#pragma once

#include <algorithm>
#include <limits>
#include <vector>

#include "feedcontrol/closed_loop.hpp"

namespace cncore::feed::scenario {

inline constexpr double kJumpUpMm = 120;     // depth 0.5 → 2.0 mm
inline constexpr double kJumpDownMm = 170;   // depth 2.0 → 0.5 mm
inline constexpr double kLightStartMm = 60;  // depth 1.0 → 0.5 mm
inline constexpr double kOverloadBandPct =
    5;  // "above target" = load > target + 5 % (10 σ of the noise)

inline PlantSettings plant() {
  PlantSettings p;
  p.base_pct = 5;
  p.k_pct_per_mm2_min = 0.04;  // at F 1000 mm/min: 1 mm deep → 45 %, 2 mm → 85 %
  p.time_constant_s = 0.05;
  p.noise_pct = 0.5;
  p.seed = 7;
  // s:     0  10 | 10  60 | 60  120 | 120 170 | 170 220 | 220 240
  // depth: air   | 1.0    | 0.5     | 2.0     | 0.5     | air
  p.depth.s_mm = {0, 10, 10, 60, 60, 120, 120, 170, 170, 220, 220, 240};
  p.depth.depth_mm = {0, 0, 1.0, 1.0, 0.5, 0.5, 2.0, 2.0, 0.5, 0.5, 0, 0};
  return p;
}

inline AdaptiveSettings settings(AntiWindup policy) {
  AdaptiveSettings s;
  s.enabled = true;
  s.target_load_pct = 60;
  s.kp = 1.0;
  s.ki = 10.0;
  s.kd = 0.0;
  s.constant_pct = 100;
  s.threshold_pct = 10;
  s.upper_pct = 150;
  s.lower_pct = 10;
  s.antiwindup = policy;
  s.control_cycles = 10;  // 10 ms control period at the 1 ms interpolation period
  return s;
}

inline StraightPathOptions options() {
  StraightPathOptions o;
  o.length_mm = 240;
  o.programmed_feed_mm_min = 1000;
  o.operator_override_pct = 100;
  o.max_accel_mm_s2 = 1000;
  o.period_s = 0.001;
  o.max_override_pct = 400;
  return o;
}

inline std::vector<TraceRow> run(AntiWindup policy) {
  return run_straight_path(settings(policy), plant(), options());
}

// Seconds with the measured load above target + band for s in [from_mm, to_mm).
inline double time_above_s(const std::vector<TraceRow>& trace, double from_mm, double to_mm,
                           double period_s, double band_pct = kOverloadBandPct) {
  double t = 0;
  for (const TraceRow& r : trace) {
    if (r.s_mm >= from_mm && r.s_mm < to_mm && r.load_pct > r.target_pct + band_pct) t += period_s;
  }
  return t;
}

// Seconds from the first row at s ≥ from_mm until the measured load is first back at or below
// target + band (infinity if never before to_mm).
inline double time_to_recover_s(const std::vector<TraceRow>& trace, double from_mm, double to_mm,
                                double band_pct = kOverloadBandPct) {
  double t0 = -1;
  bool was_above = false;
  for (const TraceRow& r : trace) {
    if (r.s_mm < from_mm) continue;
    if (r.s_mm >= to_mm) break;
    if (t0 < 0) t0 = r.t_s;
    const bool above = r.load_pct > r.target_pct + band_pct;
    if (above) was_above = true;
    if (was_above && !above) return r.t_s - t0;
  }
  return std::numeric_limits<double>::infinity();
}

struct Range {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  double span() const { return max - min; }
};

// Range of a column over rows in [from_mm, to_mm) that satisfy pred.
template <class Get, class Pred>
Range range_of(const std::vector<TraceRow>& trace, double from_mm, double to_mm, Get get,
               Pred pred) {
  Range r;
  for (const TraceRow& row : trace) {
    if (row.s_mm < from_mm || row.s_mm >= to_mm || !pred(row)) continue;
    r.min = std::min(r.min, get(row));
    r.max = std::max(r.max, get(row));
  }
  return r;
}

}  // namespace cncore::feed::scenario
