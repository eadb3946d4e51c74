// The interface between the interpreter and the planner: one interpreted block of the part
// program, in machine coordinates and mm (rotary axes in degrees), with its source line.
// The interpreter knows nothing about time; the planner knows nothing about G-code syntax.
#pragma once

#include <cstdint>
#include <limits>

#include "core/geometry.hpp"

namespace cncore {

enum class BlockKind : std::uint8_t {
  kRapid,  // G0: straight line at the machine's rapid rate
  kLine,   // G1: straight line at the programmed feed
  kArc,    // G2/G3: circular arc or helix
  kDwell,  // G4: stop and wait dwell_s
  kAux,    // M, S or T event (no motion)
};

// How the tool passes the end of a motion block (G61, G61.1, G64, G9).
enum class PathMode : std::uint8_t {
  kBlend,      // G64: keep moving; corners may round within tolerance_mm
  kExactPath,  // G61: follow the programmed path exactly, no rounding, no forced stop
  kExactStop,  // G61.1 or G9 (one block): speed 0 at the end of the block
};

// The two moves of a G33.1 rigid tap (one RIGID_TAP call in LinuxCNC's canonical listing).
enum class RigidTap : std::uint8_t { kNone, kIn, kOut };

struct Block {
  BlockKind kind = BlockKind::kLine;
  std::uint32_t line = 0;  // source line, 1-based
  std::uint32_t col = 0;   // column of the first word of the block, 1-based
  // A line merged from collinear pieces (planner/line_merge.hpp): the source line of its last
  // piece (`line` is its first's). 0: the block is one source block.
  std::uint32_t last_line = 0;
  // A merged line: the number of programmed pieces it was merged from. They follow it, each a
  // Block with `piece` set, so that observers and the kernel's line attribution see the program
  // as written (the planner plans the merged line only). 0: not merged.
  std::uint32_t pieces = 0;
  bool piece = false;  // one programmed piece of the merged line before it
  // A merged line: the unit directions of its first and last pieces (zero: not merged). The
  // corners at its ends are the pieces' corners; the planner passes them no faster than those.
  Vec3 first_piece_dir, last_piece_dir;

  // Motion (kRapid, kLine, kArc). start equals the previous motion block's end.
  AxisVec start;
  AxisVec end;
  double feed_mm_min = 0;  // programmed path feed (converted to mm/min); 0 for kRapid
  PathMode path_mode = PathMode::kBlend;
  double tolerance_mm = -1;  // G64 P value; < 0: the machine's contour tolerance
  // G64 Q value: G1 chords within it of one curve run as that curve (planner/path_smoother.hpp);
  // 0: off; < 0: the machine's smooth_tolerance_mm.
  double smooth_tolerance_mm = -1;
  // Direction feed correction (spec 03), set by the stage between interpreter and planner
  // (src/feedcontrol/direction_correction): the coefficient C already applied to feed_mm_min
  // (NaN: no correction stage; 1: a move it leaves alone, e.g. G0), and whether the operator's
  // override is ignored on this move (override mode "replace": the speed is F·C alone).
  double correction = std::numeric_limits<double>::quiet_NaN();
  bool override_fixed = false;
  // Spindle-synchronised motion (G33, G33.1, G76): the path advances sync_mm_rev per spindle
  // revolution, so feed_mm_min = sync_mm_rev · rpm and override_fixed is set (the feed override
  // does not act, as in LinuxCNC). 0: a move at its programmed feed.
  double sync_mm_rev = 0;
  // G33 / G76 D: the spindle angle past its index (degrees, >= 0) at which the synchronised
  // move starts; NaN: none programmed (the index itself).
  double sync_start_deg = std::numeric_limits<double>::quiet_NaN();
  RigidTap rigid_tap = RigidTap::kNone;

  // Arc / helix (kArc). The motion turns counter-clockwise about `normal` (right-hand rule):
  // G3 in G17 has normal +Z, G2 in G17 has -Z; G18 uses ±Y, G19 uses ±X.
  // `center` is the centre projected into the plane of the start point; the displacement
  // along `normal` from start to end is the helix rise. Other axes move linearly.
  Vec3 center;
  Vec3 normal{0, 0, 1};
  std::uint32_t turns = 0;  // extra full turns (P word minus one)

  // kDwell
  double dwell_s = 0;
  // A zero dwell that waits for the spindle's index pulse before synchronised moves (not a G4 of
  // the program; below LinuxCNC's canonical interface).
  bool index_wait = false;

  // kAux: letter 'M', 'S' or 'T' with its value (M6 → 'M', 6; S12000 → 'S', 12000).
  char aux_letter = 0;
  double aux_value = 0;
  // The event's P word where it carries one (M52 P1 / M52 P0: adaptive feed on / off); 0 else.
  double aux_p = 0;
  bool aux_waits = false;  // the motion must come to a stop before the event (M0, M1, M6, ...)
};

// G0, G1, G2/G3: the blocks that move the tool (and that the summary counts).
inline bool is_motion(const Block& b) {
  return b.kind == BlockKind::kRapid || b.kind == BlockKind::kLine || b.kind == BlockKind::kArc;
}

}  // namespace cncore
