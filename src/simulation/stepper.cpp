#include "simulation/stepper.hpp"

#include <stdexcept>

namespace cncore::sim {

ProgramStepper::ProgramStepper(const std::string& program_path, const MachineConfig& machine,
                               const motion::KernelOptions& kernel_options,
                               const interp::Options& interpreter_options,
                               const OperatorModes& modes)
    : source_(program_path, machine, interpreter_options, kernel_options, modes),
      kernel_(machine, kernel_options) {}

ProgramStepper::~ProgramStepper() = default;

bool ProgramStepper::next(motion::Sample& out) {
  // Read blocks only while the buffer has room: memory stays bounded whatever the length.
  // An error stops the motion at the end of the last good block; it is thrown once that
  // motion has run out.
  while (more_ && kernel_.wants_block()) {
    if (source_.next(block_) != BlockSource::Status::kBlock) {
      more_ = false;
      kernel_.end_of_program();
      break;
    }
    kernel_.push(block_);
  }
  if (kernel_.step(out)) return true;
  if (more_) throw std::logic_error("motion kernel stopped before the end of the program");
  if (source_.error() && !thrown_) {
    thrown_ = true;
    std::rethrow_exception(source_.error());
  }
  return false;
}

}  // namespace cncore::sim
