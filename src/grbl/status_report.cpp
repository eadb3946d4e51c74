#include "grbl/status_report.hpp"

#include <fmt/format.h>

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
  r += fmt::format("|FS:{:.0f},0", s.feed_mm_min);
  if (in.with_overrides) {
    r += fmt::format("|Ov:{:.0f},{:.0f},{}", s.feed_override_pct, s.rapid_override_pct,
                     in.spindle_override_pct);
  }
  if (in.with_wco) r += "|WCO:" + axes_text(s.work_offset, m);
  return r + ">";
}

}  // namespace cncore::grbl
