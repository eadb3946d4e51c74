// Internal to the runtime: what the control side, the planning thread and the cycle thread hand
// each other. A Job is one program or MDI run: made (allocated) by the control side, its blocks
// produced by the planning thread into `ring`, its kernel stepped by the cycle thread, and freed
// by the planning thread once the cycle has retired it.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "core/block.hpp"
#include "core/spsc_ring.hpp"
#include "motion/kernel.hpp"
#include "runtime/control.hpp"
#include "simulation/block_source.hpp"

namespace cncore::runtime {

struct Job {
  Job(const MachineConfig& machine, const motion::KernelOptions& options, std::size_t ring_blocks)
      : kernel(machine, options), ring(ring_blocks) {}

  motion::Kernel kernel;
  SpscRing<Block> ring;  // planning thread → cycle
  std::uint64_t serial = 0;
  // Planning thread → cycle (release after the last push / the error text).
  std::atomic<bool> produced_all{false};
  std::atomic<bool> failed{false};
  std::atomic<bool> fatal{false};  // not a program error: the planner itself failed
  bool end_given = false;  // the control side told the kernel the program's end (a short one)
  // feed_one's state: a block held back behind single block's program stop.
  Block held;
  bool has_held = false;
  bool pause_due = false;
  std::uint32_t pause_line = 0;
  std::uint32_t error_line = 0;
  // Cycle → planning thread.
  std::atomic<bool> cancel{false};    // stop producing (reset, E-stop, alarm)
  std::atomic<bool> retired{false};   // the cycle no longer touches the job: it may be freed
  std::atomic<bool> standing{false};  // running (not held) and the tool still this cycle
};

// A job's blocks: the program's (sim::BlockSource).
class JobSource {
 public:
  explicit JobSource(std::unique_ptr<sim::BlockSource> source) : source_(std::move(source)) {}
  sim::BlockSource::Status next(Block& out) { return source_->next(out); }
  sim::BlockSource& source() { return *source_; }

 private:
  std::unique_ptr<sim::BlockSource> source_;
};

// Block::aux_p of the program stop that single block puts after a motion block: it pauses only
// while the switch is still on when the tool gets there.
constexpr double kSingleBlockPause = -1;

// Takes the next block into the job's kernel (the one held back first, else one from `next`);
// false when `next` had none. With single block on, a program stop goes in after every motion
// block, before the next block that is not a piece of a merged line, so the tool stops at the
// end of the programmed block (the kernel never runs past the last block it has, so the stop is
// always reachable). The control side uses it for the kernel's first fill, the cycle thread
// afterwards: only one at a time, never allocating.
template <typename Next>
bool feed_one(Job& j, bool single_block, Next&& next) {
  if (!j.has_held) {
    if (!next(j.held)) return false;
    j.has_held = true;
  }
  if (j.pause_due && !j.held.piece) {
    j.pause_due = false;
    if (single_block) {
      Block pause;
      pause.kind = BlockKind::kAux;
      pause.line = j.pause_line;
      pause.start = pause.end = j.held.start;
      pause.aux_letter = 'M';
      pause.aux_value = 0;
      pause.aux_waits = true;
      pause.aux_p = kSingleBlockPause;
      j.kernel.push(pause);
      return true;
    }
  }
  j.kernel.push(j.held);
  j.has_held = false;
  if (single_block && is_motion(j.held) && !j.held.piece) {
    j.pause_due = true;
    j.pause_line = j.held.line;
  }
  return true;
}

// A command for the cycle thread (through a lock-free ring; the control side serialises).
struct CycleCommand {
  std::uint64_t seq = 0;  // numbered by the control side; the cycle publishes the last taken
  Command command = Command::kStart;
  double value = 0;
  Job* job = nullptr;  // kStart, kMdi
  JogRequest jog;
  Switches switches;
  MachineLimits limits;  // kLimits
};

inline CycleCommand cycle_command(Command command, double value = 0) {
  CycleCommand c;
  c.command = command;
  c.value = value;
  return c;
}

}  // namespace cncore::runtime
