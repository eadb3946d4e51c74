// The motion kernel: execution-data buffer + look-ahead planner + per-cycle interpolation.
// Blocks go in (push), one Sample per interpolation period comes out (step). step() is the
// real-time motion cycle: no heap allocation, no I/O, no exceptions, and its cost does not
// grow with segment count or program length (all buffers are sized at construction).
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>

#include "config/machine_config.hpp"
#include "core/block.hpp"

namespace cncore::motion {

enum class Mode : std::uint8_t {
  kLookahead,  // spec 01: passing speeds + look-ahead, no stop between blocks
  kStop,       // the seed's conventional method: stop at the end of every block
};

// The acc/dec type of look-ahead mode (stop mode always uses the moving average).
enum class AccDecType : std::uint8_t {
  kMovingAverage,  // the seed's: look-ahead limit + moving average of T (+ T2) cycles
  kAcceleration,   // constant-acceleration planning before interpolation
  kSearch,         // samples searched ahead of the tool (motion/search_accdec.hpp)
};

struct KernelOptions {
  Mode mode = Mode::kLookahead;
  AccDecType accdec = AccDecType::kAcceleration;
  double override_pct = 100;  // initial feed override
  // Arcs: bound the resultant of tangential and normal acceleration by Amax (true) or each of
  // them separately (false, the seed's way: the resultant may reach √2·Amax).
  bool bound_resultant_accel = false;
  // Tests: every cycle, also compute the look-ahead limit by a plain walk over the buffer and
  // count the cycles where it differs (reference_mismatches()). O(n) per cycle.
  bool check_reference_walk = false;
};

// The options a machine's configuration asks for: look-ahead mode, its [motion] accdec and
// bound_resultant_accel (every command that runs the kernel for a machine starts from these).
KernelOptions kernel_options_for(const MachineConfig& machine);

// One interpolation cycle.
struct Sample {
  double t_s = 0;          // time of this sample; the first sample (t = 0) is the start position
  std::uint32_t line = 0;  // source line of the block being executed, 0 when none
  AxisVec position;        // axis set-points sent to the servos (after post-interpolation acc/dec)
  AxisVec path_position;   // the interpolated point on the programmed path (before it)
  double feed_mm_min = 0;  // path speed of path_position this cycle (after the acc/dec filter)
  double override_pct = 100;
  // Optional channels (specs 03, 04); NaN when the feature is not active.
  double correction = std::nan("");
  double load_pct = std::nan("");
  double load_target_pct = std::nan("");
  double ref = std::nan("");  // table reference value (spec 02: ms, mm or deg); NaN otherwise
  // Auxiliary event (M/S/T) reached in this cycle, kind kAux; aux_letter == 0 when none.
  char aux_letter = 0;
  double aux_value = 0;
  double aux_p = 0;  // its P word (M52 P1 / P0), see Block::aux_p
};

class Kernel {
 public:
  Kernel(const MachineConfig& machine, const KernelOptions& options);
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  // True while the execution-data buffer has room for another block.
  bool wants_block() const;
  // Appends an interpreted block (motion, dwell or aux). Precondition: wants_block().
  void push(const Block& block);
  // No more blocks will come: the last block ends with a stop.
  void end_of_program();

  // One interpolation period. Writes the sample and returns true; returns false (writing
  // nothing) once the program has ended and the machine has stopped at its end point.
  // While blocks are still expected the kernel never moves past what it has been given:
  // the buffer's last end point is treated as a stop until its successor arrives.
  bool step(Sample& out);

  // Feed override in percent (0 … max_override_pct); takes effect at the next cycle.
  void set_override(double pct);
  // Rapid override in percent (0 … 100) for G0 moves, which then no longer follow the feed
  // override; a negative value makes rapids follow the feed override again (the default, as
  // `cncore run --override` does). Takes effect at the next cycle.
  void set_rapid_override(double pct);
  // Feed hold: decelerate along the path to a stop and wait; false resumes.
  void set_feed_hold(bool hold);

  // Stop at a block end (single block switched on while the program runs): from the next
  // cycle on, the first end of a motion block ahead of the tool at which it can still come to
  // rest within the machine's limits (speed, acceleration, what the acc/dec type honours: the
  // moving average's lag, the jerk stage, the post filter) is a stop, and the tool does not
  // move past it until release_stop_at_block_end(). A stop already ahead (the end of what the
  // kernel holds, a dwell, an event that waits) counts as one when it comes first. Only one at
  // a time: a request while one stands is ignored. With no block end ahead yet (the buffer
  // ends at the tool) the request waits for the next block.
  // The cycle that takes the request does extra work bounded by the buffer's capacity (the
  // block ends tried from the stopping distance on); the others one comparison more.
  void request_stop_at_block_end();
  // True while the tool rests (post filter settled) on the requested stop.
  bool stopped_at_block_end() const;
  // Lifts the requested stop, reached or not: the motion goes on (e.g. at cycle start). A new
  // request from rest stops at the next block end.
  void release_stop_at_block_end();

  // Diagnostics (tests, benchmarks).
  std::uint64_t reference_mismatches() const;  // see KernelOptions::check_reference_walk
  double filter_time_s() const;                // (T + T2 − 1)·τ: span of the acc/dec filter

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cncore::motion
