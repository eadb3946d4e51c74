#include "feedcontrol/closed_loop.hpp"

#include <algorithm>

#include "feedcontrol/adaptive_loop.hpp"

namespace cncore::feed {

std::vector<TraceRow> run_straight_path(const AdaptiveSettings& settings,
                                        const PlantSettings& plant_settings,
                                        const StraightPathOptions& o) {
  plant_settings.validate();
  PlantLoad plant(plant_settings);
  AdaptiveSettings on = settings;
  on.enabled = true;
  AdaptiveFeedLoop loop(on, o.period_s, o.max_override_pct, plant);

  std::vector<TraceRow> trace;
  const double dv_max_mm_min = o.max_accel_mm_s2 * o.period_s * 60.0;  // per cycle
  double feed_mm_min = 0;
  double s_mm = 0;
  double override_pct = o.operator_override_pct;
  for (std::uint64_t n = 0;; ++n) {
    const double t_s = static_cast<double>(n) * o.period_s;
    if (s_mm >= o.length_mm || t_s > o.max_time_s) break;
    // The commanded feed follows F × override with |dF/dt| ≤ Amax.
    const double wanted = o.programmed_feed_mm_min * override_pct / 100.0;
    feed_mm_min += std::clamp(wanted - feed_mm_min, -dv_max_mm_min, dv_max_mm_min);
    s_mm += feed_mm_min / 60.0 * o.period_s;
    override_pct = loop.cycle(t_s, s_mm, feed_mm_min, o.operator_override_pct);
    if (n % std::max<std::uint32_t>(1, o.record_every) == 0) {
      const ControllerState& st = loop.controller().state();
      TraceRow r;
      r.t_s = t_s;
      r.s_mm = s_mm;
      r.depth_mm = plant.depth_mm(s_mm);
      r.feed_mm_min = feed_mm_min;
      r.override_pct = override_pct;
      r.load_pct = loop.last_load_pct();
      r.true_load_pct = plant.true_load_pct();
      r.target_pct = settings.target_load_pct;
      r.integral_term_pct = st.integral_term_pct;
      r.active = st.active;
      r.limited = st.limited;
      trace.push_back(r);
    }
  }
  return trace;
}

}  // namespace cncore::feed
