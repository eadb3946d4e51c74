// libFuzzer target: the G-code interpreter on arbitrary program text, run with next() to the
// end on the built-in machine. Bad input must end in InputError; any other exception, a crash,
// a sanitizer report or a non-finite coordinate in a block is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"

namespace {

// Blocks interpreted per input at most: nested loops can legitimately produce 10^12 blocks,
// which is a slow input, not a bug. 200 000 blocks take well under a second.
constexpr std::uint64_t kMaxBlocks = 200000;

const cncore::MachineConfig& machine() {
  static const cncore::MachineConfig m = [] {
    cncore::MachineConfig c = cncore::default_machine_config();
    // The runaway-loop guard: the default (10^6 iterations) makes one input take seconds; a
    // smaller guard keeps the fuzzer fast and still exercises the guard's error path.
    c.max_loop_iterations = 10000;
    return c;
  }();
  return m;
}

bool finite(const cncore::AxisVec& v) {
  for (double x : v.v) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    cncore::interp::Interpreter in(cncore::interp::Interpreter::FromText{}, std::move(text),
                                   "fuzz.ngc", machine(), cncore::interp::Options{});
    cncore::Block b;
    for (std::uint64_t n = 0; n < kMaxBlocks && in.next(b); ++n) {
      // The planner divides by lengths and radii: a block must never carry NaN or infinity.
      const bool motion = b.kind == cncore::BlockKind::kRapid ||
                          b.kind == cncore::BlockKind::kLine || b.kind == cncore::BlockKind::kArc;
      if (motion && (!finite(b.start) || !finite(b.end) || !std::isfinite(b.feed_mm_min)))
        std::abort();
      if (b.kind == cncore::BlockKind::kArc &&
          (!std::isfinite(b.center.x) || !std::isfinite(b.center.y) || !std::isfinite(b.center.z)))
        std::abort();
      if (b.kind == cncore::BlockKind::kDwell && !(b.dwell_s >= 0 && std::isfinite(b.dwell_s)))
        std::abort();
      (void)cncore::interp::format_block(b, machine());
    }
  } catch (const cncore::InputError& e) {
    (void)e.formatted();
  }
  return 0;
}
