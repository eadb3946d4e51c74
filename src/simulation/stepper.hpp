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
#include "simulation/block_source.hpp"
#include "simulation/operator_modes.hpp"

namespace cncore::sim {

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
  std::uint64_t blocks() const {
    return source_.motion_blocks();
  }  // motion blocks interpreted so far

 private:
  BlockSource source_;
  motion::Kernel kernel_;
  Block block_;
  bool more_ = true;     // the source may still produce blocks
  bool thrown_ = false;  // the program's error has been thrown (once)
};

}  // namespace cncore::sim
