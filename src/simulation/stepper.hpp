// A part program run one interpolation cycle at a time, pulled by the caller (run_program pushes
// every sample to observers instead). Used where something else owns the clock: a table run
// whose master axis is moved by a part program (spec 02), or a test that interleaves its own
// actions between cycles. Memory is bounded by the kernel's buffer, as in run_program.
#pragma once

#include <cstdint>
#include <exception>
#include <memory>
#include <string>

#include "config/machine_config.hpp"
#include "interpreter/interpreter.hpp"
#include "motion/kernel.hpp"

namespace cncore::feed {
class DirectionCorrector;
}  // namespace cncore::feed

namespace cncore::sim {

class ProgramStepper {
 public:
  ProgramStepper(const std::string& program_path, const MachineConfig& machine,
                 const motion::KernelOptions& kernel_options,
                 const interp::Options& interpreter_options = {});
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
  interp::Interpreter interpreter_;
  motion::Kernel kernel_;
  // The direction feed correction stage (spec 03), as in run_program.
  std::unique_ptr<feed::DirectionCorrector> corrector_;
  Block source_;
  Block block_;
  bool more_ = true;  // the interpreter may still produce blocks
  std::exception_ptr error_;
  std::uint64_t blocks_ = 0;
};

}  // namespace cncore::sim
