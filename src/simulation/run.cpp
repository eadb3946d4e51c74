#include "simulation/run.hpp"

#include <algorithm>
#include <exception>
#include <stdexcept>

#include "core/error.hpp"
#include "feedcontrol/direction_correction.hpp"

namespace cncore::sim {

namespace {

bool is_motion(const Block& b) {
  return b.kind == BlockKind::kRapid || b.kind == BlockKind::kLine || b.kind == BlockKind::kArc;
}

}  // namespace

RunCounts run_program(const std::string& program_path, const MachineConfig& machine,
                      const RunOptions& options, std::vector<SampleObserver*> observers) {
  interp::Interpreter interpreter(program_path, machine, options.interpreter);
  motion::Kernel kernel(machine, options.kernel);
  RunCounts counts;
  motion::Sample sample;
  std::size_t next_step = 0;  // next override step to apply (steps sorted by time)
  std::vector<std::pair<double, double>> steps = options.override_steps;
  std::stable_sort(steps.begin(), steps.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });

  // Stall watchdog: a kernel that stops moving for good (a bug) would hang the run forever.
  // Standing still is legitimate during a dwell and while the override is 0, so the limit is
  // the longest dwell seen so far plus 60 s of simulated time.
  double override_now = options.kernel.override_pct;
  double override_set = override_now;  // what the kernel runs (the cycle controller's output)
  double longest_dwell_s = 0;
  std::uint64_t still_cycles = 0;
  AxisVec last_position;
  auto deliver = [&](const motion::Sample& s) {
    if (counts.cycles > 0 && s.position == last_position && override_now > 0) {
      if (++still_cycles * machine.period_s > longest_dwell_s + 60) {
        if (options.cycle_controller != nullptr && override_set <= 0) {
          // Not a kernel fault: the controller holds the feed at 0 and its load never falls
          // (a recorded load does not follow the feed).
          throw InputError(program_path, s.line, 1,
                           "adaptive feed control has held the feed override at 0 % for 60 s: "
                           "the measured load never fell below adaptive.threshold_pct (a "
                           "recorded load does not follow the feed); set adaptive.lower_pct "
                           "above 0, or an antiwindup policy other than \"none\"");
        }
        throw std::runtime_error("motion kernel stalled: no motion for " +
                                 std::to_string(still_cycles) + " cycles at line " +
                                 std::to_string(s.line) + ", t = " + std::to_string(s.t_s) + " s");
      }
    } else {
      still_cycles = 0;
    }
    last_position = s.position;
    ++counts.cycles;
    for (SampleObserver* o : observers) o->on_sample(s);
  };
  // One interpolation period. The k-th sample (k = 0, 1, ...) has t = k·τ; an override step at
  // time T is set before the first cycle with t >= T, since set_override acts on the next cycle.
  auto step = [&]() -> bool {
    const double t_next = static_cast<double>(counts.cycles) * machine.period_s;
    while (next_step < steps.size() && t_next >= steps[next_step].first - 1e-9) {
      if (options.cycle_controller == nullptr) kernel.set_override(steps[next_step].second);
      override_now = steps[next_step].second;
      ++next_step;
    }
    if (!kernel.step(sample)) return false;
    if (options.cycle_controller != nullptr) {
      override_set = options.cycle_controller->on_cycle(sample, override_now);
      kernel.set_override(override_set);
    }
    deliver(sample);
    return true;
  };

  bool more = true;  // the interpreter may still produce blocks
  Block source;      // interpreted block
  Block block;       // what the kernel gets: the direction-correction stage's output (spec 03)
  feed::DirectionCorrector corrector(machine, program_path);
  while (true) {
    // Stream: read blocks only while the execution-data buffer has room, so memory stays
    // bounded by the buffer whatever the program length. One interpreted block may give
    // several kernel blocks (an arc split by the direction correction), one at a time.
    while (kernel.wants_block()) {
      bool got = false;
      try {
        got = corrector.next(block);
        if (!got && more) {
          more = interpreter.next(source);
          if (more) {
            if (is_motion(source)) ++counts.blocks;
            if (source.kind == BlockKind::kDwell)
              longest_dwell_s = std::max(longest_dwell_s, source.dwell_s);
            corrector.put(source);
            continue;
          }
        }
      } catch (const InputError&) {
        // Stop at the end of the last good block: the samples up to there are delivered, then
        // the error goes on to the caller (which discards its output files).
        const std::exception_ptr error = std::current_exception();
        kernel.end_of_program();
        while (step()) {
        }
        std::rethrow_exception(error);
      }
      if (!got) {
        if (!more) kernel.end_of_program();
        break;
      }
      for (SampleObserver* o : observers) o->on_block(block);
      kernel.push(block);
    }
    if (!step()) {
      if (more) {
        // The kernel contract: step() returns false only after end_of_program().
        throw std::logic_error("motion kernel stopped before the end of the program");
      }
      break;
    }
  }
  for (SampleObserver* o : observers) o->on_finish();
  return counts;
}

}  // namespace cncore::sim
