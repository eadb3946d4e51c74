// The per-interpolation-cycle driver of adaptive feed control: measures the load every cycle,
// runs the controller every `control_cycles` cycles and holds its override in between. This is
// the hook `cncore run` calls after each Kernel::step(); the closed-loop harness uses it too.
#pragma once

#include "feedcontrol/adaptive.hpp"
#include "feedcontrol/load_source.hpp"
#include "motion/kernel.hpp"

namespace cncore::feed {

class AdaptiveFeedLoop {
 public:
  // period_s: the interpolation period; max_override_pct: the machine's highest override.
  // Validates the settings (InputError naming the key). The source must outlive the loop.
  AdaptiveFeedLoop(const AdaptiveSettings& settings, double period_s, double max_override_pct,
                   LoadSource& source);

  // One interpolation cycle: the tool is at path distance path_s_mm at time t_s moving at
  // feed_mm_min. Returns the override (%) to apply from the next cycle. While cutting it is
  // the controller's output times the operator's override (spec 04: they combine; at 100 %
  // operator override it is the controller's output), at most max_override_pct. Below lm,
  // and while disabled, it is the operator's override; the load is still measured.
  double cycle(double t_s, double path_s_mm, double feed_mm_min,
               double operator_override_pct) noexcept;

  // The kernel form: path distance accumulated from sample.path_position (XYZ), fills
  // sample.load_pct and sample.load_target_pct. Call once per Kernel::step() and pass the
  // result to Kernel::set_override().
  double on_sample(motion::Sample& sample, double operator_override_pct) noexcept;

  // The program switch (on/off). Switching on resets the controller (a fresh integral).
  void set_enabled(bool on) noexcept;
  bool enabled() const noexcept { return enabled_; }

  double last_load_pct() const noexcept { return last_load_pct_; }
  double override_pct() const noexcept { return override_pct_; }
  double path_s_mm() const noexcept { return path_s_mm_; }
  const AdaptiveController& controller() const noexcept { return controller_; }

 private:
  AdaptiveController controller_;
  LoadSource* source_;
  bool enabled_;
  std::uint32_t cycles_to_control_ = 0;  // 0: the controller runs at this cycle
  double last_load_pct_ = 0;
  double override_pct_ = 100;
  double adaptive_pct_ = 100;  // the controller's last output
  double max_override_pct_ = 200;
  double path_s_mm_ = 0;
  bool have_position_ = false;
  AxisVec last_position_{};
};

}  // namespace cncore::feed
