#include "feedcontrol/adaptive_loop.hpp"

#include <algorithm>
#include <cmath>

namespace cncore::feed {

namespace {

AdaptiveSettings validated(const AdaptiveSettings& s, double max_override_pct) {
  s.validate("adaptive settings", max_override_pct);
  return s;
}

}  // namespace

AdaptiveFeedLoop::AdaptiveFeedLoop(const AdaptiveSettings& settings, double period_s,
                                   double max_override_pct, LoadSource& source)
    : controller_(validated(settings, max_override_pct), period_s * settings.control_cycles,
                  max_override_pct),
      source_(&source),
      enabled_(settings.enabled),
      max_override_pct_(max_override_pct) {}

void AdaptiveFeedLoop::set_enabled(bool on) noexcept {
  if (on && !enabled_) {
    controller_.reset();
    cycles_to_control_ = 0;
  }
  enabled_ = on;
}

double AdaptiveFeedLoop::cycle(double t_s, double path_s_mm, double feed_mm_min,
                               double operator_override_pct) noexcept {
  last_load_pct_ = source_->load_pct(t_s, path_s_mm, feed_mm_min);
  if (!enabled_) {
    override_pct_ = operator_override_pct;
    return override_pct_;
  }
  if (cycles_to_control_ == 0) {
    // The controller works on its own factor (100 % = as programmed); its limits and its
    // anti-wind-up apply to that factor, whatever the operator does with the override.
    adaptive_pct_ = controller_.update(last_load_pct_, 100.0);
    cycles_to_control_ = controller_.settings().control_cycles;
  }
  --cycles_to_control_;
  // Idle (not cutting): the operator's override passes at once, not at the next control cycle.
  // Cutting: both act on the feed, F·(adaptive)·(operator), so an operator who turns the
  // override down slows an adaptive cut too.
  override_pct_ = controller_.state().active
                      ? std::min(max_override_pct_, adaptive_pct_ * operator_override_pct / 100.0)
                      : operator_override_pct;
  return override_pct_;
}

double AdaptiveFeedLoop::on_sample(motion::Sample& sample, double operator_override_pct) noexcept {
  if (have_position_) {
    double sq = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      const double d = sample.path_position[i] - last_position_[i];
      sq += d * d;
    }
    path_s_mm_ += std::sqrt(sq);
  }
  have_position_ = true;
  last_position_ = sample.path_position;
  const double out = cycle(sample.t_s, path_s_mm_, sample.feed_mm_min, operator_override_pct);
  sample.load_pct = last_load_pct_;
  sample.load_target_pct = controller_.settings().target_load_pct;
  return out;
}

}  // namespace cncore::feed
