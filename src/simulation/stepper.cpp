#include "simulation/stepper.hpp"

#include <stdexcept>
#include <utility>

#include "core/error.hpp"

namespace cncore::sim {

ProgramStepper::ProgramStepper(const std::string& program_path, const MachineConfig& machine,
                               const motion::KernelOptions& kernel_options,
                               const interp::Options& interpreter_options)
    : interpreter_(program_path, machine, interpreter_options), kernel_(machine, kernel_options) {}

bool ProgramStepper::next(motion::Sample& out) {
  // Read blocks only while the buffer has room: memory stays bounded whatever the length.
  while (more_ && kernel_.wants_block()) {
    bool got = false;
    try {
      got = interpreter_.next(block_);
    } catch (const InputError&) {
      // Finish the motion of the good blocks first, then report.
      error_ = std::current_exception();
    }
    if (!got) {
      more_ = false;
      kernel_.end_of_program();
      break;
    }
    if (block_.kind == BlockKind::kRapid || block_.kind == BlockKind::kLine ||
        block_.kind == BlockKind::kArc) {
      ++blocks_;
    }
    kernel_.push(block_);
  }
  if (kernel_.step(out)) return true;
  if (more_) throw std::logic_error("motion kernel stopped before the end of the program");
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  return false;
}

}  // namespace cncore::sim
