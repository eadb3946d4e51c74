// A closed-loop test bench without the motion kernel: one feed axis along a straight path,
// commanded feed = F × override / 100, rate-limited by a constant acceleration, driving the
// plant model. Used by the tests and by the figures of docs/adaptive-feed.md. Not real-time
// (it records a trace).
#pragma once

#include <cstdint>
#include <vector>

#include "feedcontrol/adaptive.hpp"
#include "feedcontrol/load_source.hpp"

namespace cncore::feed {

struct StraightPathOptions {
  double length_mm = 100;                // the run ends when the tool reaches this distance
  double programmed_feed_mm_min = 1000;  // F
  double operator_override_pct = 100;
  double max_accel_mm_s2 = 1000;   // |dF/dt| limit of the commanded feed
  double period_s = 0.001;         // interpolation period
  double max_override_pct = 400;   // the machine's highest override (the bound under kNone)
  double max_time_s = 600;         // stop here even if the end was not reached
  std::uint32_t record_every = 1;  // keep one trace row per this many cycles
};

// One recorded interpolation cycle.
struct TraceRow {
  double t_s = 0;
  double s_mm = 0;
  double depth_mm = 0;
  double feed_mm_min = 0;    // feed actually run this cycle (after the acceleration limit)
  double override_pct = 0;   // the controller's output in force this cycle
  double load_pct = 0;       // measured (with noise)
  double true_load_pct = 0;  // the plant's noise-free load
  double target_pct = 0;
  double integral_term_pct = 0;  // Ki·I after the last control cycle
  bool active = false;           // load ≥ lm at the last control cycle
  bool limited = false;          // the output was limited at the last control cycle
};

// Runs the plant and the controller from standstill at s = 0 until s = length_mm. The feed at
// cycle n is the rate-limited response to the override computed at cycle n − 1.
std::vector<TraceRow> run_straight_path(const AdaptiveSettings& settings,
                                        const PlantSettings& plant,
                                        const StraightPathOptions& options);

}  // namespace cncore::feed
