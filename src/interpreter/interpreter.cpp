// Reading and executing blocks: word parsing, modal-group checks, and the LinuxCNC order of
// execution within a block. Flow control (O-words, M98/M99) lives in flow.cpp, the arc
// geometry in arcs.cpp.
#include "interpreter/interpreter.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

namespace {

constexpr std::size_t kLinearAxes = 3;
constexpr double kZeroMoveMm = 1e-9;  // moves shorter than this are not emitted

// LinuxCNC CENTER_ARC_RADIUS_TOLERANCE_{MM,INCH} = 2·0.01·√2 mm, 2·0.001·√2 in, and the
// relative tolerance 0.1 % (both must be exceeded for an error, or 100× the absolute one).
constexpr double kArcAbsTolMm = 2 * 0.01 * 1.4142135623730951;
constexpr double kArcAbsTolInch = 2 * 0.001 * 1.4142135623730951;
constexpr double kArcRelTol = 0.001;
// R-form: half-chord may exceed |R| by this much (LinuxCNC TOLERANCE_MM / TOLERANCE_INCH).
constexpr double kRadiusTolMm = 0.005;
constexpr double kRadiusTolInch = 0.0005;

constexpr std::array<char, kMaxAxes> kAxisWords = {'x', 'y', 'z', 'a', 'b', 'c'};

bool is_rotary(std::size_t axis) {
  return axis >= kLinearAxes;
}

// Parameter numbers (LinuxCNC) for state kept in the parameter table; lengths in mm.
constexpr int kParamG28Home = 5161;
constexpr int kParamG30Home = 5181;
constexpr int kParamG92Applied = 5210;
constexpr int kParamG92 = 5211;
constexpr int kParamCoordSystem = 5220;
constexpr int kParamWorkOffsets = 5221;  // + 20·(system − 1) + axis
constexpr int kParamTool = 5400;
constexpr int kParamPosition = 5420;

int work_param(int system, std::size_t axis) {
  return kParamWorkOffsets + 20 * (system - 1) + static_cast<int>(axis);
}

}  // namespace

Interpreter::Impl::Impl(LineReader r, std::string name, const MachineConfig& m,
                        const Options& options)
    : file_(std::move(name)), machine_(m), reader_(std::move(r)) {
  ctx_.file = &file_;
  params_.set_live(this);
  for (std::size_t a = 0; a < kMaxAxes; ++a) pos_[a] = machine_.start_position[a];
  if (options.modal) modal_ = *options.modal;
  params_.set_numbered(kParamCoordSystem, modal_.coord_system);
  for (const auto& [n, v] : options.params) {
    if (!Parameters::valid_number(n)) {
      throw InputError(file_, 0, 0, fmt::format("--param {}: no such parameter number", n));
    }
    params_.set_numbered(n, v);
  }
  // A saved active system (5220) selects it when no modal state is carried over.
  if (const auto it = options.params.find(kParamCoordSystem);
      it != options.params.end() && !options.modal) {
    modal_.coord_system = std::clamp(static_cast<int>(std::lround(it->second)), 1, 9);
    params_.set_numbered(kParamCoordSystem, modal_.coord_system);
  }
  for (const auto& [name_in, v] : options.named_params) {
    std::string key;
    for (char c : name_in) {
      if (c == ' ' || c == '\t') continue;
      key.push_back(c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c);
    }
    params_.set_named(key, v);
  }
  out_.reserve(8);
  words_.assignments.reserve(8);
}

bool Interpreter::Impl::next(Block& out) {
  while (out_head_ >= out_.size()) {
    out_.clear();
    out_head_ = 0;
    if (finished_) return false;
    step();
  }
  out = out_[out_head_++];
  return true;
}

bool Interpreter::Impl::recover() {
  // A move beyond the travel: the blocks after it were written from its end point, not from
  // the last position reached; continue from there rather than judge them against a start
  // the program never meant.
  if (travel_failed_) {
    pos_ = travel_target_;
    beyond_travel_ = true;
  }
  travel_failed_ = false;
  out_.clear();
  out_head_ = 0;
  words_.clear();
  if (at_eof_) finished_ = true;  // an error at the end (unclosed sub, loop, ...) ends it
  return !finished_;
}

double Interpreter::Impl::offset(std::size_t axis) const {
  double off = params_.stored(work_param(modal_.coord_system, axis));
  if (params_.stored(kParamG92Applied) != 0)
    off += params_.stored(kParamG92 + static_cast<int>(axis));
  return off;
}

bool Interpreter::Impl::read_live(int number, double& value) const {
  if (number >= kParamPosition && number < kParamPosition + static_cast<int>(kMaxAxes)) {
    const auto axis = static_cast<std::size_t>(number - kParamPosition);
    const double unit = is_rotary(axis) ? 1.0 : modal_.length_unit_mm();
    value = (pos_[axis] - offset(axis)) / unit;
    return true;
  }
  if (number == kParamTool) {
    value = modal_.tool;
    return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// Reading one line

void Interpreter::Impl::step() {
  std::string_view raw;
  if (!reader_.next(raw)) {
    at_eof_ = true;
    end_of_file();
    return;
  }
  ctx_.line = reader_.current().line;
  normalize_line(raw, line_, ctx_);
  if (line_.block_delete) return;  // block delete switch is on: skip "/" lines
  if (line_.percent) {
    // "%" opens the program on its first line; a second "%" ends it.
    if (!started_ && !percent_framed_) {
      percent_framed_ = true;
    } else if (percent_framed_) {
      finished_ = true;
    }
    return;
  }
  if (line_.text.empty()) return;

  std::size_t pos = 0;
  // N word (line number): only at the start of the line; ignored.
  if (line_.text[0] == 'n') {
    ++pos;
    while (pos < line_.text.size() && (is_digit(line_.text[pos]) || line_.text[pos] == '.')) ++pos;
    if (pos == 1) fail(line_.col(0), "N word without a line number");
    if (pos == line_.text.size()) return;
  }
  if (line_.text[pos] == 'o') {
    OWord o;
    parse_oword(o);
    execute_oword(o);
    started_ = true;
    return;
  }
  parse_words(pos);
  started_ = true;
  execute_words();
}

void Interpreter::Impl::parse_words(std::size_t pos) {
  Words& w = words_;
  w.clear();
  w.first_col = line_.col(pos);
  Evaluator eval(line_, ctx_, params_);
  const std::string& t = line_.text;
  while (pos < t.size()) {
    const char c = t[pos];
    const std::uint32_t col = line_.col(pos);
    if (c == '#') {
      Words::Assignment a;
      a.ref = eval.param_ref(pos);
      if (pos >= t.size() || t[pos] != '=')
        fail(line_.col(pos), "expected '=' after the parameter");
      ++pos;
      a.value = eval.real_value(pos);
      w.assignments.push_back(a);
      continue;
    }
    if (c == '@' || c == '^') {
      fail(col, fmt::format("polar coordinates ('{}' word) are not supported", c));
    }
    if (!is_lower(c)) {
      fail(col, fmt::format("unexpected character '{}'", c));
    }
    const char upper = static_cast<char>(c - 'a' + 'A');
    switch (c) {
      case 'n':
        fail(col, "N word (line number) must be at the start of the line");
      case 'o':
        fail(col, "O word must be at the start of the line");
      case 'e':
      case 'u':
      case 'v':
      case 'w':
        if (c == 'e') fail(col, "unknown word 'E'");
        fail(col, fmt::format("{} axis is not supported (cncore axes: X Y Z A B C)", upper));
      case 'g':
      case 'm': {
        ++pos;
        const double v = eval.real_value(pos);
        if (v < 0 || v > 10000) fail(col, fmt::format("unknown {} code {}{}", upper, upper, v));
        const double v10 = v * 10;
        const int code10 = static_cast<int>(std::lround(v10));
        if (std::fabs(v10 - code10) > 1e-6) {
          fail(col, fmt::format("unknown {} code {}{}", upper, upper, v));
        }
        const bool is_g = c == 'g';
        const CodeInfo info = is_g ? g_code_info(code10) : m_code_info(code10);
        if (!info.known)
          fail(col, "unknown " + std::string(1, upper) + " code " + code_text(upper, code10));
        auto& list = is_g ? w.g : w.m;
        int& count = is_g ? w.g_count : w.m_count;
        if (count >= Words::kMaxCodes)
          fail(col, fmt::format("too many {} words in one block", upper));
        int& slot = is_g ? w.g_group[static_cast<std::size_t>(info.group)]
                         : w.m_group[static_cast<std::size_t>(info.group)];
        if (slot >= 0) {
          const int other = list[static_cast<std::size_t>(slot)].code10;
          // LinuxCNC lets M7 and M8 (mist and flood) share a block.
          const bool coolant_pair = !is_g && other != 90 && code10 != 90 && other != code10;
          if (!(coolant_pair && info.group == static_cast<int>(MGroup::kCoolant))) {
            fail(col, fmt::format("{} and {} are in the same modal group: only one per block",
                                  code_text(upper, other), code_text(upper, code10)));
          }
        }
        slot = count;
        list[static_cast<std::size_t>(count++)] = {code10, col};
        continue;
      }
      default:
        break;
    }
    Words::Value& slot = w.letter[static_cast<std::size_t>(c - 'a')];
    if (slot.present) fail(col, fmt::format("two {} words in one block", upper));
    ++pos;
    if (pos < t.size() && is_lower(t[pos]) && !(pos + 1 < t.size() && t[pos + 1] == '[')) {
      // A letter followed by another word letter: the value is missing ("X Y1") unless it
      // is a function such as SIN[…].
      std::size_t e = pos;
      while (e < t.size() && is_lower(t[e])) ++e;
      if (e >= t.size() || t[e] != '[') fail(col, fmt::format("{} word without a value", upper));
    }
    slot.value = eval.real_value(pos);
    slot.col = col;
    slot.present = true;
  }
  // Parameters set on this line take effect after the whole line has been read (LinuxCNC):
  // "#1=2 #2=#1" sets #2 to the old value of #1.
  for (const Words::Assignment& a : w.assignments) {
    if (a.ref.number > 0) {
      params_.set_numbered(a.ref.number, a.value);
    } else {
      params_.set_named(a.ref.name, a.value);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Executing one block in the LinuxCNC order of execution:
//   1 O-word (flow.cpp)  2 comment  3 feed mode G93/G94  4 F  5 S  6 T  8 M6  9 M3 M4 M5
//   11 M7 M8 M9  14 G4 dwell  15 G17/G18/G19  16 G20/G21  17 G40  18 G49  19 G54…G59.3
//   20 G61/G61.1/G64  21 G90/G91  22 G90.1/G91.1  23 G98/G99  24 G10 G28 G30 G92…
//   25 motion G0…G3 (G53 modifies it)  26 M0 M1 M2 M30 (then M98/M99)

Block Interpreter::Impl::base_block(BlockKind kind) const {
  Block b;
  b.kind = kind;
  b.line = ctx_.line;
  b.col = words_.first_col;
  b.start = pos_;
  b.end = pos_;
  return b;
}

void Interpreter::Impl::emit_aux(char letter, double value, bool waits) {
  Block b = base_block(BlockKind::kAux);
  b.aux_letter = letter;
  b.aux_value = value;
  b.aux_waits = waits;
  out_.push_back(b);
}

void Interpreter::Impl::execute_words() {
  const Words& w = words_;

  // Everything beyond cncore's dialect is refused first, naming the feature.
  for (int i = 0; i < w.g_count; ++i) {
    const auto& g = w.g[static_cast<std::size_t>(i)];
    const CodeInfo info = g_code_info(g.code10);
    if (!info.supported) {
      fail(g.col, fmt::format("{} {} is not supported", code_text('G', g.code10), info.name));
    }
  }
  for (int i = 0; i < w.m_count; ++i) {
    const auto& m = w.m[static_cast<std::size_t>(i)];
    const CodeInfo info = m_code_info(m.code10);
    if (!info.supported) {
      fail(m.col, fmt::format("{} {} is not supported", code_text('M', m.code10), info.name));
    }
  }
  if (w.has('d')) fail(w['d'].col, "D word: cutter compensation (G41/G42) is not supported");
  if (w.has('h')) fail(w['h'].col, "H word: tool length offset (G43) is not supported");

  // The units of this block: a G20/G21 in the block applies to all its numbers (cncore reads
  // F with them too, so "G20 F10" is 10 in/min).
  bool inch = modal_.inch;
  if (const auto* u = w.group(GGroup::kUnits)) inch = u->code10 == 200;
  const double unit = inch ? 25.4 : 1.0;

  // 4 F
  if (w.has('f')) {
    if (w['f'].value < 0) fail(w['f'].col, "negative feed rate F");
    modal_.feed_mm_min = w['f'].value * unit;
    modal_.feed_set = true;
  }
  // 5 S
  if (w.has('s')) {
    if (w['s'].value < 0) fail(w['s'].col, "negative spindle speed S");
    emit_aux('S', w['s'].value, false);
  }
  // 6 T (select: the tool is prepared; M6 makes it current)
  int selected_tool = modal_.tool;
  if (w.has('t')) {
    const double tv = w['t'].value;
    if (tv < 0 || tv != std::floor(tv) || tv > 1e9) {
      fail(w['t'].col, "T must be a tool number (a non-negative integer)");
    }
    selected_tool = static_cast<int>(tv);
    emit_aux('T', tv, false);
  }
  // 8 M6
  if (w.mgroup(MGroup::kToolChange) != nullptr) {
    modal_.tool = selected_tool;
    emit_aux('M', 6, true);
  }
  // 9 spindle
  if (const auto* m = w.mgroup(MGroup::kSpindle)) emit_aux('M', m->code10 / 10.0, true);
  // 10 overrides: M52 adaptive feed control (spec 04), P1 or no P on, P0 off. An aux event
  // that does not stop the motion: it takes effect where the tool passes it.
  for (int i = 0; i < w.m_count; ++i) {
    const auto& m = w.m[static_cast<std::size_t>(i)];
    if (m.code10 != 520) continue;
    double p = 1;
    if (w.has('p')) {
      const Words::Code* g_nm = w.group(GGroup::kNonModal);
      const Words::Code* g_pc = w.group(GGroup::kPathControl);
      const Words::Code* g_mo = w.group(GGroup::kMotion);
      const Words::Code* other =
          (g_nm != nullptr && (g_nm->code10 == 40 || g_nm->code10 == 100))  ? g_nm
          : (g_pc != nullptr && g_pc->code10 == 640)                        ? g_pc
          : (g_mo != nullptr && (g_mo->code10 == 20 || g_mo->code10 == 30)) ? g_mo
                                                                            : nullptr;
      if (other != nullptr) {
        fail(m.col, fmt::format("M52 and {} both use the P word: put them in separate blocks",
                                code_text('G', other->code10)));
      }
      p = w['p'].value;
      if (p != 0 && p != 1) {
        fail(w['p'].col, "M52 P must be 1 (adaptive feed on) or 0 (off)");
      }
    }
    Block b = base_block(BlockKind::kAux);
    b.aux_letter = 'M';
    b.aux_value = 52;
    b.aux_p = p;
    out_.push_back(b);
  }
  // 11 coolant (M7 and M8 may both be present)
  for (int i = 0; i < w.m_count; ++i) {
    const auto& m = w.m[static_cast<std::size_t>(i)];
    if (m.code10 == 70 || m.code10 == 80 || m.code10 == 90) emit_aux('M', m.code10 / 10.0, false);
  }
  // 12 user-defined M codes: M160 / M161 switch the direction feed correction (spec 03) on / off
  // from this block's motion on. No stop: the correction stage acts on the event in the stream.
  if (const auto* m = w.mgroup(MGroup::kUser)) emit_aux('M', m->code10 / 10.0, false);
  // 14 dwell
  const Words::Code* nonmodal = w.group(GGroup::kNonModal);
  const int nm = nonmodal != nullptr ? nonmodal->code10 : -1;
  if (nm == 40) {
    if (!w.has('p')) fail(nonmodal->col, "G4 dwell without P (seconds)");
    if (w['p'].value < 0) fail(w['p'].col, "negative dwell time P");
    Block b = base_block(BlockKind::kDwell);
    b.dwell_s = w['p'].value;
    out_.push_back(b);
  }
  // 15 plane
  if (const auto* g = w.group(GGroup::kPlane)) {
    modal_.plane = g->code10 == 170 ? Plane::kXY : g->code10 == 180 ? Plane::kZX : Plane::kYZ;
  }
  // 16 units
  modal_.inch = inch;
  // 17 G40, 18 G49: compensation is never on, nothing to cancel.
  // 19 coordinate system
  if (const auto* g = w.group(GGroup::kCoordSystem)) {
    modal_.coord_system = g->code10 <= 590 ? (g->code10 - 540) / 10 + 1 : 7 + (g->code10 - 591);
    params_.set_numbered(kParamCoordSystem, modal_.coord_system);
  }
  // 20 path control
  if (const auto* g = w.group(GGroup::kPathControl)) {
    if (g->code10 == 610) {
      modal_.path_mode = PathMode::kExactPath;
      modal_.tolerance_mm = -1;
    } else if (g->code10 == 611) {
      modal_.path_mode = PathMode::kExactStop;
      modal_.tolerance_mm = -1;
    } else {
      modal_.path_mode = PathMode::kBlend;
      modal_.tolerance_mm = -1;
      if (w.has('p')) {
        if (w['p'].value < 0) fail(w['p'].col, "negative G64 tolerance P");
        modal_.tolerance_mm = w['p'].value * unit;
      }
      modal_.smooth_tolerance_mm = -1;
      if (w.has('q')) {
        if (w['q'].value < 0) fail(w['q'].col, "negative G64 smoothing tolerance Q");
        modal_.smooth_tolerance_mm = w['q'].value * unit;
      }
    }
  }
  // 21 distance mode, 22 arc distance mode
  if (const auto* g = w.group(GGroup::kDistance)) modal_.absolute = g->code10 == 900;
  if (const auto* g = w.group(GGroup::kArcDistance)) modal_.arc_absolute = g->code10 == 901;
  // 23 G98/G99: retract modes of canned cycles, which cncore does not run.

  // Which words are axis words, and who uses them.
  bool have_axes = false;
  std::uint32_t first_axis_col = 0;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    const auto& v = w[kAxisWords[a]];
    if (!v.present) continue;
    if (!machine_.axes[a].enabled) {
      fail(v.col, fmt::format("{} axis is not configured on this machine", kAxisLetters[a]));
    }
    if (!have_axes) first_axis_col = v.col;
    have_axes = true;
  }
  const Words::Code* motion_word = w.group(GGroup::kMotion);
  const bool axes_for_nonmodal = nm == 100 || nm == 280 || nm == 300 || nm == 920;
  if (axes_for_nonmodal && motion_word != nullptr && motion_word->code10 != 800 && have_axes) {
    fail(motion_word->col, fmt::format("{} and {} both use the axis words", code_text('G', nm),
                                       code_text('G', motion_word->code10)));
  }

  // 24 offsets and homing
  if (nm == 100 || nm == 920 || nm == 921 || nm == 922 || nm == 923) set_offsets();
  if (nm == 280 || nm == 281 || nm == 300 || nm == 301) go_home(nm);

  // 25 motion
  if (motion_word != nullptr) {
    switch (motion_word->code10) {
      case 0:
        modal_.motion = Motion::kRapid;
        break;
      case 10:
        modal_.motion = Motion::kLine;
        break;
      case 20:
        modal_.motion = Motion::kArcCw;
        break;
      case 30:
        modal_.motion = Motion::kArcCcw;
        break;
      default:
        modal_.motion = Motion::kNone;
        break;  // G80
    }
  }
  const bool arc_mode = modal_.motion == Motion::kArcCw || modal_.motion == Motion::kArcCcw;
  const bool have_centre = w.has('i') || w.has('j') || w.has('k');
  if (!arc_mode) {
    for (char c : {'i', 'j', 'k', 'r'}) {
      if (w.has(c) && !(c == 'r' && nm == 100)) {
        fail(w[c].col, fmt::format("{} word without G2/G3", static_cast<char>(c - 'a' + 'A')));
      }
    }
  }
  const bool machine_coords = nm == 530;
  if (!axes_for_nonmodal) {
    const std::uint32_t col = motion_word != nullptr ? motion_word->col
                              : have_axes            ? first_axis_col
                                                     : w.first_col;
    if (machine_coords) {
      if (!have_axes) fail(nonmodal->col, "G53 without axis words");
      if (modal_.motion != Motion::kRapid && modal_.motion != Motion::kLine) {
        fail(nonmodal->col, "G53 needs G0 or G1 (not an arc or G80)");
      }
      if (!modal_.absolute) fail(nonmodal->col, "G53 cannot be used in incremental mode G91");
    }
    if (have_axes || (arc_mode && (have_centre || w.has('r')))) {
      if (modal_.motion == Motion::kNone) {
        fail(have_axes ? first_axis_col : w.first_col,
             "axis words without a motion mode: program G0, G1, G2 or G3 first");
      }
      const AxisVec target = target_from_words(machine_coords);
      if (arc_mode) {
        arc(target, modal_.motion == Motion::kArcCcw, col);
      } else {
        line_motion(target, col);
      }
    }
  }

  // 26 stops
  if (const auto* m = w.mgroup(MGroup::kStopping)) {
    switch (m->code10) {
      case 0:
      case 10:
        emit_aux('M', m->code10 / 10.0, true);
        break;
      case 20:
      case 300:
        emit_aux('M', m->code10 / 10.0, true);
        finished_ = true;
        break;
      case 990:
        return_fanuc(m->col);
        break;
      default:
        break;
    }
  }
  // The group also holds M52 (adaptive feed, emitted at step 10): only M98 calls.
  if (const auto* m = w.mgroup(MGroup::kSubprogram); m != nullptr && m->code10 == 980) {
    call_fanuc(m->col);
  }
}

AxisVec Interpreter::Impl::target_from_words(bool machine_coords) const {
  AxisVec target = pos_;
  const double unit = modal_.length_unit_mm();
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    const auto& v = words_[kAxisWords[a]];
    if (!v.present) continue;
    const double value = v.value * (is_rotary(a) ? 1.0 : unit);
    if (machine_coords) {
      target[a] = value;  // G53: machine coordinates, no offsets
    } else if (modal_.absolute) {
      target[a] = value + offset(a);  // G90: program coordinate + work offset (+ G92)
    } else {
      target[a] = pos_[a] + value;  // G91
    }
  }
  return target;
}

void Interpreter::Impl::check_travel(const AxisVec& lo, const AxisVec& hi, const AxisVec& target,
                                     std::uint32_t col) {
  constexpr double kSlack = 1e-9;
  if (beyond_travel_) {
    bool inside = true;
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      const AxisConfig& ax = machine_.axes[a];
      if (!ax.enabled || ax.max_mm <= ax.min_mm) continue;
      inside = inside && hi[a] <= ax.max_mm + kSlack && lo[a] >= ax.min_mm - kSlack;
    }
    if (!inside) return;  // still out there, as a consequence of the first error
    beyond_travel_ = false;
  }
  travel_target_ = target;
  travel_failed_ = true;  // cleared below when the move stays inside
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    const AxisConfig& ax = machine_.axes[a];
    if (!ax.enabled || ax.max_mm <= ax.min_mm) continue;  // rotary without limits
    const auto& word = words_[kAxisWords[a]];
    const std::uint32_t c = word.present ? word.col : col;
    if (hi[a] > ax.max_mm + kSlack) {
      fail(c, fmt::format("{} {:.3f} is beyond the travel limit {:.3f}", kAxisLetters[a], hi[a],
                          ax.max_mm));
    }
    if (lo[a] < ax.min_mm - kSlack) {
      fail(c, fmt::format("{} {:.3f} is beyond the travel limit {:.3f}", kAxisLetters[a], lo[a],
                          ax.min_mm));
    }
  }
  travel_failed_ = false;
}

void Interpreter::Impl::emit_motion(BlockKind kind, const AxisVec& target, std::uint32_t col) {
  Block b = base_block(kind);
  b.end = target;
  b.col = col;
  b.feed_mm_min = kind == BlockKind::kRapid ? 0 : modal_.feed_mm_min;
  b.path_mode =
      words_.group(GGroup::kExactStopOnce) != nullptr ? PathMode::kExactStop : modal_.path_mode;
  b.tolerance_mm = b.path_mode == PathMode::kBlend ? modal_.tolerance_mm : -1;
  b.smooth_tolerance_mm = modal_.smooth_tolerance_mm;
  out_.push_back(b);
}

// G0/G1 to `target` (machine coordinates).
void Interpreter::Impl::line_motion(const AxisVec& target, std::uint32_t col) {
  const bool rapid = modal_.motion == Motion::kRapid;
  if (!rapid && !modal_.feed_set) {
    fail(col, "no feed rate: program F before the first G1/G2/G3");
  }
  if (!rapid && modal_.feed_mm_min <= 0) fail(col, "feed rate F is zero");
  check_travel(target, target, target, col);
  double len2 = 0;
  for (std::size_t a = 0; a < kMaxAxes; ++a) len2 += (target[a] - pos_[a]) * (target[a] - pos_[a]);
  if (len2 > kZeroMoveMm * kZeroMoveMm) {
    emit_motion(rapid ? BlockKind::kRapid : BlockKind::kLine, target, col);
  }
  pos_ = target;
}

// G2/G3. The centre comes from R (centre_from_radius) or from I J K (check_centre); the helix
// axis (plane normal) and any other axes move linearly with the angle.
void Interpreter::Impl::arc(const AxisVec& target, bool ccw, std::uint32_t col) {
  const Words& w = words_;
  const char* g = ccw ? "G3" : "G2";
  if (!modal_.feed_set) fail(col, "no feed rate: program F before the first G1/G2/G3");
  if (modal_.feed_mm_min <= 0) fail(col, "feed rate F is zero");
  const PlaneAxes pa = plane_axes(modal_.plane);
  const double unit = modal_.length_unit_mm();
  const Vec2 s{pos_[pa.first], pos_[pa.second]};
  const Vec2 e{target[pa.first], target[pa.second]};
  Vec2 c;
  if (w.has(pa.normal_word)) {
    const char up = static_cast<char>(pa.normal_word - 'a' + 'A');
    fail(w[pa.normal_word].col,
         fmt::format("{} word given for an arc in the {} plane", up, plane_gcode(modal_.plane)));
  }
  const bool has_first = w.has(pa.first_word), has_second = w.has(pa.second_word);
  if (w.has('r')) {
    if (has_first || has_second) fail(w['r'].col, "arc with both R and I/J/K");
    const double tol = modal_.inch ? kRadiusTolInch * 25.4 : kRadiusTolMm;
    const ArcCheck chk = centre_from_radius(s, e, w['r'].value * unit, ccw, tol, c);
    if (!chk.ok) fail(w['r'].col, chk.message);
  } else {
    if (!has_first && !has_second) {
      fail(col, fmt::format("{} arc without centre (I J K) or radius (R)", g));
    }
    const double i = w[pa.first_word].value * unit;  // absent words are 0
    const double j = w[pa.second_word].value * unit;
    if (modal_.arc_absolute) {
      c = {i + offset(pa.first), j + offset(pa.second)};  // G90.1: program coordinates
    } else {
      c = {s.a + i, s.b + j};  // G91.1: relative to the start point
    }
    const double abs_tol = modal_.inch ? kArcAbsTolInch * 25.4 : kArcAbsTolMm;
    const ArcCheck chk = check_centre(s, e, c, abs_tol, kArcRelTol);
    if (!chk.ok) {
      const double r0 = std::hypot(s.a - c.a, s.b - c.b), r1 = std::hypot(e.a - c.a, e.b - c.b);
      fail(col,
           fmt::format("{} ({:.4f} mm at the start, {:.4f} mm at the end)", chk.message, r0, r1));
    }
  }
  std::uint32_t turns = 0;
  if (w.has('p')) {
    const double p = w['p'].value;
    if (p < 1 || p != std::floor(p) || p > 1e6) {
      fail(w['p'].col, "arc turns P must be a positive integer");
    }
    turns = static_cast<std::uint32_t>(p) - 1;
  }
  // Travel: the end point, plus the axis-aligned extremes of the circle that the arc passes.
  // When the whole circle (c ± r) lies inside the travel, the extremes need not be computed.
  AxisVec lo = target, hi = target;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    lo[a] = std::min(pos_[a], target[a]);
    hi[a] = std::max(pos_[a], target[a]);
  }
  const double r = std::sqrt((s.a - c.a) * (s.a - c.a) + (s.b - c.b) * (s.b - c.b));
  const AxisConfig& fa = machine_.axes[pa.first];
  const AxisConfig& sa = machine_.axes[pa.second];
  const bool circle_inside =
      c.a - r >= fa.min_mm && c.a + r <= fa.max_mm && c.b - r >= sa.min_mm && c.b + r <= sa.max_mm;
  if (!circle_inside) {
    const double sweep = arc_sweep(s, e, c, ccw, turns);
    Vec2 lo2, hi2;
    arc_bounds(s, e, c, sweep, lo2, hi2);
    lo[pa.first] = lo2.a;
    lo[pa.second] = lo2.b;
    hi[pa.first] = hi2.a;
    hi[pa.second] = hi2.b;
  }
  check_travel(lo, hi, target, col);

  Block b = base_block(BlockKind::kArc);
  b.col = col;
  b.end = target;
  b.feed_mm_min = modal_.feed_mm_min;
  b.path_mode =
      w.group(GGroup::kExactStopOnce) != nullptr ? PathMode::kExactStop : modal_.path_mode;
  b.tolerance_mm = b.path_mode == PathMode::kBlend ? modal_.tolerance_mm : -1;
  std::array<double, 3> centre{};
  centre[pa.first] = c.a;
  centre[pa.second] = c.b;
  centre[pa.normal] = pos_[pa.normal];  // projected into the plane of the start point
  b.center = {centre[0], centre[1], centre[2]};
  std::array<double, 3> normal{};
  normal[pa.normal] = ccw ? 1.0 : -1.0;
  b.normal = {normal[0], normal[1], normal[2]};
  b.turns = turns;
  out_.push_back(b);
  pos_ = target;
}

// G10 L2 / L20 (work offsets), G92, G92.1, G92.2, G92.3.
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
        fail(w['l'].col, fmt::format("G10 L{} tool table data is not supported", l));
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
          // pos = value + work + g92  →  work = pos − g92 − value
          const double g92 = params_.numbered(kParamG92Applied) != 0
                                 ? params_.numbered(kParamG92 + static_cast<int>(a))
                                 : 0.0;
          value = pos_[a] - g92 - scaled(a);
        }
        params_.set_numbered(work_param(system, a), value);
      }
      break;
    }
    case 920: {
      bool any = false;
      // G92: pos = value + work + g92  →  g92 = pos − work − value, for the named axes.
      for (std::size_t a = 0; a < kMaxAxes; ++a) {
        if (!w[kAxisWords[a]].present) continue;
        any = true;
        const double work = params_.numbered(work_param(modal_.coord_system, a));
        params_.set_numbered(kParamG92 + static_cast<int>(a), pos_[a] - work - scaled(a));
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

// ---------------------------------------------------------------------------------------------

Interpreter::Interpreter(const std::string& path, const MachineConfig& machine,
                         const Options& options)
    : impl_(std::make_unique<Impl>(LineReader::open_file(path), path, machine, options)) {}

Interpreter::Interpreter(FromText, std::string text, std::string name, const MachineConfig& machine,
                         const Options& options)
    : impl_(std::make_unique<Impl>(LineReader::from_text(std::move(text)), std::move(name), machine,
                                   options)) {}

Interpreter::~Interpreter() = default;

bool Interpreter::next(Block& out) {
  return impl_->next(out);
}

bool Interpreter::recover() {
  return impl_->recover();
}
bool Interpreter::beyond_travel() const {
  return impl_->beyond_travel_;
}

}  // namespace cncore::interp
