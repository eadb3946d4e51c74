// Adaptive feed control on spindle load (spec 04, seed: Fanuc CN adaptive feed): a PID whose
// error is target load − measured load and whose output is the feed override, with an output
// limit and a selectable anti-wind-up policy. update() is the real-time part: no allocation, no
// exceptions, constant time.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

namespace cncore::feed {

// What happens to the integral when the output is limited.
//  kNone:             plain PID (the seed's Fig. 5): the adaptive limits upper/lower are NOT
//                     applied; the output is only kept within [0, hard maximum] (the machine's
//                     max_override_pct), so on light cuts the feed rises past `upper_pct`.
//  kClamp:            the seed's prior art (Fig. 6): the output is overwritten with the limit, the
//                     integral keeps integrating the error (wind-up).
//  kBackCalculation:  the seed's method (Fig. 2): output the limit and assign the integral the
//                     value that makes the PID formula give exactly the limit (Formula 4),
//                     I = (ot − Kp·e − Kd·de/dt − c) / Ki, for the upper and the lower limit.
enum class AntiWindup : std::uint8_t { kNone, kClamp, kBackCalculation };

// "none", "clamp", "back_calculation" (the configuration spelling); nullopt for anything else.
std::optional<AntiWindup> parse_antiwindup(std::string_view name);
std::string_view antiwindup_name(AntiWindup policy);

// One key that failed validation: `key` is the configuration key ("adaptive.upper_pct").
struct SettingsProblem {
  std::string key;
  std::string message;
};

// Configuration keys are the field names under [adaptive] (adaptive.<field>).
// Units: load in % of the spindle rating, override in %, so Kp is %override per %load,
// Ki %override per (%load·s), Kd %override·s per %load.
struct AdaptiveSettings {
  bool enabled = false;         // adaptive.enabled: on/off at program start
  double target_load_pct = 60;  // adaptive.target_load_pct
  double kp = 1.0;              // adaptive.kp
  double ki = 5.0;              // adaptive.ki  [1/s]
  double kd = 0.0;              // adaptive.kd  [s]
  double constant_pct = 100;    // adaptive.constant_pct: c, the output at e = 0 and I = 0
  double threshold_pct = 10;    // adaptive.threshold_pct: lm; below it the tool is not cutting
  double upper_pct = 150;       // adaptive.upper_pct: ot
  double lower_pct = 10;        // adaptive.lower_pct
  AntiWindup antiwindup = AntiWindup::kBackCalculation;  // adaptive.antiwindup
  std::uint32_t control_cycles =
      10;  // adaptive.control_cycles: control period / interpolation period

  friend bool operator==(const AdaptiveSettings&, const AdaptiveSettings&) = default;

  // The first problem found, naming its key; nullopt when the settings are usable.
  // max_override_pct: the machine's highest override (upper_pct may not exceed it).
  std::optional<SettingsProblem> find_problem(
      double max_override_pct = std::numeric_limits<double>::infinity()) const;
  // Throws InputError(source, 0, 0, "KEY: MESSAGE") for the first problem found. A loader that
  // knows where the key is written should call find_problem() and throw with that position.
  void validate(const std::string& source = "adaptive settings",
                double max_override_pct = std::numeric_limits<double>::infinity()) const;
};

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
