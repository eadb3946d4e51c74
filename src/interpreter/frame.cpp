// The program's coordinate frame, as LinuxCNC composes it: a program position p (the numbers a
// program writes, in mm) is at the machine position
//   m = R(θ)·(p + g92) + work + tool,
// where work is the active system's offset (G54…G59.3), θ its XY rotation (G10 L2 R, degrees,
// counter-clockwise about Z), g92 the G92/G52 offset while applied and tool the tool length
// offset. R turns X and Y only. G53 moves take machine positions directly.
#include <cmath>
#include <numbers>

#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

namespace {

// (x, y) turned by θ degrees counter-clockwise.
void rotate(double& x, double& y, double deg) {
  if (deg == 0) return;
  const double rad = deg * std::numbers::pi / 180.0;
  const double c = std::cos(rad), s = std::sin(rad);
  const double rx = x * c - y * s;
  y = x * s + y * c;
  x = rx;
}

}  // namespace

double Interpreter::Impl::rotation_deg(int system) const {
  return params_.stored(work_param(system, kRotationSlot));
}

Vec2 Interpreter::Impl::rotated(Vec2 v, double deg) {
  rotate(v.a, v.b, deg);
  return v;
}

AxisVec Interpreter::Impl::g92_offset() const {
  AxisVec g{};
  if (params_.stored(kParamG92Applied) == 0) return g;
  for (std::size_t a = 0; a < kMaxAxes; ++a) g[a] = params_.stored(kParamG92 + static_cast<int>(a));
  return g;
}

AxisVec Interpreter::Impl::to_program(const AxisVec& m, const AxisVec& tool) const {
  AxisVec p;
  for (std::size_t a = 0; a < kMaxAxes; ++a)
    p[a] = m[a] - params_.stored(work_param(modal_.coord_system, a)) - tool[a];
  rotate(p[0], p[1], -rotation_deg(modal_.coord_system));
  const AxisVec g92 = g92_offset();
  for (std::size_t a = 0; a < kMaxAxes; ++a) p[a] -= g92[a];
  return p;
}

AxisVec Interpreter::Impl::from_program(const AxisVec& p) const {
  AxisVec m = p;
  const AxisVec g92 = g92_offset();
  for (std::size_t a = 0; a < kMaxAxes; ++a) m[a] += g92[a];
  rotate(m[0], m[1], rotation_deg(modal_.coord_system));
  for (std::size_t a = 0; a < kMaxAxes; ++a)
    m[a] += params_.stored(work_param(modal_.coord_system, a)) + tool_offset_[a];
  return m;
}

AxisVec Interpreter::Impl::target_from_words(bool machine_coords) const {
  const double unit = modal_.length_unit_mm();
  auto value = [&](std::size_t a) {
    return words_[kAxisWords[a]].value * (is_rotary(a) ? 1.0 : unit);
  };
  AxisVec target = pos_;
  const bool turned = rotation_deg(modal_.coord_system) != 0 && !machine_coords &&
                      (words_.has('x') || words_.has('y'));
  if (turned) {
    // X and Y go through the rotation together: the program position, its words replaced.
    AxisVec p = to_program(pos_, tool_offset_);
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (!words_[kAxisWords[a]].present) continue;
      p[a] = modal_.absolute ? value(a) : p[a] + value(a);
    }
    const AxisVec m = from_program(p);
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (a < 2 || words_[kAxisWords[a]].present) target[a] = m[a];
    }
    return target;
  }
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!words_[kAxisWords[a]].present) continue;
    if (machine_coords) {
      target[a] = value(a);  // G53: the machine position itself, whatever tool offset is active
    } else if (modal_.absolute) {
      target[a] = value(a) + offset(a);  // G90: program coordinate + work offset (+ G92)
    } else {
      target[a] = pos_[a] + value(a);  // G91
    }
  }
  return target;
}

// #5420…#5425 and #<_x>…#<_c>: the position in program coordinates; #5021…#5026 and
// #<_abs_x>…#<_abs_c>: the machine position, where G53 goes (program units).
bool Interpreter::Impl::read_live(int number, double& value) const {
  auto unit = [&](std::size_t a) { return is_rotary(a) ? 1.0 : modal_.length_unit_mm(); };
  if (machine_.parameters_inch && offset_length_param(number)) {
    value = params_.stored(number) / 25.4;
    return true;
  }
  if (number >= kParamPosition && number < kParamPosition + static_cast<int>(kMaxAxes)) {
    const auto axis = static_cast<std::size_t>(number - kParamPosition);
    value = to_program(pos_, tool_offset_)[axis] / unit(axis);
    return true;
  }
  if (number >= kParamMachinePosition &&
      number < kParamMachinePosition + static_cast<int>(kMaxAxes)) {
    const auto axis = static_cast<std::size_t>(number - kParamMachinePosition);
    value = pos_[axis] / unit(axis);
    return true;
  }
  return read_tool_param(number, value);
}

// The X Y Z slots of the G28/G30 homes, the G92 offset and the work offsets: lengths kept in
// mm, read and written by programs in the unit of machine_.parameters_inch.
bool offset_length_param(int n) {
  auto xyz_of = [&](int base) { return n >= base && n < base + 3; };
  if (xyz_of(kParamG28Home) || xyz_of(kParamG30Home) || xyz_of(kParamG92)) return true;
  const int k = n - kParamWorkOffsets;
  return k >= 0 && k < 20 * 9 && k % 20 < 3;
}

bool Interpreter::Impl::read_live_named(std::string_view name, double& value) const {
  // LinuxCNC's #<_lathe_diameter_mode> (1 in G7) and #<_lathe_radius_mode> (1 in G8).
  if (name == "_lathe_diameter_mode" || name == "_lathe_radius_mode") {
    value = modal_.diameter_mode == (name == "_lathe_diameter_mode") ? 1 : 0;
    return true;
  }
  if (read_modal_named(name, value)) return true;
  const bool abs = name.starts_with("_abs_");
  const std::string_view axis = name.substr(abs ? 5 : 1);
  if (!name.starts_with('_') || axis.size() != 1) return false;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (axis[0] == kAxisWords[a]) {
      return read_live((abs ? kParamMachinePosition : kParamPosition) + static_cast<int>(a), value);
    }
  }
  return false;
}

CanonFrame Interpreter::Impl::canon_frame() const {
  CanonFrame f;
  f.unit_mm = modal_.length_unit_mm();
  f.tool_offset_mm = tool_offset_;
  for (std::size_t a = 0; a < kMaxAxes; ++a)
    f.work_offset_mm[a] = params_.stored(work_param(modal_.coord_system, a));
  f.g92_offset_mm = g92_offset();
  f.rotation_deg = rotation_deg(modal_.coord_system);
  return f;
}

}  // namespace cncore::interp
