// The simulated machine: interpreter → motion kernel → sample observers, streamed. Used by
// `cncore run`, the tests and the benchmarks, so that all three run exactly the same path.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "config/machine_config.hpp"
#include "interpreter/interpreter.hpp"
#include "motion/kernel.hpp"
#include "simulation/operator_modes.hpp"

namespace cncore::sim {

// Receives every interpolation cycle's sample, in order, and every block as it is planned.
class SampleObserver {
 public:
  virtual ~SampleObserver() = default;
  virtual void on_block(const Block& /*block*/) {}
  virtual void on_sample(const motion::Sample& sample) = 0;
  // Consecutive samples with no block between them, in order: the same as on_sample on each
  // (the default), in one virtual call (an observer may override it to loop inline).
  virtual void on_samples(std::span<const motion::Sample> samples) {
    for (const motion::Sample& s : samples) on_sample(s);
  }
  // The run ended normally (all samples delivered).
  virtual void on_finish() {}
};

// Sets the feed override every interpolation cycle from what the cycle measured (adaptive feed
// control, spec 04). Called after each Kernel::step(), before the observers see the sample: it
// may fill the sample's optional channels (load, load target). Real-time: no allocation.
class CycleController {
 public:
  virtual ~CycleController() = default;
  // operator_override_pct: the operator's override in force (--override, --override-at).
  // Returns the override (%) the kernel runs from the next cycle.
  virtual double on_cycle(motion::Sample& sample, double operator_override_pct) noexcept = 0;
};

// CNCORE_PRODUCER_THREAD from the environment ("1": true, anything else: false), false when
// unset. Read once per process.
bool default_producer_thread();

struct RunOptions {
  motion::KernelOptions kernel;
  interp::Options interpreter;
  OperatorModes operator_modes;  // dry run, single-block stop
  // Feed-override steps (time in s, override in %), applied at the first cycle with t >= time.
  std::vector<std::pair<double, double>> override_steps;
  // When set, it decides the kernel's override every cycle; the override steps then only set
  // the operator's override it is given. Not owned.
  CycleController* cycle_controller = nullptr;
  // Interpret the program (interpreter + direction correction) on a producer thread
  // that hands the blocks to the motion cycle through a lock-free ring of `ring_blocks` blocks
  // (a power of two). The samples are bit-identical either way: the cycle takes exactly the
  // same blocks at exactly the same cycles, and waits for the producer rather than run short.
  // false: everything on the calling thread. Off by default: on the shared 2-core machine it
  // was not consistently faster (bench/README.md, bench_pipeline). The default can be set for
  // a whole process (A/B measurements of `cncore run`, which has no flag for it) with the
  // environment variable CNCORE_PRODUCER_THREAD=1.
  bool producer_thread = default_producer_thread();
  std::size_t ring_blocks = 4096;
  // Linux: pin the producer thread to this CPU (benchmarks); < 0: let the scheduler place it.
  int producer_cpu = -1;
};

struct RunCounts {
  std::uint64_t blocks = 0;  // motion blocks interpreted
  std::uint64_t cycles = 0;  // samples produced
  // With the producer thread: how often the cycle found no block ready and waited for the
  // producer (a late block), and for how long in total (wall time).
  std::uint64_t producer_waits = 0;
  double producer_wait_s = 0;
};

// Runs the program to its end. Throws InputError on an error in the program; samples delivered
// before the error stay delivered (a run stops at the end of the last good block). Observers
// and the cycle controller are called on the calling thread only, in the same order whether
// or not the program is interpreted on a producer thread (RunOptions::producer_thread).
RunCounts run_program(const std::string& program_path, const MachineConfig& machine,
                      const RunOptions& options, const std::vector<SampleObserver*>& observers);

}  // namespace cncore::sim
