// The acc/dec type: the part of the motion cycle that turns the programmed feed, the passing
// speeds of the buffer and the override into the tool's position along the path, one cycle at a
// time. The buffer, the geometry and the shape interpolation do not depend on it, so each type
// (the moving average, constant-acceleration planning before interpolation, the sample search)
// plugs in behind this interface without touching them.
#pragma once

#include <cstdint>

#include "planner/segment.hpp"

namespace cncore::motion {

struct CycleInput {
  double or_ratio = 1;  // feed override (1 = 100 %)
  bool hold = false;    // feed hold: come to a stop on the path
  // The commanded position may not pass this (mm): the buffer's last end point while its
  // successor has not arrived, the end of the program, or the next dwell / waiting event.
  double stop_mm = 0;
};

class AccDec {
 public:
  virtual ~AccDec() = default;

  // A motion segment was appended to the buffer as item `index` (before on_joint with it).
  virtual void on_segment(std::uint64_t /*index*/, const planner::Segment& /*s*/) {}
  // The successor b of motion item a (buffer index index_a) arrived: the joint is known.
  virtual void on_joint(std::uint64_t index_a, const planner::Segment& a,
                        const planner::Segment& b) = 0;
  // A barrier (exact stop, dwell, waiting event) follows the last motion segment: the tool must
  // stop at its end. (The acceleration types read it from CycleInput::stop_mm instead.)
  virtual void on_barrier() {}
  // No more blocks will come.
  virtual void on_end_of_program() {}
  // Whether the acc/dec still needs buffer item `index` (the interpolator has passed it).
  virtual bool holds(std::uint64_t index) const = 0;
  // The buffer is full and its oldest item `index` is still held: keep what the acc/dec needs
  // of it elsewhere (possibly stricter) so that it can be dropped; false when it cannot. Without
  // this a full buffer whose oldest item is held deadlocks: no new block, so the tool waits at
  // the window's end, so the item is never passed.
  virtual bool detach(std::uint64_t /*index*/) { return false; }
  // The buffer drops item `index`.
  virtual void on_retire(std::uint64_t index) = 0;

  // One interpolation cycle. Real-time: no allocation, no I/O, bounded work.
  virtual void step(const CycleInput& in) = 0;

  // A stop at a block end was asked for (Kernel::request_stop_at_block_end). Called between two
  // cycles, on the cycle of the request only; the kernel tries the block ends from
  // stop_reach_mm() on and takes the first that can_stop_at() accepts.
  // The lowest path position the commanded motion can still stop at within the type's limits.
  virtual double stop_reach_mm() = 0;
  // Whether a stop at `stop_mm` (≥ stop_reach_mm()) keeps every limit of the type.
  virtual bool can_stop_at(double /*stop_mm*/) const { return true; }
  // From the next cycle on CycleInput::stop_mm is at most `stop_mm`: a type that plans ahead
  // of the cycle plans again for it.
  virtual void on_stop_request(double /*stop_mm*/) {}
  // The requested stop is lifted (the tool rests on it, or has not got there yet).
  virtual void on_stop_release() {}

  virtual double tool_mm() const = 0;        // the tool's path position (filtered)
  virtual double tool_speed_pc() const = 0;  // its step this cycle (mm/cycle)
  virtual double commanded_mm() const = 0;   // the commanded (pre-filter) path position
  virtual bool at_rest() const = 0;          // no motion left in the acc/dec
};

}  // namespace cncore::motion
