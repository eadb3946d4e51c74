#include "simulation/stepper.hpp"

#include <stdexcept>
#include <utility>

#include "core/error.hpp"
#include "feedcontrol/direction_correction.hpp"

namespace cncore::sim {

ProgramStepper::ProgramStepper(const std::string& program_path, const MachineConfig& machine,
                               const motion::KernelOptions& kernel_options,
                               const interp::Options& interpreter_options,
                               const OperatorModes& modes)
    : modes_(modes),
      interpreter_(program_path, machine, interpreter_options),
      kernel_(machine, kernel_options),
      corrector_(std::make_unique<feed::DirectionCorrector>(machine, program_path)),
      merger_(make_line_merger(machine, kernel_options)) {}

ProgramStepper::~ProgramStepper() = default;

bool ProgramStepper::produce(Block& block) {
  while (true) {
    if (merger_.next(block)) return true;
    if (corrector_->next(corrected_)) {
      merger_.put(corrected_);
      continue;
    }
    if (wait_pending_) {  // single-block stop: the wait after the block just handed on
      wait_pending_ = false;
      corrector_->put(wait_);
      continue;
    }
    if (!error_ && interpreter_.next(source_)) {
      if (is_motion(source_)) ++blocks_;
      wait_pending_ = apply_operator_modes(modes_, source_, wait_);
      corrector_->put(source_);
      continue;
    }
    merger_.finish();
    return merger_.next(block);
  }
}

bool ProgramStepper::next(motion::Sample& out) {
  // Read blocks only while the buffer has room: memory stays bounded whatever the length.
  // One interpreted block may give several kernel blocks (an arc split by the direction
  // correction) and several pieces one (a line merged), handed out one at a time.
  while (more_ && kernel_.wants_block()) {
    bool got = false;
    try {
      got = produce(block_);
    } catch (const InputError&) {
      // Finish the motion of the good blocks first (the line merged up to here too), then
      // report.
      error_ = std::current_exception();
      merger_.finish();
      got = merger_.next(block_);
    }
    if (!got) {
      more_ = false;
      kernel_.end_of_program();
      break;
    }
    kernel_.push(block_);
  }
  if (kernel_.step(out)) return true;
  if (more_) throw std::logic_error("motion kernel stopped before the end of the program");
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  return false;
}

}  // namespace cncore::sim
