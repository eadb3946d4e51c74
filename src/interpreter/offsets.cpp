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
      if (w.has('r')) fail(w['r'].col, "G10 R: coordinate system rotation is not supported");
      if (!w.has('p')) fail(g->col, "G10 L2/L20 without P (coordinate system 0…9)");
      const double p = w['p'].value;
      if (p < 0 || p > 9 || p != std::floor(p)) fail(w['p'].col, "G10 P must be 0…9");
      const int system = p == 0 ? modal_.coord_system : static_cast<int>(p);
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        if (!w[kAxisWords[a]].present) continue;
        double value;
        if (l == 2) {
          value = scaled(a);  // L2: the offset itself (G90/G91 do not apply)
        } else {
          // L20: choose the offset so that the current position reads `value`:
          // pos = value + work + g92 + tool  →  work = pos − g92 − tool − value
          const double g92 = params_.numbered(kParamG92Applied) != 0
                                 ? params_.numbered(kParamG92 + static_cast<int>(a))
                                 : 0.0;
          value = pos_[a] - g92 - tool_offset_[a] - scaled(a);
        }
        params_.set_numbered(work_param(system, a), value);
      }
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
      // G92: pos = value + work + g92 + tool  →  g92 = pos − work − tool − value, for the
      // named axes.
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        if (!w[kAxisWords[a]].present) continue;
        any = true;
        const double work = params_.numbered(work_param(modal_.coord_system, a));
        params_.set_numbered(kParamG92 + static_cast<int>(a),
                             pos_[a] - work - tool_offset_[a] - scaled(a));
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
  if (any) line_motion(target_from_words(false), col);
  AxisVec home = pos_;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!machine_.axes[a].enabled) continue;
    if (!any || words_[kAxisWords[a]].present)
      home[a] = params_.numbered(base + static_cast<int>(a));
  }
  line_motion(home, col);
  modal_.motion = saved;
}

}  // namespace cncore::interp
