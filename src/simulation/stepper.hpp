// A part program run one interpolation cycle at a time, pulled by the caller (run_program pushes
// every sample to observers instead). Used where something else owns the clock: a table run
// whose master axis is moved by a part program (spec 02), or a test that interleaves its own
// actions between cycles. Memory is bounded by the kernel's buffer, as in run_program.
#pragma once

#include <algorithm>
#include <cstdint>
#include <exception>
#include <memory>
#include <string>

#include "config/machine_config.hpp"
#include "interpreter/interpreter.hpp"
#include "motion/kernel.hpp"
#include "planner/line_merge.hpp"
#include "simulation/operator_modes.hpp"

namespace cncore::feed {
class DirectionCorrector;
}  // namespace cncore::feed

namespace cncore::sim {

// The stage that merges collinear pieces (planner/line_merge.hpp) for this machine: joints
// turning by less than a corner passed at max(Vmax, rapid) needs. Off in stop mode (a stop at
// every programmed block).
inline planner::LineMerger make_line_merger(const MachineConfig& machine,
                                            const motion::KernelOptions& kernel) {
  const double top_mm_s = std::max(machine.max_feed_mm_min, machine.rapid_mm_min) / 60;
  return {kernel.mode == motion::Mode::kStop ? 0.0 : machine.merge_tolerance_mm,
          planner::LineMerger::max_turn_rad(machine.max_accel_mm_s2, machine.period_s, top_mm_s)};
}

class ProgramStepper {
 public:
  ProgramStepper(const std::string& program_path, const MachineConfig& machine,
                 const motion::KernelOptions& kernel_options,
                 const interp::Options& interpreter_options = {}, const OperatorModes& modes = {});
  ~ProgramStepper();
  ProgramStepper(const ProgramStepper&) = delete;
  ProgramStepper& operator=(const ProgramStepper&) = delete;

  // The next sample (the first one is the start position at t = 0). Returns false, writing
  // nothing, once the program has ended and the machine has stopped. An error in the program
  // stops the motion at the end of the last good block; the InputError is thrown from the call
  // after the last sample of that motion.
  bool next(motion::Sample& out);

  motion::Kernel& kernel() { return kernel_; }
  std::uint64_t blocks() const { return blocks_; }  // motion blocks interpreted so far

 private:
  // The next block for the kernel (false at the end of the program or after an error).
  bool produce(Block& block);

  OperatorModes modes_;  // dry run, single-block stop
  Block wait_;           // the wait a single-block stop hands on after a block
  bool wait_pending_ = false;
  interp::Interpreter interpreter_;
  motion::Kernel kernel_;
  // The direction feed correction stage (spec 03), as in run_program.
  std::unique_ptr<feed::DirectionCorrector> corrector_;
  planner::LineMerger merger_;  // collinear pieces merged (planner/line_merge.hpp)
  Block source_, corrected_;
  Block block_;
  bool more_ = true;  // the interpreter may still produce blocks
  std::exception_ptr error_;
  std::uint64_t blocks_ = 0;
};

}  // namespace cncore::sim
