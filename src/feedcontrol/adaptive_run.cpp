#include "feedcontrol/adaptive_run.hpp"

#include "core/error.hpp"

namespace cncore::feed {

SelectedLoadSource make_load_source(const MachineConfig& machine,
                                    const LoadSourceOptions& options) {
  if (!options.load_csv.empty()) {
    return {std::make_unique<RecordedLoad>(RecordedLoad::load(options.load_csv)),
            "recorded " + options.load_csv};
  }
  if (!machine.adaptive_plant.depth.s_mm.empty()) {
    // The loader validated the plant; a configuration built in code is checked here.
    machine.adaptive_plant.validate("machine configuration");
    return {std::make_unique<PlantLoad>(machine.adaptive_plant), "plant model"};
  }
  return {nullptr, ""};
}

namespace {

const AdaptiveSettings& validated(const AdaptiveSettings& s, const MachineConfig& machine,
                                  const std::string& config_name) {
  s.validate(config_name, machine.max_override_pct);
  return s;
}

}  // namespace

AdaptiveCycleController::AdaptiveCycleController(const MachineConfig& machine,
                                                 const AdaptiveSettings& settings,
                                                 LoadSource& source, const std::string& config_name)
    : loop_(validated(settings, machine, config_name), machine.period_s, machine.max_override_pct,
            source) {}

double AdaptiveCycleController::on_cycle(motion::Sample& sample,
                                         double operator_override_pct) noexcept {
  if (sample.aux_letter == 'M' && sample.aux_value == 52) {
    loop_.set_enabled(sample.aux_p != 0);
    ++switches_;
  }
  ever_enabled_ = ever_enabled_ || loop_.enabled();
  return loop_.on_sample(sample, operator_override_pct);
}

double cycle_time_without_adaptive_s(const std::string& program_path, const MachineConfig& machine,
                                     sim::RunOptions options) {
  options.cycle_controller = nullptr;
  const sim::RunCounts counts = sim::run_program(program_path, machine, options, {});
  // The k-th sample is at t = k·τ, the first (k = 0) the start position.
  return counts.cycles > 0 ? static_cast<double>(counts.cycles - 1) * machine.period_s : 0.0;
}

}  // namespace cncore::feed
