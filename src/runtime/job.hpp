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
  std::uint32_t error_line = 0;
  // Cycle → planning thread.
  std::atomic<bool> cancel{false};    // stop producing (reset, E-stop, alarm)
  std::atomic<bool> retired{false};   // the cycle no longer touches the job: it may be freed
  std::atomic<bool> standing{false};  // running (not held) and the tool still this cycle
};

// A job's blocks: the program's (sim::BlockSource), with a program stop after every motion
// block when single block is on (cycle start goes on).
class JobSource {
 public:
  JobSource(std::unique_ptr<sim::BlockSource> source, bool single_block)
      : source_(std::move(source)), single_block_(single_block) {}
  sim::BlockSource::Status next(Block& out) {
    if (pause_pending_) {
      pause_pending_ = false;
      out = pause_;
      return sim::BlockSource::Status::kBlock;
    }
    const auto st = source_->next(out);
    if (st == sim::BlockSource::Status::kBlock && single_block_ && is_motion(out)) {
      pause_ = Block{};
      pause_.kind = BlockKind::kAux;
      pause_.line = out.line;
      pause_.start = pause_.end = out.end;
      pause_.aux_letter = 'M';
      pause_.aux_value = 0;
      pause_.aux_waits = true;
      pause_pending_ = true;
    }
    return st;
  }
  sim::BlockSource& source() { return *source_; }

 private:
  std::unique_ptr<sim::BlockSource> source_;
  bool single_block_ = false;
  Block pause_;
  bool pause_pending_ = false;
};

// A command for the cycle thread (through a lock-free ring; the control side serialises).
struct CycleCommand {
  std::uint64_t seq = 0;  // numbered by the control side; the cycle publishes the last taken
  Command command = Command::kStart;
  double value = 0;
  Job* job = nullptr;  // kStart, kMdi
  JogRequest jog;
  Switches switches;
};

inline CycleCommand cycle_command(Command command, double value = 0) {
  CycleCommand c;
  c.command = command;
  c.value = value;
  return c;
}

}  // namespace cncore::runtime
