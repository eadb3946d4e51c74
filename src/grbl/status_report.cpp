#include "grbl/status_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace cncore::grbl {

namespace {

std::string axes_text(const AxisVec& v, const MachineConfig& m) {
  std::string r;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!m.axes[a].enabled) continue;
    if (!r.empty()) r += ',';
    r += fmt::format("{:.3f}", v[a]);
  }
  return r;
}

}  // namespace

std::string probe_report(const AxisVec& machine_mm, bool tripped, const MachineConfig& machine) {
  return fmt::format("[PRB:{}:{}]", axes_text(machine_mm, machine), tripped ? 1 : 0);
}

std::string state_text(const runtime::Status& s, const ReportInputs& in) {
  using runtime::MachineState;
  if (in.sleep) return "Sleep";
  if (s.state == MachineState::kAlarm) return "Alarm";
  if (in.door) return s.state == MachineState::kHold && !s.hold_complete ? "Door:2" : "Door:0";
  switch (s.state) {
    case MachineState::kIdle:
      return s.resetting ? "Run" : "Idle";
    case MachineState::kRun:
      return "Run";
    case MachineState::kHold:
      return s.hold_complete ? "Hold:0" : "Hold:1";
    case MachineState::kJog:
      return "Jog";
    case MachineState::kHoming:
      return "Home";
    case MachineState::kCheck:
      return "Check";
    case MachineState::kAlarm:
      return "Alarm";
  }
  return "Idle";
}

std::string status_report(const runtime::Status& s, const MachineConfig& m,
                          const ReportInputs& in) {
  std::string r = "<" + state_text(s, in);
  const bool machine_pos = (in.mask & 1U) != 0;
  AxisVec pos = s.commanded;
  if (!machine_pos) {
    for (std::size_t a = 0; a < kMaxAxes; ++a) pos[a] -= s.work_offset[a];
  }
  r += fmt::format("|{}:{}", machine_pos ? "MPos" : "WPos", axes_text(pos, m));
  if ((in.mask & 2U) != 0) r += fmt::format("|Bf:{},{}", in.planner_blocks_free, in.rx_bytes_free);
  if (in.line != 0) r += fmt::format("|Ln:{}", in.line);
  r += fmt::format("|FS:{:.0f},{:.0f}", s.feed_mm_min, s.spindle_on ? s.spindle_rpm : 0.0);
  if (in.with_overrides) {
    r += fmt::format("|Ov:{:.0f},{:.0f},{}", s.feed_override_pct, s.rapid_override_pct,
                     in.spindle_override_pct);
    // Accessories, sent with Ov: and left out when none is on (Grbl 1.1).
    std::string a;
    if (s.spindle_on) a += s.spindle_ccw ? 'C' : 'S';
    if (s.coolant_flood) a += 'F';
    if (s.coolant_mist) a += 'M';
    if (!a.empty()) r += "|A:" + a;
  }
  if (in.with_wco) r += "|WCO:" + axes_text(s.work_offset, m);
  return r + ">";
}

namespace {

std::string motion_word(const interp::ModalState& p) {
  switch (p.motion) {
    case interp::Motion::kRapid:
      return "G0";
    case interp::Motion::kLine:
      return "G1";
    case interp::Motion::kArcCw:
      return "G2";
    case interp::Motion::kArcCcw:
      return "G3";
    case interp::Motion::kCycle:
      return fmt::format("G{}", p.cycle / 10);
    case interp::Motion::kProbe:
      return fmt::format("G38.{}", p.probe_code - 380);
    case interp::Motion::kCubicSpline:
      return "G5";
    case interp::Motion::kQuadSpline:
      return "G5.1";
    case interp::Motion::kNurbs:
      return "G5.2";
    case interp::Motion::kSpindleSync:
      return "G33";
    case interp::Motion::kRigidTap:
      return "G33.1";
    case interp::Motion::kNone:
      break;
  }
  return "G80";
}

std::string coord_word(int system) {
  if (system >= 7 && system <= 9) return fmt::format("G59.{}", system - 6);
  return fmt::format("G{}", 53 + std::clamp(system, 1, 6));
}

}  // namespace

std::string gcode_modes(const interp::ModalState& p, const runtime::Status& s) {
  const char* plane = p.plane == interp::Plane::kXY   ? "G17"
                      : p.plane == interp::Plane::kZX ? "G18"
                                                      : "G19";
  const char* feed_mode = p.feed_mode == interp::FeedMode::kInverseTime     ? "G93"
                          : p.feed_mode == interp::FeedMode::kPerRevolution ? "G95"
                                                                            : "G94";
  std::string coolant;
  if (s.coolant_mist) coolant += " M7";
  if (s.coolant_flood) coolant += " M8";
  if (coolant.empty()) coolant = " M9";
  // F as the program writes it: per minute or per revolution, in its units.
  const double unit = p.length_unit_mm();
  const double f = p.feed_mode == interp::FeedMode::kPerRevolution ? p.feed_mm_rev / unit
                   : p.feed_mode == interp::FeedMode::kPerMinute   ? p.feed_mm_min / unit
                                                                   : 0.0;
  return fmt::format("[GC:{} {} {} {} {} {} {}{} T{} F{:g} S{:g}]", motion_word(p),
                     coord_word(p.coord_system), plane, p.inch ? "G20" : "G21",
                     p.absolute ? "G90" : "G91", feed_mode,
                     !s.spindle_on   ? "M5"
                     : s.spindle_ccw ? "M4"
                                     : "M3",
                     coolant, p.tool, std::round(f * 1000) / 1000, p.spindle_rpm);
}

}  // namespace cncore::grbl
