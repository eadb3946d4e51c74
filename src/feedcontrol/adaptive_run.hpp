// Adaptive feed control inside `cncore run` (spec 04): the choice of the load source, the
// per-cycle controller the simulated run calls (with the program switch M52 P1 / M52 P0), and
// the comparison run without adaptive control.
#pragma once

#include <memory>
#include <string>

#include "config/machine_config.hpp"
#include "feedcontrol/adaptive_loop.hpp"
#include "feedcontrol/load_source.hpp"
#include "simulation/run.hpp"

namespace cncore::feed {

// Command-line choices that select a load source.
struct LoadSourceOptions {
  std::string load_csv;  // --load FILE.csv: a recorded load signal (against time or distance)
};

struct SelectedLoadSource {
  std::unique_ptr<LoadSource> source;  // nullptr: no load source, adaptive control unavailable
  std::string description;             // "recorded FILE", "plant model" (summaries)
};

// The one place that picks the load source, in this order: --load FILE.csv (RecordedLoad; a
// bad file throws InputError at its line), [adaptive.plant] with a depth profile (PlantLoad),
// else none. (The cutting simulation is added here.)
SelectedLoadSource make_load_source(const MachineConfig& machine, const LoadSourceOptions& options);

// The adaptive loop as the run's cycle controller. Every cycle: a sample carrying M52 switches
// the controller (P1 on, resetting the integral; P0 off), then AdaptiveFeedLoop::on_sample
// measures the load, fills the sample's load columns and gives the override.
class AdaptiveCycleController final : public sim::CycleController {
 public:
  // Validates the settings against the machine: InputError(config_name, "KEY: MESSAGE") (a
  // configuration file checks them at load with the key's line; this catches the rest, e.g.
  // the default upper_pct above a lowered max_override_pct without an [adaptive] table).
  AdaptiveCycleController(const MachineConfig& machine, const AdaptiveSettings& settings,
                          LoadSource& source, const std::string& config_name);
  double on_cycle(motion::Sample& sample, double operator_override_pct) noexcept override;

  const AdaptiveFeedLoop& loop() const noexcept { return loop_; }
  std::uint64_t switch_count() const noexcept { return switches_; }  // M52 events seen
  bool ever_enabled() const noexcept { return ever_enabled_; }       // the controller ran at all

 private:
  AdaptiveFeedLoop loop_;
  std::uint64_t switches_ = 0;
  bool ever_enabled_ = false;
};

// The cycle time (s) of the same run without adaptive control: the program run again with
// the operator's override alone (options.cycle_controller ignored), no outputs.
double cycle_time_without_adaptive_s(const std::string& program_path, const MachineConfig& machine,
                                     sim::RunOptions options);

}  // namespace cncore::feed
