#include "runtime/adaptive_feed.hpp"

namespace cncore::runtime {

namespace {

const feed::AdaptiveSettings& validated(const MachineConfig& machine) {
  machine.adaptive.validate("machine configuration", machine.max_override_pct);
  return machine.adaptive;
}

}  // namespace

AdaptiveFeed::AdaptiveFeed(const MachineConfig& machine, const CuttingThread& cutting)
    : enabled_at_start_(machine.adaptive.enabled),
      load_(cutting),
      loop_(validated(machine), machine.period_s, machine.max_override_pct, load_) {}

double AdaptiveFeed::on_cycle(motion::Sample& s, const Status& status) noexcept {
  if (status.job != job_) {
    job_ = status.job;
    loop_.set_enabled(false);  // so that switching on below starts a fresh integral
    loop_.set_enabled(enabled_at_start_);
  }
  if (s.aux_letter == 'M' && s.aux_value == 52) loop_.set_enabled(s.aux_p != 0);
  const double pct = loop_.on_sample(s, status.feed_override_pct);
  s.load_pct = status.load_pct;  // the simulation's, as the status shows it
  return pct;
}

}  // namespace cncore::runtime
