// Tools: T (select), M6 (change), M61 (set the tool number), the tool length offsets G43 H,
// G43.1 (from the axis words), G43.2 (added), G49, the tool table writes G10 L1/L10/L11, and
// the words of cutter radius compensation G40/G41/G42/G41.1/G42.1 D (its path: cutter_comp.cpp).
// The table comes from the machine configuration's [[tools]] and the --tool-table file. An
// offset is applied here, as part of the offset between program and machine coordinates
// (offset()), so the planner sees machine coordinates of the controlled point.
#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

namespace {
// LinuxCNC: #5400 tool number, #5401…#5409 its offsets X…W, #5410 its diameter.
constexpr int kParamToolOffsets = 5401;
constexpr int kParamToolDiameter = 5410;
}  // namespace

void Interpreter::Impl::init_tools(const Options& options) {
  for (const ToolSpec& t : machine_.cutting.tools) {
    ToolEntry e;
    e.number = t.number;
    e.offset_mm[kZ] = t.length_mm;
    e.diameter_mm = t.diameter_mm;
    tools_[t.number] = e;
  }
  for (const auto& [number, entry] : options.tools) tools_[number] = entry;
  tool_table_given_ = options.tools_listed.value_or(!tools_.empty());
}

// The entry of tool `number`. Without any table every tool exists, with zero offsets (as in
// LinuxCNC's rs274 without -t), so programs that only select tools run unchanged.
const ToolEntry& Interpreter::Impl::tool_entry(double number, std::uint32_t col, const char* what) {
  if (number < 0 || number != std::floor(number) || number > 1e9) {
    fail(col, fmt::format("{} must be a tool number (a non-negative integer)", what));
  }
  const auto n = static_cast<std::uint32_t>(number);
  if (auto it = tools_.find(n); it != tools_.end()) return it->second;
  if (tool_table_given_ && n != 0) {
    fail(col, fmt::format("tool {} is not in the tool table", n));
  }
  // Kept apart from the table: only real entries are carried to the next program.
  ToolEntry& e = implicit_tools_[n];
  e.number = n;
  return e;
}

// Step 6: T selects the tool that the next M6 loads.
void Interpreter::Impl::select_tool() {
  const Words::Value& t = words_['t'];
  selected_tool_ = tool_entry(t.value, t.col, "T").number;
  emit_aux('T', t.value, false);
}

// Step 8: M6 loads the selected tool; M61 Q sets the tool in the spindle without a change.
// Neither applies an offset: that is G43's job.
void Interpreter::Impl::change_tool(const Words::Code& m) {
  if (m.code10 == 610) {
    if (!words_.has('q')) fail(m.col, "M61 without Q (tool number)");
    modal_.tool = static_cast<int>(tool_entry(words_['q'].value, words_['q'].col, "Q").number);
    selected_tool_ = static_cast<std::uint32_t>(modal_.tool);
    return;
  }
  modal_.tool = static_cast<int>(selected_tool_);
  emit_aux('M', 6, true);
}

// Step 18: G43 [H] (the table's offsets of tool H, default the tool in the spindle), G43.1
// (the offsets from the axis words), G43.2 H / axis words (added to the active offsets), G49.
void Interpreter::Impl::tool_length(const Words::Code& g) {
  const Words& w = words_;
  const double unit = modal_.length_unit_mm();
  if (w.has('h') && g.code10 != 430 && g.code10 != 432) {
    fail(w['h'].col, fmt::format("H word with {}", code_text('G', g.code10)));
  }
  switch (g.code10) {
    case 430: {
      const double h = w.has('h') ? w['h'].value : modal_.tool;
      tool_offset_.v = tool_entry(h, w.has('h') ? w['h'].col : g.col, "H").offset_mm;
      break;
    }
    case 431:
    case 432: {
      AxisVec added{};
      if (w.has('h')) added.v = tool_entry(w['h'].value, w['h'].col, "H").offset_mm;
      bool any = w.has('h');
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        const auto& v = w[kAxisWords[a]];
        if (!v.present) continue;
        any = true;
        added[a] += v.value * (is_rotary(a) ? 1.0 : unit);
      }
      if (g.code10 == 431) {
        if (w.has('h')) fail(w['h'].col, "G43.1 takes the offsets from the axis words, not H");
        if (!any) fail(g.col, "G43.1 without axis words (the offsets)");
        tool_offset_ = added;
      } else {
        if (!any) fail(g.col, "G43.2 without H or axis words");
        for (std::size_t a = 0; a < kMaxAxes; ++a) tool_offset_[a] += added[a];
      }
      break;
    }
    default:  // G49
      tool_offset_ = {};
      break;
  }
  modal_.tool_length_code = g.code10;
}

// G10 L1 P<tool> [R<radius>] <axes>: the offsets themselves. G10 L10: the offsets that make the
// current position read the given coordinates (with the active work offset, rotation and G92);
// G10 L11: the same with G59.3's offset and rotation and no G92. Lengths in program units.
void Interpreter::Impl::set_tool_data(int l) {
  const Words& w = words_;
  const Words::Code* g = w.group(GGroup::kNonModal);
  if (!w.has('p')) fail(g->col, fmt::format("G10 L{} without P (tool number)", l));
  const ToolEntry& found = tool_entry(w['p'].value, w['p'].col, "G10 P");
  ToolEntry e = found;
  const double unit = modal_.length_unit_mm();
  if (w.has('r')) {
    if (w['r'].value < 0) fail(w['r'].col, "G10 R: negative tool radius");
    e.diameter_mm = 2 * w['r'].value * unit;
  }
  if (l == 1) {
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      const auto& v = w[kAxisWords[a]];
      if (v.present) e.offset_mm[a] = v.value * (is_rotary(a) ? 1.0 : unit);
    }
  } else {
    // The position as it reads with this tool's stored offset, the named axes replaced; then
    // the offset that puts that reading here: m = R(θ)·(p + g92) + work + tool.
    const int system = l == 10 ? modal_.coord_system : 9;
    const double deg = rotation_deg(system);
    AxisVec work, g92{};
    for (std::size_t a = 0; a < kMaxAxes; ++a) work[a] = params_.stored(work_param(system, a));
    if (l == 10) g92 = g92_offset();
    AxisVec p;
    for (std::size_t a = 0; a < kMaxAxes; ++a) p[a] = pos_[a] - work[a] - found.offset_mm[a];
    const Vec2 xy = rotated({p[0], p[1]}, -deg);
    p[0] = xy.a;
    p[1] = xy.b;
    bool named_xy = false;
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      const auto& v = w[kAxisWords[a]];
      if (v.present) {
        p[a] = v.value * (is_rotary(a) ? 1.0 : unit);
        named_xy = named_xy || a < 2;
      } else {
        p[a] -= g92[a];
      }
    }
    const Vec2 at = rotated({p[0] + g92[0], p[1] + g92[1]}, deg);
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      const double q = a == 0 ? at.a : a == 1 ? at.b : p[a] + g92[a];
      if (w[kAxisWords[a]].present || (a < 2 && named_xy && deg != 0))
        e.offset_mm[a] = pos_[a] - work[a] - q;
    }
  }
  tools_[e.number] = e;
}

bool Interpreter::Impl::read_tool_param(int number, double& value) const {
  if (number == kParamTool) {
    value = modal_.tool;
    return true;
  }
  const auto it = tools_.find(static_cast<std::uint32_t>(modal_.tool));
  if (number >= kParamToolOffsets && number < kParamToolOffsets + static_cast<int>(kMaxAxes)) {
    const auto a = static_cast<std::size_t>(number - kParamToolOffsets);
    const double mm = it != tools_.end() ? it->second.offset_mm[a] : 0.0;
    value = mm / (is_rotary(a) ? 1.0 : modal_.length_unit_mm());
    return true;
  }
  if (number == kParamToolDiameter) {
    value = (it != tools_.end() ? it->second.diameter_mm : 0.0) / modal_.length_unit_mm();
    return true;
  }
  return false;
}

// Step 17. G41/G42 D: the diameter of tool D in the table (without D, of the tool in the
// spindle); G41.1/G42.1 D: the diameter itself, in program units. A negative diameter puts the
// tool on the other side (LinuxCNC). The blocks the line made so far ran under the old mode.
void Interpreter::Impl::cutter_comp(double unit) {
  const Words& w = words_;
  refuse_with_comp();
  const Words::Code* g = w.group(GGroup::kCutterComp);
  if (g == nullptr) {
    // D is also G33's and G76's start angle of the thread (degrees; LinuxCNC): the simulated
    // spindle has no angle, so it does not change the motion.
    const Words::Code* m = w.group(GGroup::kMotion);
    const bool thread = (m != nullptr && (m->code10 == 330 || m->code10 == 760)) ||
                        (m == nullptr && modal_.motion == Motion::kSpindleSync);
    if (w.has('d') && w.group(GGroup::kSpindleMode) == nullptr && !lathe_cycle_block() && !thread) {
      fail(w['d'].col, "D word without G41, G42, G41.1, G42.1, G96, G33 or G76");
    }
    return;
  }
  comp_.pass(out_, comp_from_);
  if (g->code10 == 400) {
    if (w.has('d')) fail(w['d'].col, "D word with G40");
    comp_.stop(out_, ctx_.line, g->col);
    comp_code_ = 400;
    comp_from_ = out_.size();
    return;
  }
  if (comp_.on()) fail(g->col, "cutter radius compensation is already on: program G40 first");
  double diameter_mm = 0;
  if (g->code10 == 411 || g->code10 == 421) {
    if (!w.has('d'))
      fail(g->col, fmt::format("{} without D (the tool diameter)", code_text('G', g->code10)));
    diameter_mm = w['d'].value * unit;
  } else {
    const bool has_d = w.has('d');
    diameter_mm = tool_entry(has_d ? w['d'].value : modal_.tool, has_d ? w['d'].col : g->col, "D")
                      .diameter_mm;
  }
  bool left = g->code10 == 410 || g->code10 == 411;
  if (diameter_mm < 0) left = !left;
  comp_.start(left ? CutterComp::Side::kLeft : CutterComp::Side::kRight, std::fabs(diameter_mm) / 2,
              modal_.plane);
  comp_code_ = g->code10;
  comp_from_ = out_.size();
}

// What cannot run while cutter radius compensation is on: a change of plane, a tool change,
// G28/G30, G53 and the canned cycles.
void Interpreter::Impl::refuse_with_comp() const {
  if (!comp_.on()) return;
  const Words& w = words_;
  auto refuse = [&](std::uint32_t col, const std::string& what) {
    fail(col, fmt::format("{} with cutter radius compensation on: program G40 first", what));
  };
  if (const auto* g = w.group(GGroup::kPlane); g != nullptr && modal_.plane != comp_.plane()) {
    refuse(g->col, "change of plane");
  }
  if (const auto* m = w.mgroup(MGroup::kToolChange)) refuse(m->col, code_text('M', m->code10));
  if (const auto* g = w.group(GGroup::kNonModal)) {
    if (g->code10 == 280 || g->code10 == 300 || g->code10 == 530) {
      refuse(g->col, code_text('G', g->code10));
    }
  }
  const auto* motion = w.group(GGroup::kMotion);
  const bool cycle_words = w.has('x') || w.has('y') || w.has('z') || w.has('r');
  const int code10 = motion != nullptr                                ? motion->code10
                     : modal_.motion == Motion::kCycle && cycle_words ? modal_.cycle
                                                                      : 0;
  if (code10 == 730 || code10 == 740 || (code10 >= 810 && code10 <= 890)) {
    refuse(motion != nullptr ? motion->col : w.first_col, "a canned cycle");
  }
  if (code10 == 760 || code10 == 331 || (code10 >= 710 && code10 <= 722)) {
    refuse(motion->col, code_text('G', code10));
  }
}

}  // namespace cncore::interp
