#include "motion/search_accdec.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace cncore::motion {

namespace {
// Front cycles searched per cycle: two while fewer than kLeadSamples committed samples wait
// (the front gains on the tool), then one (it keeps pace). Two every cycle made every other
// cycle search two once the output ring was full: bench_motion Latency/random_2k/search worst
// cycle 132 → 84–89 µs, p99 102–107 → 71–72 µs with one.
constexpr int kCatchUpCyclesPerCycle = 2;
constexpr std::size_t kLeadSamples = 256;

SampleSearchOptions search_options(std::size_t window_segments) {
  SampleSearchOptions o;
  o.window_segments = window_segments;
  return o;
}
}  // namespace

SearchAccDec::SearchAccDec(const planner::Limits& lim, std::size_t window_segments)
    : search_(lim, search_options(window_segments)),
      // The checker lets an override decrease take one ramp to the top speed: Vmax/Amax.
      ramp_cycles_(static_cast<std::size_t>(std::max(lim.vmax_pc, lim.rapid_pc) / lim.amax_pc2)) {}

void SearchAccDec::on_segment(std::uint64_t /*index*/, const planner::Segment& s) {
  if (!search_.push(s, false)) {
    throw std::runtime_error("line " + std::to_string(s.line) +
                             ": acc/dec type \"search\" cannot run this move (a rotary-only "
                             "move, or a window too small for the look-ahead buffer)");
  }
  if (!started_) {
    started_ = true;
    tool_mm_ = s.s0_mm;
    // The search's first sample is the start, which the kernel has sent already (t = 0).
    AxisVec p;
    std::uint32_t line = 0;
    double s0 = 0;
    search_.pop(p, line, s0);
  }
}

void SearchAccDec::step(const CycleInput& in) {
  if (!stepped_) {
    // The override in force from the first cycle: no sample ran at another one, so no ramp.
    stepped_ = true;
    if (in.or_ratio != ratio_) {
      ratio_ = in.or_ratio;
      search_.restart(ratio_, 0);
    }
  }
  if (in.hold != hold_) {
    hold_ = in.hold;
    if (hold_) {
      search_.brake_now();
    } else if (in.or_ratio != ratio_) {
      ratio_ = in.or_ratio;
      search_.restart(ratio_, ramp_cycles_);
    }
  } else if (!hold_ && in.or_ratio != ratio_) {
    ratio_ = in.or_ratio;
    search_.restart(ratio_, ramp_cycles_);
  }
  if (!hold_) {
    // The kernel has handled the stop's event (its next stop lies ahead): plan on.
    if (search_.at_stop() && search_.ready() == 0 && in.stop_mm > tool_mm_) search_.resume();
    // A few front cycles every cycle, so that the front gains on the tool (until the output
    // ring or the window's end stops it) and the search's work is spread over the cycles; it
    // came in bursts when the committed samples ran out (a worst cycle of 1.9 ms on random_2k).
    // When nothing committed waits (the start, a resume, an override change), the search goes
    // on until its lineages coalesce: committing earlier, from a beam a few cycles deep, makes
    // the beam die and the tool brake to rest after frequent override changes (1–7 recoveries on
    // a rounded circle with a restart every 7–64 cycles, none without).
    const int budget = search_.ready() < kLeadSamples ? kCatchUpCyclesPerCycle : 1;
    for (int i = 0; i < budget && search_.advance(false); ++i) {
    }
    while (search_.ready() == 0 && search_.advance(false)) {
    }
    while (search_.ready() == 0 && search_.advance(true)) {
    }
    // Nothing committed and no way on (a failed recovery): the certified brake.
    if (search_.ready() == 0 && !search_.at_stop() && !search_.finished() && started_)
      search_.brake_now();
  }
  AxisVec p;
  std::uint32_t line = 0;
  double s = 0;
  if (search_.ready() > 0 && search_.pop(p, line, s)) {
    // (The first sample is the start position, where the tool already is.)
    step_pc_ = s - tool_mm_;
    tool_mm_ = s;
  } else {
    step_pc_ = 0;
    search_.idle();
  }
}

}  // namespace cncore::motion
