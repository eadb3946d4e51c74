// The modal state of the interpreter: everything a program sets once and that stays in force
// until changed. Internally every length is mm and every position machine coordinates; the
// program's units (G20/G21) only scale the numbers as they are read.
#pragma once

#include <array>
#include <cstdint>

#include "core/block.hpp"
#include "interpreter/arcs.hpp"

namespace cncore::interp {

// G80 G0 G1 G2 G3, a canned cycle (G73 G74 G81…G89: ModalState::cycle holds which), and the
// splines G5 (cubic), G5.1 (quadratic), G5.2 (a NURBS being defined, until G5.3), and the
// straight probe G38.2…G38.5 (ModalState::probe_code).
enum class Motion : std::uint8_t {
  kNone,
  kRapid,
  kLine,
  kArcCw,
  kArcCcw,
  kCycle,
  kCubicSpline,
  kQuadSpline,
  kNurbs,
  kProbe,
  kSpindleSync,  // G33
  kRigidTap,     // G33.1
};

// Group 5: what F means. G93: the move takes 1/F minutes (an F on every feed move's line);
// G94: mm (or inch) per minute; G95: mm (or inch) per spindle revolution, at the last S.
enum class FeedMode : std::uint8_t { kInverseTime, kPerMinute, kPerRevolution };

struct ModalState {
  Motion motion = Motion::kNone;          // group 1 (LinuxCNC starts in G80)
  Plane plane = Plane::kXY;               // group 2: G17
  bool absolute = true;                   // group 3: G90 (false: G91)
  bool arc_absolute = false;              // group 4: G91.1 (true: G90.1)
  bool inch = false;                      // group 6: G21 (true: G20)
  int coord_system = 1;                   // group 12: 1 = G54 … 6 = G59, 7…9 = G59.1…G59.3
  PathMode path_mode = PathMode::kBlend;  // group 13: G64
  double tolerance_mm = -1;               // G64 P (mm); < 0: none given
  double smooth_tolerance_mm = -1;        // G64 Q (mm); < 0: none given

  // Canned cycles: the cycle (ten times its G number), group 10 (G98: retract to the start
  // height, G99: to R), and the words that stay in force from one cycle block to the next, as
  // written (program units; R and Z relative in G91).
  int cycle = 0;
  int probe_code = 382;  // kProbe: G38.2 … G38.5 as 382 … 385
  bool retract_to_r = false;
  double cycle_r = 0, cycle_z = 0, cycle_p = 0, cycle_q = 0;
  // G87: I J K as written (the offsets of the entry point in the plane's axes, the top of the
  // back bore along the drill axis), in force for the next G87 blocks.
  std::array<double, 3> cycle_ijk{};
  bool cycle_r_set = false, cycle_z_set = false;
  // LinuxCNC's initial level: the drill-axis position (machine mm) before the first cycle block
  // of a series (until the motion mode changes). G98 returns to it; in G91, R counts from it.
  double cycle_initial_mm = 0;
  bool cycle_initial_set = false;

  FeedMode feed_mode = FeedMode::kPerMinute;  // group 5: G94
  double feed_mm_min = 0;                     // F in G94, converted to mm/min when it is read
  double feed_mm_rev = 0;                     // F in G95, mm per spindle revolution
  bool feed_set = false;                      // an F word has been seen in the current feed mode
  double spindle_rpm = 0;                     // the spindle speed: the last S word in G97
  int spindle_dir = 0;                        // M3: 1, M4: −1, M5: 0
  // G96 constant surface speed (group 14; false: G97): the spindle turns at
  // rpm = css_mm_min / (2π·|X|) at the tool's work X, at most css_max_rpm (D; 0: no D).
  bool css = false;
  double css_mm_min = 0;  // surface speed, mm/min (S m/min · 1000 or S ft/min · 304.8)
  double css_max_rpm = 0;
  int tool = 0;                // T of the last M6 (tool in the spindle)
  int tool_length_code = 490;  // group 8: G49 (430 G43, 431 G43.1, 432 G43.2)
  bool diameter_mode = false;  // group 15: G8 (true: G7, X words are diameters)

  double length_unit_mm() const { return inch ? 25.4 : 1.0; }
};

}  // namespace cncore::interp
