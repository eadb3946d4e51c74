#include "feedcontrol/adaptive.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace cncore::feed {

std::optional<AntiWindup> parse_antiwindup(std::string_view name) {
  if (name == "none") return AntiWindup::kNone;
  if (name == "clamp") return AntiWindup::kClamp;
  if (name == "back_calculation") return AntiWindup::kBackCalculation;
  return std::nullopt;
}

std::string_view antiwindup_name(AntiWindup policy) {
  switch (policy) {
    case AntiWindup::kNone:
      return "none";
    case AntiWindup::kClamp:
      return "clamp";
    case AntiWindup::kBackCalculation:
      return "back_calculation";
  }
  return "none";
}

namespace {

std::optional<SettingsProblem> problem(const char* key, std::string message) {
  return SettingsProblem{key, std::move(message)};
}

}  // namespace

std::optional<SettingsProblem> AdaptiveSettings::find_problem(double max_override_pct) const {
  const struct {
    const char* key;
    double value;
  } finite[] = {{"adaptive.target_load_pct", target_load_pct},
                {"adaptive.kp", kp},
                {"adaptive.ki", ki},
                {"adaptive.kd", kd},
                {"adaptive.constant_pct", constant_pct},
                {"adaptive.threshold_pct", threshold_pct},
                {"adaptive.upper_pct", upper_pct},
                {"adaptive.lower_pct", lower_pct}};
  for (const auto& f : finite) {
    if (!std::isfinite(f.value)) return problem(f.key, "must be a finite number");
  }
  if (target_load_pct < 0) return problem("adaptive.target_load_pct", "must not be negative");
  // A negative gain turns the loop into positive feedback: more load, more feed.
  if (kp < 0) return problem("adaptive.kp", "must not be negative");
  if (ki < 0) return problem("adaptive.ki", "must not be negative");
  if (kd < 0) return problem("adaptive.kd", "must not be negative");
  if (threshold_pct < 0) return problem("adaptive.threshold_pct", "must not be negative");
  if (threshold_pct >= target_load_pct && target_load_pct > 0) {
    // The controller is idle below lm, so a target below lm could never be reached.
    return problem("adaptive.threshold_pct", "must be below adaptive.target_load_pct");
  }
  if (lower_pct < 0) return problem("adaptive.lower_pct", "must not be negative");
  if (upper_pct <= lower_pct) {
    return problem("adaptive.upper_pct", "must be greater than adaptive.lower_pct");
  }
  if (upper_pct > max_override_pct) {
    return problem("adaptive.upper_pct", "must not exceed the machine's max_override_pct (" +
                                             std::to_string(max_override_pct) + ")");
  }
  if (antiwindup == AntiWindup::kBackCalculation && ki == 0) {
    // Formula 4 divides by Ki.
    return problem("adaptive.ki",
                   "must be positive with adaptive.antiwindup = \"back_calculation\"");
  }
  if (control_cycles == 0) return problem("adaptive.control_cycles", "must be at least 1");
  return std::nullopt;
}

void AdaptiveSettings::validate(const std::string& source, double max_override_pct) const {
  if (auto p = find_problem(max_override_pct)) {
    throw InputError(source, 0, 0, p->key + ": " + p->message);
  }
}

AdaptiveController::AdaptiveController(const AdaptiveSettings& settings, double control_period_s,
                                       double hard_max_pct)
    : settings_(settings), dt_s_(control_period_s), hard_max_pct_(hard_max_pct) {}

double AdaptiveController::output_min_pct() const noexcept {
  return settings_.antiwindup == AntiWindup::kNone ? 0.0 : settings_.lower_pct;
}

double AdaptiveController::output_max_pct() const noexcept {
  return settings_.antiwindup == AntiWindup::kNone ? hard_max_pct_ : settings_.upper_pct;
}

void AdaptiveController::reset() noexcept {
  state_ = ControllerState{};
  have_previous_error_ = false;
  previous_error_pct_ = 0;
}

double AdaptiveController::update(double load_pct, double operator_override_pct) noexcept {
  const AdaptiveSettings& s = settings_;
  // Step SA01/SA06: not cutting (or no reading) → the operator's override, controller idle.
  // The integral is kept; the derivative restarts so that re-entering the cut gives no kick.
  if (!(load_pct >= s.threshold_pct)) {
    state_.active = false;
    state_.limited = false;
    state_.output_pct = operator_override_pct;
    have_previous_error_ = false;
    return operator_override_pct;
  }

  // Step SA02: o = Kp·e + Ki·I + Kd·de/dt + c, I advanced by the rectangle e·Δt (Formula 2).
  const double e = s.target_load_pct - load_pct;
  const double de_dt = have_previous_error_ ? (e - previous_error_pct_) / dt_s_ : 0.0;
  previous_error_pct_ = e;
  have_previous_error_ = true;
  state_.integral += e * dt_s_;
  const double p_d_c = s.kp * e + s.kd * de_dt + s.constant_pct;
  const double o = p_d_c + s.ki * state_.integral;

  // Steps SA03–SA05.
  const double lo = output_min_pct();
  const double hi = output_max_pct();
  double out = o;
  state_.limited = false;
  if (o > hi || o < lo) {
    out = o > hi ? hi : lo;
    state_.limited = true;
    if (s.antiwindup == AntiWindup::kBackCalculation) {
      // Formula 4: the integral that makes Formula 3 give exactly the output limit,
      // I = (ot − Kp·e − Kd·de/dt − c) / Ki (validate() guarantees Ki > 0).
      state_.integral = (out - p_d_c) / s.ki;
    }
  }
  state_.active = true;
  state_.error_pct = e;
  state_.integral_term_pct = s.ki * state_.integral;
  state_.pid_output_pct = o;
  state_.output_pct = out;
  return out;
}

}  // namespace cncore::feed
