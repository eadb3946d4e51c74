// Internal to the runtime: the work of one interpolation cycle, run by the cycle thread. It
// applies the commands that arrived, moves the tool (program kernel, jog or homing), runs the
// servo model and outputs, and publishes the status. Real-time: after construction nothing here
// allocates, locks, logs or blocks.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

#include "core/spsc_ring.hpp"
#include "runtime/control.hpp"
#include "runtime/job.hpp"
#include "runtime/line_motion.hpp"
#include "runtime/seqlock.hpp"
#include "runtime/servo.hpp"

namespace cncore::runtime {

class CuttingThread;
class AdaptiveFeed;

struct CycleLinks {
  SpscRing<CycleCommand>* commands = nullptr;   // control → cycle
  SpscRing<motion::Sample>* samples = nullptr;  // cycle → read_samples (may be null)
  SpscRing<AppliedCommand>* applied = nullptr;  // cycle → read_applied
  Seqlock<Status>* status = nullptr;
  ServoOutput* output = nullptr;     // may be null (sim only)
  bool lossless_samples = false;     // ControllerOptions::lossless_samples
  CuttingThread* cutting = nullptr;  // the cutting simulation (a machine with [stock])
  AdaptiveFeed* adaptive = nullptr;  // adaptive feed control on its load
};

class CycleLoop {
 public:
  CycleLoop(const MachineConfig& machine, const CycleLinks& links, const AxisVec& start,
            const AxisVec& sim_position_error);
  // One cycle, number n since the start (wake-up lateness and the previous cycle's work are
  // reported in the status).
  void run(std::uint64_t n);
  void add_overrun() { ++status_.overruns; }
  void set_work_us(double us) {
    if (us > status_.cycle_work_max_us) status_.cycle_work_max_us = us;
  }
  MachineState state() const { return status_.state; }
  // Lets a lossless sample wait give up (the controller is stopping).
  void set_stopping(const std::atomic<bool>* stopping) { stopping_ = stopping; }

  // Blocks the kernel may take in one cycle (bounds a cycle's work when segments are tiny).
  static constexpr int kMaxPushesPerCycle = 256;

 private:
  void apply(const CycleCommand& c, std::uint64_t n);
  void apply_stop_or_move(const CycleCommand& c, bool moving_alone);
  void start_job(Job* job, std::uint64_t n, bool mdi);
  void retire_job(JobEnd end);
  void program_cycle(motion::Sample& s);
  void note_aux(const motion::Sample& s);  // spindle and tool from the M/S/T events reached
  void feed_kernel();
  void motion_cycle(motion::Sample& s);
  void homing_step();
  void start_homing_axis();
  void raise_alarm(AlarmCode alarm, std::uint32_t line);
  void finish_outputs(std::uint64_t n, motion::Sample& s);

  enum class HomePhase : std::uint8_t { kSearch, kStopping, kLatch, kPulloff };

  MachineConfig machine_;  // its own copy: kLimits changes it between two cycles
  CycleLinks links_;
  SimAxes sim_;
  Status status_;
  Job* job_ = nullptr;
  bool ended_sent_ = false;
  bool paused_by_program_ = false;
  std::uint32_t tool_prepared_ = 0;  // the last T word; M6 puts it in the spindle
  LineMotion line_;
  JogRequest pending_jog_;
  bool jog_pending_ = false;
  std::array<std::uint8_t, kMaxAxes> home_order_{};
  std::size_t home_count_ = 0, home_index_ = 0;
  HomePhase home_phase_ = HomePhase::kSearch;
  double speed_mm_s_ = 0;
  bool rapid_set_ = false;  // a rapid override was given: rapids no longer follow the feed's
  const std::atomic<bool>* stopping_ = nullptr;  // the controller is stopping (see set_stopping)
};

}  // namespace cncore::runtime
