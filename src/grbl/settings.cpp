#include "grbl/settings.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

namespace cncore::grbl {

namespace {

// Settings without a meaning on a controller that does not generate steps: accepted, no effect.
bool without_effect(int n) {
  return (n >= 0 && n <= 6) || n == 12 || n == 23 || n == 26 || n == 30 || n == 31 ||
         (n >= 100 && n <= 102);
}

// Settings whose only honest value is the one cncore implements.
std::optional<double> fixed_value(int n) {
  switch (n) {
    case 13:
      return 0;  // reports in mm
    case 20:
      return 1;  // soft limits: cncore always checks the travel before motion
    case 21:
      return 0;  // no hard-limit switches on the simulated machine
    case 22:
      return 1;  // homing against the simulated switches
    case 32:
      return 0;  // no laser mode
    default:
      return std::nullopt;
  }
}

constexpr int kAxisBase[] = {110, 120, 130};

}  // namespace

Settings Settings::from_machine(const MachineConfig& m) {
  Settings s;
  auto& v = s.values_;
  v[0] = 10, v[1] = 25, v[2] = 0, v[3] = 0, v[4] = 0, v[5] = 0, v[6] = 0;
  v[10] = 1;
  v[11] = m.contour_tolerance_mm;
  v[12] = 0.002;
  v[13] = 0, v[20] = 1, v[21] = 0, v[22] = 1, v[23] = 0;
  v[24] = m.servo.home_latch_mm_min;
  v[25] = m.servo.home_search_mm_min;
  v[26] = 250;
  v[27] = m.servo.home_pulloff_mm;
  v[30] = 1000, v[31] = 0, v[32] = 0;
  for (int a = 0; a < 3; ++a) {
    const AxisConfig& ax = m.axes[static_cast<std::size_t>(a)];
    v[100 + a] = 250;
    v[110 + a] = ax.max_speed_mm_min;
    v[120 + a] = ax.max_accel_mm_s2;
    v[130 + a] = ax.max_mm - ax.min_mm;
  }
  return s;
}

std::string Settings::listing() const {
  std::string out;
  for (const auto& [n, value] : values_) {
    const bool integral = value == std::floor(value) && std::abs(value) < 1e9;
    out += integral ? fmt::format("${}={}\r\n", n, static_cast<long long>(value))
                    : fmt::format("${}={:.3f}\r\n", n, value);
  }
  return out;
}

std::optional<double> Settings::value(int number) const {
  const auto it = values_.find(number);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::optional<int> Settings::write(int n, double value) {
  if (!values_.contains(n) || !std::isfinite(value)) return 3;
  if (const auto fixed = fixed_value(n)) {
    if (value != *fixed) return 3;
  } else if (n == 10) {
    if (value < 0 || value > 3) return 3;
  } else if (without_effect(n) ? value < 0 : value <= 0) {
    return 4;
  }
  values_[n] = value;
  return std::nullopt;
}

void Settings::apply(MachineConfig& m) const {
  m.contour_tolerance_mm = values_.at(11);
  m.servo.home_latch_mm_min = values_.at(24);
  m.servo.home_search_mm_min = values_.at(25);
  m.servo.home_pulloff_mm = values_.at(27);
  for (std::size_t a = 0; a < 3; ++a) {
    AxisConfig& ax = m.axes[a];
    if (!ax.enabled) continue;
    const int i = static_cast<int>(a);
    ax.max_speed_mm_min = values_.at(kAxisBase[0] + i);
    ax.max_accel_mm_s2 = values_.at(kAxisBase[1] + i);
    // Travel: Grbl's machine space ends at the home switch (the maximum here).
    ax.min_mm = ax.max_mm - values_.at(kAxisBase[2] + i);
  }
}

std::string Settings::to_json() const {
  nlohmann::json j;
  j["settings"] = nlohmann::json::object();
  for (const auto& [n, value] : values_) j["settings"][std::to_string(n)] = value;
  j["startup"] = {startup[0], startup[1]};
  return j.dump(1);
}

void Settings::merge_json(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (!j.is_object()) return;
  if (const auto st = j.find("startup"); st != j.end() && st->is_array() && st->size() == 2) {
    for (std::size_t i = 0; i < 2; ++i) {
      if ((*st)[i].is_string()) startup[i] = (*st)[i].get<std::string>();
    }
  }
  const auto s = j.find("settings");
  if (s == j.end() || !s->is_object()) return;
  for (const auto& [key, value] : s->items()) {
    if (!value.is_number()) continue;
    const int n = std::atoi(key.c_str());
    if (values_.contains(n)) (void)write(n, value.get<double>());
  }
}

}  // namespace cncore::grbl
