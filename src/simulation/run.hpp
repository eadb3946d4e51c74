// The simulated machine: interpreter → motion kernel → sample observers, streamed. Used by
// `cncore run`, the tests and the benchmarks, so that all three run exactly the same path.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "config/machine_config.hpp"
#include "interpreter/interpreter.hpp"
#include "motion/kernel.hpp"

namespace cncore::sim {

// Receives every interpolation cycle's sample, in order, and every block as it is planned.
class SampleObserver {
 public:
  virtual ~SampleObserver() = default;
  virtual void on_block(const Block& /*block*/) {}
  virtual void on_sample(const motion::Sample& sample) = 0;
  // The run ended normally (all samples delivered).
  virtual void on_finish() {}
};

struct RunOptions {
  motion::KernelOptions kernel;
  interp::Options interpreter;
  // Feed-override steps (time in s, override in %), applied at the first cycle with t >= time.
  std::vector<std::pair<double, double>> override_steps;
};

struct RunCounts {
  std::uint64_t blocks = 0;  // motion blocks interpreted
  std::uint64_t cycles = 0;  // samples produced
};

// Runs the program to its end. Throws InputError on an error in the program; samples delivered
// before the error stay delivered (a run stops at the end of the last good block).
RunCounts run_program(const std::string& program_path, const MachineConfig& machine,
                      const RunOptions& options, std::vector<SampleObserver*> observers);

}  // namespace cncore::sim
