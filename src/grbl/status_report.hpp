// Grbl 1.1's real-time status report `<State|MPos:…|FS:…|…>` from the controller's status.
#pragma once

#include <cstdint>
#include <string>

#include "config/machine_config.hpp"
#include "runtime/control.hpp"

namespace cncore::grbl {

// What the report needs beyond runtime::Status: the connection's own state.
struct ReportInputs {
  bool door = false;       // safety door opened (0x84), not yet resumed
  bool sleep = false;      // $SLP
  std::uint32_t mask = 1;  // $10: bit 0 MPos (else WPos), bit 1 Bf:
  int planner_blocks_free = 15;
  int rx_bytes_free = 128;
  std::uint32_t line = 0;  // Ln: (0: left out)
  int spindle_override_pct = 100;
  bool with_wco = false;        // WCO: is sent now and then and when it changes, as Grbl does
  bool with_overrides = false;  // Ov: likewise
};

// "Idle", "Run", "Hold:0" (stopped) / "Hold:1" (decelerating), "Jog", "Alarm", "Door:0" /
// "Door:2" (stopping), "Check", "Home", "Sleep".
std::string state_text(const runtime::Status& s, const ReportInputs& in);

std::string status_report(const runtime::Status& s, const MachineConfig& machine,
                          const ReportInputs& in);

// `[PRB:x,y,z:t]`: where the last probe move ended (machine coordinates) and whether it
// tripped, as Grbl reports after G38.x and in `$#`.
std::string probe_report(const AxisVec& machine_mm, bool tripped, const MachineConfig& machine);

// `$G`'s `[GC:…]` line: motion, coordinate system, plane, units, distance and feed modes, spindle,
// coolant, tool, F (in program units per minute, or per revolution in G95) and S, as Grbl 1.1
// orders them. The G words and F, S, T are the parser's (`parser`); spindle and coolant are the
// machine's (`s`), which the interpreter's modal state does not hold.
std::string gcode_modes(const interp::ModalState& parser, const runtime::Status& s);

}  // namespace cncore::grbl
