#include "simulation/block_source.hpp"

#include <utility>

#include "core/error.hpp"
#include "feedcontrol/direction_correction.hpp"

namespace cncore::sim {

BlockSource::BlockSource(const std::string& program_path, const MachineConfig& machine,
                         const interp::Options& options, const motion::KernelOptions& kernel,
                         const OperatorModes& modes)
    : BlockSource(std::make_unique<interp::Interpreter>(program_path, machine, options),
                  program_path, machine, kernel, modes) {}

BlockSource::BlockSource(std::unique_ptr<interp::Interpreter> interpreter,
                         const std::string& program_name, const MachineConfig& machine,
                         const motion::KernelOptions& kernel, const OperatorModes& modes)
    : modes_(modes),
      interpreter_(std::move(interpreter)),
      corrector_(std::make_unique<feed::DirectionCorrector>(machine, program_name)),
      smoother_(smoothing_settings(machine, kernel)),
      merger_(make_line_merger(machine, kernel)) {}

BlockSource::~BlockSource() = default;

BlockSource::Status BlockSource::next(Block& out) {
  if (error_) {
    // The curve and the line held at the error go out first: the run stops at the end of the
    // last good block, as without smoothing and merging.
    return drain(out) ? Status::kBlock : Status::kInputError;
  }
  try {
    return produce(out) ? Status::kBlock : Status::kEnd;
  } catch (const InputError&) {
    error_ = std::current_exception();
    smoother_.finish();
    return drain(out) ? Status::kBlock : Status::kInputError;
  }
}

bool BlockSource::drain(Block& block) {
  while (true) {
    if (merger_.next(block)) return true;
    if (!smoother_.next(smoothed_)) break;
    merger_.put(smoothed_);
  }
  merger_.finish();
  return merger_.next(block);
}

bool BlockSource::produce(Block& block) {
  while (true) {
    if (merger_.next(block)) return true;
    if (smoother_.next(smoothed_)) {
      merger_.put(smoothed_);
      continue;
    }
    if (corrector_->next(corrected_)) {
      smoother_.put(corrected_);
      continue;
    }
    if (wait_pending_) {  // single-block stop: the wait after the block just handed on
      wait_pending_ = false;
      corrector_->put(wait_);
      continue;
    }
    if (more_) more_ = interpreter_->next(source_);
    if (!more_) {
      if (!ended_) {
        ended_ = true;
        smoother_.finish();
        continue;
      }
      merger_.finish();
      return merger_.next(block);
    }
    if (is_motion(source_)) ++motion_blocks_;
    wait_pending_ = apply_operator_modes(modes_, source_, wait_);
    corrector_->put(source_);
  }
}

}  // namespace cncore::sim
