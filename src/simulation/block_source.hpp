// The blocks the motion cycle takes, in the order every driver must take them: interpreter →
// operator modes (dry run, single block) → direction correction (spec 03) → path smoothing
// (planner/path_smoother) → collinear pieces merged (planner/line_merge). `cncore run`
// (run_program), the pulled ProgramStepper and the controller's planning thread (`cncore serve`)
// all read their blocks from here, so they plan exactly the same path. One kernel block per call,
// reading source blocks only as needed: memory stays bounded whatever the program length.
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
#include "planner/path_smoother.hpp"
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

// The path smoothing stage (planner/path_smoother.hpp) for this machine; off in stop mode.
inline planner::SmoothingSettings smoothing_settings(const MachineConfig& machine,
                                                     const motion::KernelOptions& kernel) {
  const bool stop = kernel.mode == motion::Mode::kStop;
  const double top_mm_s = std::max(machine.max_feed_mm_min, machine.rapid_mm_min) / 60;
  return {stop ? 0.0 : machine.smooth_tolerance_mm, machine.smooth_corner_deg,
          stop ? 0.0 : machine.contour_tolerance_mm, machine.merge_tolerance_mm,
          planner::LineMerger::max_turn_rad(machine.max_accel_mm_s2, machine.period_s, top_mm_s)};
}

class BlockSource {
 public:
  // Reads the program file (throws InputError when it cannot be read).
  BlockSource(const std::string& program_path, const MachineConfig& machine,
              const interp::Options& options, const motion::KernelOptions& kernel,
              const OperatorModes& modes);
  // Takes an interpreter already made (program text held in memory: an MDI line);
  // `program_name` is the name errors of later stages use.
  BlockSource(std::unique_ptr<interp::Interpreter> interpreter, const std::string& program_name,
              const MachineConfig& machine, const motion::KernelOptions& kernel,
              const OperatorModes& modes);
  ~BlockSource();
  BlockSource(const BlockSource&) = delete;
  BlockSource& operator=(const BlockSource&) = delete;

  enum class Status : std::uint8_t {
    kBlock,       // `out` holds the next kernel block
    kEnd,         // the program has ended
    kInputError,  // an error in the program (error()); the blocks before it were all handed out
  };
  // Errors other than InputError propagate.
  Status next(Block& out);

  std::exception_ptr error() const { return error_; }
  // Motion blocks interpreted so far.
  std::uint64_t motion_blocks() const { return motion_blocks_; }
  interp::Interpreter& interpreter() { return *interpreter_; }

 private:
  bool produce(Block& block);
  bool drain(Block& block);  // the blocks the smoother and the merger hold, after an error

  OperatorModes modes_;
  Block wait_;  // the wait a single-block stop hands on after a block
  bool wait_pending_ = false;
  std::unique_ptr<interp::Interpreter> interpreter_;
  std::unique_ptr<feed::DirectionCorrector> corrector_;
  planner::PathSmoother smoother_;
  planner::LineMerger merger_;
  Block source_, corrected_, smoothed_;
  bool more_ = true;    // the interpreter may still produce blocks
  bool ended_ = false;  // the smoother has been told the program ended
  std::uint64_t motion_blocks_ = 0;
  std::exception_ptr error_;
};

}  // namespace cncore::sim
