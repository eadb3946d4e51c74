// libFuzzer target: the whole simulated machine (interpreter → look-ahead planner → motion
// cycle) on arbitrary program text, on the built-in machine. Findings: a crash or sanitizer
// report, an exception other than InputError, a non-finite sample, a kernel that stands still
// for 2 s of machine time without a dwell (a stall), and a run that ends anywhere but at the
// end point of the last motion block (spec 01 P4, ≤ 1e-6 mm here).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"
#include "motion/kernel.hpp"

namespace {

// Cycles per input at most (10 s of machine time at 1 ms): longer runs are slow inputs.
constexpr std::uint64_t kMaxCycles = 10000;
// Standing still longer than this (plus the longest dwell) is a stall: nothing else in a run
// on this machine (override 100 %, no feed hold) stops the tool for long. run_program allows
// 60 s; 2 s keeps the check inside kMaxCycles.
constexpr double kStallS = 2;

const cncore::MachineConfig& machine() {
  static const cncore::MachineConfig m = [] {
    cncore::MachineConfig c = cncore::default_machine_config();
    c.max_loop_iterations = 1000;  // keep one input fast (see fuzz_interpreter.cpp)
    // A short execution-data buffer: building the default 10 000-block one costs ~0.3 s per
    // input under the sanitizers, and a full buffer is a path worth exercising.
    c.lookahead_blocks = 64;
    return c;
  }();
  return m;
}

[[noreturn]] void finding(const char* what, const cncore::motion::Sample& s) {
  std::fprintf(stderr, "finding: %s at t = %.6f s, line %u, X %.9g Y %.9g Z %.9g\n", what, s.t_s,
               s.line, s.position[cncore::kX], s.position[cncore::kY], s.position[cncore::kZ]);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  const cncore::MachineConfig& m = machine();
  cncore::interp::Interpreter in(cncore::interp::Interpreter::FromText{}, std::move(text),
                                 "fuzz.ngc", m, cncore::interp::Options{});
  cncore::motion::Kernel kernel(m, cncore::motion::KernelOptions{});
  cncore::AxisVec end;  // where the machine must stop: the last motion block's end
  for (std::size_t a = 0; a < cncore::kMaxAxes; ++a) end[a] = m.start_position[a];
  bool more = true;
  double longest_dwell_s = 0;
  std::uint64_t cycles = 0, still = 0;
  cncore::motion::Sample s, prev;
  cncore::Block b;
  for (;;) {
    while (more && kernel.wants_block()) {
      try {
        more = in.next(b);
      } catch (const cncore::InputError&) {
        more = false;  // stop at the end of the last good block, as run_program does
      }
      if (!more) {
        kernel.end_of_program();
        break;
      }
      if (cncore::is_motion(b)) end = b.end;
      if (b.kind == cncore::BlockKind::kDwell)
        longest_dwell_s = std::max(longest_dwell_s, b.dwell_s);
      kernel.push(b);
    }
    if (!kernel.step(s)) {
      if (more) finding("step() returned false before the end of the program", prev);
      break;
    }
    for (std::size_t a = 0; a < cncore::kMaxAxes; ++a) {
      if (!std::isfinite(s.position[a]) || !std::isfinite(s.path_position[a]))
        finding("non-finite position", s);
    }
    if (!std::isfinite(s.feed_mm_min)) finding("non-finite feed", s);
    if (cycles > 0 && s.position == prev.position) {
      if (++still * m.period_s > longest_dwell_s + kStallS) finding("kernel stalled", s);
    } else {
      still = 0;
    }
    prev = s;
    if (++cycles >= kMaxCycles) return 0;
  }
  for (std::size_t a = 0; a < cncore::kMaxAxes; ++a) {
    if (cycles > 0 && std::abs(prev.position[a] - end[a]) > 1e-6)
      finding("the run ended away from the last block's end point", prev);
  }
  return 0;
}
