// Coordinate systems: the active work offset (G54…G59.3 + G92), G10 L2/L20, the G92 family and
// G28/G30 homing. Offsets are kept in LinuxCNC's parameters (#5211…, #5221…), in mm.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

double Interpreter::Impl::offset(std::size_t axis) const {
  double off = params_.stored(work_param(modal_.coord_system, axis));
  if (params_.stored(kParamG92Applied) != 0)
    off += params_.stored(kParamG92 + static_cast<int>(axis));
  return off + tool_offset_[axis];
}

void Interpreter::Impl::set_offsets() {
  const Words& w = words_;
  const Words::Code* g = w.group(GGroup::kNonModal);
  const double unit = modal_.length_unit_mm();
  auto scaled = [&](std::size_t a) { return w[kAxisWords[a]].value * (is_rotary(a) ? 1.0 : unit); };
  switch (g->code10) {
    case 100: {
      if (!w.has('l')) fail(g->col, "G10 without L");
      const double l = w['l'].value;
      if (l == 1 || l == 10 || l == 11) {
        set_tool_data(static_cast<int>(l));
        break;
      }
      if (l != 2 && l != 20) fail(w['l'].col, fmt::format("G10 L{}: unknown G10 form", l));
      if (!w.has('p')) fail(g->col, "G10 L2/L20 without P (coordinate system 0…9)");
      const double p = w['p'].value;
      if (p < 0 || p > 9 || p != std::floor(p)) fail(w['p'].col, "G10 P must be 0…9");
      set_work_offset(p == 0 ? modal_.coord_system : static_cast<int>(p), l == 20);
      break;
    }
    case 520:
      // G52: a local offset of the active system. LinuxCNC keeps it in the G92 registers; the
      // values are the offset itself (G90/G91 do not apply), G52 X0 Y0 … clears it.
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        if (w[kAxisWords[a]].present)
          params_.set_numbered(kParamG92 + static_cast<int>(a), scaled(a));
      }
      params_.set_numbered(kParamG92Applied, 1);
      break;
    case 920: {
      bool any = false;
      // G92: the offset that makes the current position read the words, for the named axes:
      // m = R(θ)·(value + g92) + work + tool  →  g92 = R(−θ)·(m − work − tool) − value.
      params_.set_numbered(kParamG92Applied, 0);
      const AxisVec unshifted = to_program(pos_, tool_offset_);
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        if (!w[kAxisWords[a]].present) continue;
        any = true;
        params_.set_numbered(kParamG92 + static_cast<int>(a), unshifted[a] - scaled(a));
      }
      if (!any) fail(g->col, "G92 without axis words");
      params_.set_numbered(kParamG92Applied, 1);
      break;
    }
    case 921:
      for (std::size_t a = 0; a < kMaxAxes; ++a)
        params_.set_numbered(kParamG92 + static_cast<int>(a), 0);
      params_.set_numbered(kParamG92Applied, 0);
      break;
    case 922:
      params_.set_numbered(kParamG92Applied, 0);
      break;
    case 923:
      params_.set_numbered(kParamG92Applied, 1);
      break;
    default:
      break;
  }
}

// G10 L2 (the offset itself) or L20 (the offset that makes the current position read the
// words) of `system`, with R its XY rotation (degrees). L20 keeps the current reading of the
// axes it does not name: m = R(θ)·(p + g92) + work + tool  →  work = m − tool − R(θ)·(p + g92).
void Interpreter::Impl::set_work_offset(int system, bool l20) {
  const Words& w = words_;
  const double unit = modal_.length_unit_mm();
  auto scaled = [&](std::size_t a) { return w[kAxisWords[a]].value * (is_rotary(a) ? 1.0 : unit); };
  if (!l20) {
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (w[kAxisWords[a]].present) params_.set_numbered(work_param(system, a), scaled(a));
    }
    if (w.has('r')) params_.set_numbered(work_param(system, kRotationSlot), w['r'].value);
    return;
  }
  // The reading in the active frame, the named axes replaced, placed in `system`'s frame.
  AxisVec p = to_program(pos_, tool_offset_);
  bool any = false;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!w[kAxisWords[a]].present) continue;
    p[a] = scaled(a);
    any = true;
  }
  if (w.has('r')) params_.set_numbered(work_param(system, kRotationSlot), w['r'].value);
  if (!any) return;
  const AxisVec g92 = g92_offset();
  const Vec2 xy = rotated({p[0] + g92[0], p[1] + g92[1]}, rotation_deg(system));
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    const double q = a == 0 ? xy.a : a == 1 ? xy.b : p[a] + g92[a];
    const bool turned = a < 2 && (w.has('x') || w.has('y')) && rotation_deg(system) != 0;
    if (w[kAxisWords[a]].present || turned)
      params_.set_numbered(work_param(system, a), pos_[a] - tool_offset_[a] - q);
  }
}

// G28/G30: rapid through the optional intermediate point (the axis words, in program
// coordinates) to the stored home position (#5161… / #5181…, machine coordinates, mm), moving
// only the named axes, or all axes when none is named. G28.1/G30.1 store the current position.
void Interpreter::Impl::go_home(int code10) {
  const int base = (code10 == 280 || code10 == 281) ? kParamG28Home : kParamG30Home;
  if (code10 == 281 || code10 == 301) {
    for (std::size_t a = 0; a < kMaxAxes; ++a)
      params_.set_numbered(base + static_cast<int>(a), pos_[a]);
    return;
  }
  const std::uint32_t col = words_.group(GGroup::kNonModal)->col;
  bool any = false;
  for (std::size_t a = 0; a < kMaxAxes; ++a) any = any || words_[kAxisWords[a]].present;
  const Motion saved = modal_.motion;
  modal_.motion = Motion::kRapid;
  line_motion(target_from_words(false), col);  // without words, where it is (as LinuxCNC lists)
  AxisVec home = pos_;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!machine_.axes[a].enabled) continue;
    if (!any || words_[kAxisWords[a]].present)
      home[a] = params_.stored(base + static_cast<int>(a));  // mm, whatever parameter_units
  }
  line_motion(home, col);
  modal_.motion = saved;
}

}  // namespace cncore::interp
