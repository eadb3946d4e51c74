// Internal to the runtime: adaptive feed control (spec 04, docs/adaptive-feed.md) in `cncore
// serve`, on the spindle load of the cutting simulation (src/runtime/cutting.hpp). The cycle
// thread runs the controller after each program cycle and gives the kernel its override for the
// next cycle, as `cncore run` does; the load it reads is the one the simulation's thread last
// published, late by the simulation's lag (Status::cutting_lag_cycles).
#pragma once

#include <cstdint>

#include "config/machine_config.hpp"
#include "feedcontrol/adaptive_loop.hpp"
#include "motion/kernel.hpp"
#include "runtime/control.hpp"
#include "runtime/cutting.hpp"

namespace cncore::runtime {

class AdaptiveFeed {
 public:
  // Validates [adaptive] against the machine: InputError naming the key otherwise.
  AdaptiveFeed(const MachineConfig& machine, const CuttingThread& cutting);

  // Cycle thread, each cycle of a program or MDI job: the override (%) for the next cycle. A job
  // starts with the controller on or off as [adaptive] enabled says (on: a fresh integral);
  // M52 P1 / M52 P0 switch it. Fills s.load_target_pct. Real-time: no allocation, no exceptions.
  double on_cycle(motion::Sample& s, const Status& status) noexcept;

 private:
  // The simulation's last published load.
  class Load final : public feed::LoadSource {
   public:
    explicit Load(const CuttingThread& cutting) : cutting_(&cutting) {}
    double load_pct(double /*t_s*/, double /*path_s_mm*/,
                    double /*feed_mm_min*/) noexcept override {
      return cutting_->load_pct();
    }

   private:
    const CuttingThread* cutting_;
  };

  bool enabled_at_start_;
  Load load_;
  feed::AdaptiveFeedLoop loop_;
  std::uint64_t job_ = 0;
};

}  // namespace cncore::runtime
