// Spindle-load sources for adaptive feed control (spec 04): a recorded signal (CSV against time
// or path distance) and a plant model. The cutting simulation implements the same
// interface. load_pct() is called once per interpolation cycle: no allocation, no exceptions.
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "feedcontrol/settings.hpp"

namespace cncore::feed {

class LoadSource {
 public:
  virtual ~LoadSource() = default;
  // The spindle load (% of rating) measured at time t_s, with the tool at path distance
  // path_s_mm moving at feed_mm_min. Calls come in order of non-decreasing t_s.
  virtual double load_pct(double t_s, double path_s_mm, double feed_mm_min) noexcept = 0;
};

// A recorded load signal. CSV with a header naming the abscissa: "t_s,load_pct" (time since the
// start of the run) or "s_mm,load_pct" (path distance). The abscissa may not decrease (equal
// values make a step); between rows the load is interpolated linearly, outside the first and
// last row it is held. Lines starting with '#' and blank lines are skipped.
class RecordedLoad final : public LoadSource {
 public:
  enum class Axis : std::uint8_t { kTime, kDistance };

  // Throws InputError(FILE, LINE, COL) for a missing file, a bad header, an empty field, text
  // where a number belongs, a non-finite or negative load, or an abscissa going backwards.
  static RecordedLoad load(const std::string& path);
  static RecordedLoad parse(std::string_view text, const std::string& source_name);

  double load_pct(double t_s, double path_s_mm, double feed_mm_min) noexcept override;

  Axis axis() const { return axis_; }
  std::size_t size() const { return x_.size(); }
  // The interpolated value at abscissa x (s or mm).
  double at(double x) const noexcept;

 private:
  Axis axis_ = Axis::kTime;
  std::vector<double> x_;
  std::vector<double> load_;
};

// load = base + k·feed·depth(s), through a first-order lag τ·dl/dt = u − l (exact discrete
// step l += (u − l)·(1 − e^(−Δt/τ))), plus seeded Gaussian measurement noise on the reading
// (the lag state itself is noise-free). The state starts at the base load.
class PlantLoad final : public LoadSource {
 public:
  explicit PlantLoad(PlantSettings settings);
  double load_pct(double t_s, double path_s_mm, double feed_mm_min) noexcept override;
  // The noise-free lagged load after the last call.
  double true_load_pct() const noexcept { return state_pct_; }
  double depth_mm(double path_s_mm) const noexcept { return settings_.depth.at(path_s_mm); }

 private:
  PlantSettings settings_;
  double state_pct_;
  double last_t_s_ = 0;
  bool started_ = false;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_;
};

}  // namespace cncore::feed
