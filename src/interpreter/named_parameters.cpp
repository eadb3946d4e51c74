// LinuxCNC's predefined named parameters that read the interpreter's modal state: #<_line>,
// #<_motion_mode>, #<_plane>, #<_metric> … (docs/gcode.md, *Parameters*). G codes read as ten
// times their number (G38.2: 382, G59.1: 591); flags read 1 or 0.
#include <string_view>
#include <utility>

#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

namespace {

int motion_code(const ModalState& m) {
  switch (m.motion) {
    case Motion::kNone:
      return 800;
    case Motion::kRapid:
      return 0;
    case Motion::kLine:
      return 10;
    case Motion::kArcCw:
      return 20;
    case Motion::kArcCcw:
      return 30;
    case Motion::kCycle:
      return m.cycle;
    case Motion::kCubicSpline:
      return 50;
    case Motion::kQuadSpline:
      return 51;
    case Motion::kNurbs:
      return 52;
    case Motion::kProbe:
      return m.probe_code;
    case Motion::kSpindleSync:
      return 330;
    case Motion::kRigidTap:
      return 331;
  }
  return 800;
}

int plane_code(Plane p) {
  return p == Plane::kXY ? 170 : p == Plane::kZX ? 180 : 190;
}

// G54 … G59: 540 … 590; G59.1 … G59.3: 591 … 593.
int coord_system_code(int system) {
  return system <= 6 ? 530 + 10 * system : 584 + system;
}

}  // namespace

bool Interpreter::Impl::read_modal_named(std::string_view name, double& value) const {
  const ModalState& m = modal_;
  const double unit = m.length_unit_mm();
  const double feed = m.feed_mode == FeedMode::kPerMinute       ? m.feed_mm_min / unit
                      : m.feed_mode == FeedMode::kPerRevolution ? m.feed_mm_rev / unit
                                                                : 0.0;
  auto num = [](auto v) { return static_cast<double>(v); };
  const std::pair<std::string_view, double> table[] = {
      {"_line", num(ctx_.line)},
      {"_motion_mode", num(motion_code(m))},
      {"_plane", num(plane_code(m.plane))},
      {"_ccomp", num(comp_code_)},
      {"_metric", num(m.inch ? 0 : 1)},
      {"_imperial", num(m.inch ? 1 : 0)},
      {"_absolute", num(m.absolute ? 1 : 0)},
      {"_incremental", num(m.absolute ? 0 : 1)},
      {"_inverse_time", num(m.feed_mode == FeedMode::kInverseTime ? 1 : 0)},
      {"_units_per_minute", num(m.feed_mode == FeedMode::kPerMinute ? 1 : 0)},
      {"_units_per_rev", num(m.feed_mode == FeedMode::kPerRevolution ? 1 : 0)},
      {"_coord_system", num(coord_system_code(m.coord_system))},
      {"_tool_offset", num(m.tool_length_code == 490 ? 0 : 1)},
      {"_retract_r_plane", num(m.retract_to_r ? 1 : 0)},
      {"_retract_old_z", num(m.retract_to_r ? 0 : 1)},
      {"_spindle_rpm_mode", num(m.css ? 0 : 1)},
      {"_spindle_css_mode", num(m.css ? 1 : 0)},
      {"_ijk_absolute_mode", num(m.arc_absolute ? 1 : 0)},
      {"_spindle_on", num(m.spindle_dir != 0 ? 1 : 0)},
      {"_spindle_cw", num(m.spindle_dir > 0 ? 1 : 0)},
      {"_feed", feed},
      {"_rpm", num(m.spindle_rpm)},
      {"_current_tool", num(m.tool)},
      {"_selected_tool", num(selected_tool_)},
      {"_call_level", num(frames_.size())},
  };
  for (const auto& [key, v] : table) {
    if (key == name) {
      value = v;
      return true;
    }
  }
  return false;
}

}  // namespace cncore::interp
