// Adaptive feed control on spindle load (spec 04, seed: Fanuc CN adaptive feed): a PID whose
// error is target load − measured load and whose output is the feed override, with an output
// limit and a selectable anti-wind-up policy. update() is the real-time part: no allocation, no
// exceptions, constant time.
#pragma once

#include <cstdint>

#include "feedcontrol/settings.hpp"

namespace cncore::feed {

// The controller's state after a control cycle (the trace the seed's figures plot).
struct ControllerState {
  bool active = false;           // the load was ≥ lm at the last control cycle
  bool limited = false;          // the PID output was outside the output range and was replaced
  double error_pct = 0;          // e = target − load
  double integral = 0;           // I = ∫e dt  [%·s]
  double integral_term_pct = 0;  // Ki·I
  double pid_output_pct = 0;     // o = Kp·e + Ki·I + Kd·de/dt + c, before limiting
  double output_pct = 0;         // the override sent to the motion cycle
};

class AdaptiveController {
 public:
  // control_period_s = settings.control_cycles × interpolation period. hard_max_pct: the
  // machine's max_override_pct, the only upper bound under AntiWindup::kNone.
  // Precondition: settings.validate() passed; control_period_s > 0.
  AdaptiveController(const AdaptiveSettings& settings, double control_period_s,
                     double hard_max_pct);

  // One control cycle. load_pct: the measured spindle load; operator_override_pct: the
  // operator's override, passed through unchanged while load < lm. Returns the override (%).
  double update(double load_pct, double operator_override_pct) noexcept;

  // Forget the integral and the derivative memory (a new cut, or re-enabling).
  void reset() noexcept;

  const ControllerState& state() const noexcept { return state_; }
  const AdaptiveSettings& settings() const noexcept { return settings_; }
  double control_period_s() const noexcept { return dt_s_; }
  // The output range of the active policy: [lower, upper], or [0, hard max] under kNone.
  double output_min_pct() const noexcept;
  double output_max_pct() const noexcept;

 private:
  AdaptiveSettings settings_;
  double dt_s_;
  double hard_max_pct_;
  double previous_error_pct_ = 0;
  bool have_previous_error_ = false;
  ControllerState state_;
};

}  // namespace cncore::feed
