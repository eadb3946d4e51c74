// The G and M codes cncore knows, with their LinuxCNC modal groups. Codes are kept as ten times
// their value (G59.1 → 591) so that decimal codes compare exactly.
//
// Modal groups (at most one word of a group per block; RS274/NGC, LinuxCNC numbering):
//   G group 0  non-modal      G4 G10 G28 G30 G53 G92 G92.1 G92.2 G92.3
//   G group 1  motion         G0 G1 G2 G3 G5 G5.1 G5.2 G5.3 G80 (G33 G38.x G76 unsupported)
//   G group 2  plane          G17 G18 G19
//   G group 3  distance       G90 G91
//   G group 4  arc distance   G90.1 G91.1
//   G group 5  feed mode      G94 (G93 G95 unsupported)
//   G group 6  units          G20 G21
//   G group 7  cutter comp.   G40 G41 G41.1 G42 G42.1
//   G group 8  tool length    G49 (G43 unsupported)
//   G group 10 canned return  G98 G99 (accepted, no effect without canned cycles)
//   G group 12 coordinate sys G54 G55 G56 G57 G58 G59 G59.1 G59.2 G59.3
//   G group 13 path control   G61 G61.1 G64
//   G group 14 spindle mode   G97 (G96 constant surface speed unsupported)
//   G group 15 lathe X mode   G7 (X words are diameters) G8 (radii)
//   G9 (exact stop for one block) is non-modal and belongs to no group.
//   M group 4  stopping       M0 M1 M2 M30 M99
//   M group 6  tool change    M6
//   M group 7  spindle        M3 M4 M5
//   M group 8  coolant        M7 M8 M9 (M7 and M8 may share a block)
//   M group 10 user-defined  M160 M161 direction feed correction on / off (spec 03)
//   M98 (subprogram call) is in a group of its own.
#pragma once

#include <cstdint>
#include <string>

namespace cncore::interp {

enum class GGroup : std::uint8_t {
  kNonModal = 0,
  kMotion = 1,
  kPlane = 2,
  kDistance = 3,
  kArcDistance = 4,
  kFeedMode = 5,
  kUnits = 6,
  kCutterComp = 7,
  kToolLength = 8,
  kCannedReturn = 10,
  kCoordSystem = 12,
  kPathControl = 13,
  kSpindleMode = 14,
  kExactStopOnce = 15,  // G9: cncore's own slot so it combines with anything
  kLatheDiameter = 16,  // G7 G8 (LinuxCNC's group 15)
};
inline constexpr int kGroupSlots = 17;

enum class MGroup : std::uint8_t {
  kStopping = 4,
  kToolChange = 6,
  kSpindle = 7,
  kCoolant = 8,
  kSubprogram = 9,  // M98
  kUser = 10,       // M160 M161 (direction feed correction on / off, spec 03)
};
inline constexpr int kMGroupSlots = 11;

struct CodeInfo {
  bool known = false;      // false: no such code in RS274/NGC
  bool supported = false;  // known but beyond cncore's dialect: error naming `name`
  int group = 0;           // GGroup or MGroup value
  const char* name = "";   // what the code does, for messages
};

CodeInfo g_code_info(int code10);
CodeInfo m_code_info(int code10);

// "G59.1", "M3" from ten times the value.
std::string code_text(char letter, int code10);

}  // namespace cncore::interp
