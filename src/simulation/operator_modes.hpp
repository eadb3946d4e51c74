// Operator modes of a run (spec 01, "beyond the seed"): dry run and single-block stop. They act
// on each interpreted block, before the direction correction, the merge and the kernel, so
// every limit of the look-ahead holds as for a program written that way.
#pragma once

#include "core/block.hpp"

namespace cncore::sim {

struct OperatorModes {
  // Dry run: every feed move (G1 G2 G3) at this feed instead of its F, mm/min (0: off). Rapids
  // keep the rapid rate; the override and the direction correction apply as they would to F.
  double dry_run_feed_mm_min = 0;
  // Single-block stop: the tool stops at the end of every motion block (as G9 would), then waits
  // single_block_wait_s (the operator's cycle start; 0: at once) before the next one.
  bool single_block = false;
  double single_block_wait_s = 0;
};

// Applies the modes to interpreted block `b`. Returns true when a wait must follow it: `wait`
// is then the dwell block to hand on next.
inline bool apply_operator_modes(const OperatorModes& m, Block& b, Block& wait) {
  if (!is_motion(b)) return false;
  if (m.dry_run_feed_mm_min > 0 && b.kind != BlockKind::kRapid)
    b.feed_mm_min = m.dry_run_feed_mm_min;
  if (!m.single_block) return false;
  b.path_mode = PathMode::kExactStop;
  b.tolerance_mm = -1;  // (as the interpreter writes a G9 block)
  if (!(m.single_block_wait_s > 0)) return false;
  wait = Block{};
  wait.kind = BlockKind::kDwell;
  wait.line = b.line;
  wait.col = b.col;
  wait.start = wait.end = b.end;
  wait.dwell_s = m.single_block_wait_s;
  return true;
}

}  // namespace cncore::sim
