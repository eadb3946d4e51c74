// The cutting simulator as the cycle controller of sim::run_program (used by `cncore run`).
#pragma once

#include "simulation/cutting/cutting_sim.hpp"
#include "simulation/run.hpp"

namespace cncore::cut {

// The simulator inside sim::run_program as the run's cycle controller: each cycle it sweeps and
// writes Sample::load_pct before the observers see the sample, then hands the sample on to the
// next controller (adaptive feed control, whose load source is the simulator: it reads the
// load of this very cycle) or returns the operator's override. Register it as an observer too:
// on_block checks the T words against the tool table; on_sample does nothing.
class CuttingCycleController final : public sim::CycleController, public sim::SampleObserver {
 public:
  explicit CuttingCycleController(CuttingSimulator& sim, sim::CycleController* next = nullptr)
      : sim_(&sim), next_(next) {}
  double on_cycle(motion::Sample& sample, double operator_override_pct) noexcept override {
    sim_->process(sample);
    return next_ != nullptr ? next_->on_cycle(sample, operator_override_pct)
                            : operator_override_pct;
  }
  void on_block(const Block& block) override { sim_->on_block(block); }
  void on_sample(const motion::Sample& /*sample*/) override {}

 private:
  CuttingSimulator* sim_;
  sim::CycleController* next_;
};

}  // namespace cncore::cut
