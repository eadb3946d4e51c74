// Settings of adaptive feed control (spec 04): the controller's [adaptive] keys and the plant
// model's [adaptive.plant] keys, with their validation. A light header (no <random>, no toml):
// MachineConfig holds these, so it is included widely.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

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

// Depth of cut along the path: piecewise linear through (s_mm, depth_mm) points, held outside.
// Two points at the same s make a jump (the value after the jump is the later point's).
struct DepthProfile {
  std::vector<double> s_mm;
  std::vector<double> depth_mm;

  friend bool operator==(const DepthProfile&, const DepthProfile&) = default;

  double at(double path_s_mm) const noexcept;
  // First problem (key "adaptive.plant.depth"): empty, unequal lengths, s decreasing,
  // negative or non-finite depth.
  std::optional<SettingsProblem> find_problem() const;
};

// Plant-model settings (keys adaptive.plant.<field>).
struct PlantSettings {
  double base_pct = 5;              // no-cut load (spindle idling)
  double k_pct_per_mm2_min = 0.04;  // load per (feed mm/min × depth mm)
  double time_constant_s = 0.05;    // first-order lag of the load behind feed × depth
  double noise_pct = 0.5;           // standard deviation of the Gaussian measurement noise
  std::uint64_t seed = 1;           // noise seed: the same seed gives the same run
  DepthProfile depth;

  friend bool operator==(const PlantSettings&, const PlantSettings&) = default;

  std::optional<SettingsProblem> find_problem() const;
  void validate(const std::string& source = "plant settings") const;
};

}  // namespace cncore::feed
