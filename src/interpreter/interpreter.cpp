// Reading and executing blocks: word parsing, modal-group checks, and the LinuxCNC order of
// execution within a block. Moves are made in motion.cpp, offsets in offsets.cpp, flow control
// (O-words, M98/M99) in flow.cpp, the arc geometry in arcs.cpp; every line's blocks pass through
// cutter radius compensation (cutter_comp.cpp).
#include "interpreter/interpreter.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

Interpreter::Impl::Impl(LineReader r, std::string name, MachineConfig m, const Options& options)
    : file_(std::move(name)),
      program_file_(file_),
      machine_(std::move(m)),
      sub_dirs_(options.subroutine_path) {
  sources_.push_back(std::make_unique<Source>(Source{std::move(r), file_}));
  reader_ = &sources_[0]->reader;
  ctx_.file = &file_;
  params_.set_live(this);
  for (std::size_t a = 0; a < kMaxAxes; ++a) pos_[a] = machine_.start_position[a];
  if (options.modal) modal_ = *options.modal;
  params_.set_numbered(kParamCoordSystem, modal_.coord_system);
  // LinuxCNC defines these before any call returns, so a program may read them at once.
  params_.set_named("_value", 0);
  params_.set_named("_value_returned", 0);
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
  init_tools(options);
  block_delete_ = options.block_delete;
  on_message_ = options.on_message;
  zero_length_moves_ = options.zero_length_moves;
  out_.reserve(8);
  words_.assignments.reserve(8);
}

bool Interpreter::Impl::next(Block& out) {
  while (out_head_ >= out_.size()) {
    out_.clear();
    out_head_ = 0;
    comp_from_ = 0;
    if (finished_) return false;
    step();
    comp_.pass(out_, comp_from_);
    if (finished_) comp_.finish(out_, ctx_.line, words_.first_col);
  }
  out = out_[out_head_++];
  produced_ = true;
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
  comp_.recover();
  out_.clear();
  out_head_ = 0;
  words_.clear();
  if (at_eof_) finished_ = true;  // an error at the end (unclosed sub, loop, ...) ends it
  return !finished_;
}

// ---------------------------------------------------------------------------------------------
// Reading one line

void Interpreter::Impl::step() {
  std::string_view raw;
  if (!reader_->next(raw)) {
    at_eof_ = true;
    end_of_file();
    return;
  }
  ctx_.line = reader_->current().line;
  normalize_line(raw, line_, ctx_);
  if (skipped()) return;
  if (line_.percent) {
    // "%" opens the program on its first line; a second "%" ends it.
    if (!started_ && !percent_framed_) {
      percent_framed_ = true;
    } else if (percent_framed_) {
      finished_ = true;
    }
    return;
  }
  if (line_.message != NormLine::Message::kNone) show_message();
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
    parse_oword(o, true);
    execute_oword(o);
    started_ = true;
    return;
  }
  parse_words(pos);
  started_ = true;
  if (lathe_capture_ != nullptr) {
    capture_profile_block();  // a line of a lathe cycle's profile (lathe_cycles.cpp)
  } else {
    execute_words();
  }
}

// An E word at t[pos]. Right after the digits of an axis or parameter value ("X1e400") it is
// C's exponent notation, which G-code does not have: say so. Else it is a word (G76's taper
// length; unknown in any other block, see execute_words).
void Interpreter::Impl::exponent_or_unknown(std::size_t pos, std::size_t value_start,
                                            char last_letter) const {
  const std::string& t = line_.text;
  // Written together, as in "1e400" (not "X10 E5": spaces are gone from the text, not from
  // the column map).
  const bool after_number = pos > value_start && (is_digit(t[pos - 1]) || t[pos - 1] == '.') &&
                            line_.col(pos) == line_.col(pos - 1) + 1 &&
                            line_.col(pos + 1) == line_.col(pos) + 1;
  std::size_t e = pos + 1;
  if (e < t.size() && (t[e] == '-' || t[e] == '+')) ++e;
  if (after_number && last_letter != 'g' && last_letter != 'm' && e < t.size() && is_digit(t[e])) {
    while (e < t.size() && is_digit(t[e])) ++e;
    std::size_t start = pos;
    while (start > value_start && (is_digit(t[start - 1]) || t[start - 1] == '.')) --start;
    fail(line_.col(start), "bad number '" + printable(t.substr(start, e - start)) +
                               "': G-code numbers have no exponent (write the digits out)");
  }
}

// Size: one pass over the line's characters, one branch per kind of word (letter, parameter
// assignment, comment, O-word, error); split, each branch would need the whole scan state.
void Interpreter::Impl::parse_words(std::size_t pos) {
  Words& w = words_;
  w.clear();
  w.first_col = line_.col(pos);
  Evaluator eval(line_, ctx_, params_);
  const std::string& t = line_.text;
  char last_letter = 0;         // the word letter before the current one
  std::size_t value_start = 0;  // where that word's value began
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
      fail(col, fmt::format("unexpected character '{}'", printable(c)));
    }
    const char upper = static_cast<char>(c - 'a' + 'A');
    switch (c) {
      case 'n':
        fail(col, "N word (line number) must be at the start of the line");
      case 'o':
        fail(col, "O word must be at the start of the line");
      case 'e':
        exponent_or_unknown(pos, value_start, last_letter);  // G76 reads E; an exponent fails
        break;
      case 'v':
        fail(col, fmt::format("{} axis is not supported (cncore axes: X Y Z A B C)", upper));
      case 'g':
      case 'm': {
        ++pos;
        last_letter = c;
        value_start = pos;
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
        if (slot >= 0 && is_g && info.group == static_cast<int>(GGroup::kMotion) &&
            (code10 == 800 || list[static_cast<std::size_t>(slot)].code10 == 800)) {
          // "G0 G80" (Fanuc, where G80 has a group of its own): the cycle is cancelled and
          // the other motion code is the block's motion.
          if (code10 != 800) list[static_cast<std::size_t>(slot)] = {code10, col};
          continue;
        }
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
    last_letter = c;
    value_start = pos;
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
      const bool inch = machine_.parameters_inch && offset_length_param(a.ref.number);
      params_.set_numbered(a.ref.number, inch ? a.value * 25.4 : a.value);
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
  b.line = source_ == 0 ? ctx_.line : entry_line_;
  b.col = source_ == 0 ? words_.first_col : entry_col_;
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
  refuse_unsupported();
  apply_lathe_mode();

  // The units of this block: a G20/G21 in the block applies to all its numbers (cncore reads
  // F with them too, so "G20 F10" is 10 in/min).
  bool inch = modal_.inch;
  if (const auto* u = w.group(GGroup::kUnits)) inch = u->code10 == 200;
  const double unit = inch ? 25.4 : 1.0;

  if (const auto* g = w.group(GGroup::kFeedMode)) set_feed_mode(g->code10);  // 3 feed mode
  feed_and_speed(unit);                                                      // 4 F, 5 S
  // 6 T (select: the tool is prepared; M6 makes it current), 8 M6 / M61
  if (w.has('t')) select_tool();
  if (const auto* m = w.mgroup(MGroup::kToolChange)) change_tool(*m);
  // 9 spindle
  if (const auto* m = w.mgroup(MGroup::kSpindle)) {
    if (m->code10 == 190) orient_words();
    modal_.spindle_dir = m->code10 == 30 ? 1 : m->code10 == 40 ? -1 : 0;
    emit_aux('M', m->code10 / 10.0, true);
  }
  // 10 overrides
  adaptive_feed_events();
  // 11 coolant (M7 and M8 may both be present)
  for (int i = 0; i < w.m_count; ++i) {
    const int code10 = w.m[static_cast<std::size_t>(i)].code10;
    if (code10 == 70 || code10 == 80 || code10 == 90) emit_aux('M', code10 / 10.0, false);
  }
  // 12 user-defined M codes: M160 / M161 switch the direction feed correction (spec 03) on / off
  // from this block's motion on. No stop: the correction stage acts on the event in the stream.
  if (const auto* m = w.mgroup(MGroup::kUser)) emit_aux('M', m->code10 / 10.0, false);
  // 14 dwell
  const Words::Code* nonmodal = w.group(GGroup::kNonModal);
  const int nm = nonmodal != nullptr ? nonmodal->code10 : -1;
  if (nm == 40) dwell(nonmodal->col);
  // 15 plane
  if (const auto* g = w.group(GGroup::kPlane)) {
    modal_.plane = g->code10 == 170 ? Plane::kXY : g->code10 == 180 ? Plane::kZX : Plane::kYZ;
  }
  // 16 units
  modal_.inch = inch;
  // 17 cutter radius compensation, 18 tool length offset.
  cutter_comp(unit);
  if (const auto* g = w.group(GGroup::kToolLength)) {
    tool_length(*g);
  } else if (w.has('h') && !threading_block()) {
    fail(w['h'].col, "H word without G43 or G43.2");
  }
  // 19 coordinate system
  if (const auto* g = w.group(GGroup::kCoordSystem)) {
    modal_.coord_system = g->code10 <= 590 ? (g->code10 - 540) / 10 + 1 : 7 + (g->code10 - 591);
    params_.set_numbered(kParamCoordSystem, modal_.coord_system);
  }
  // 20 path control
  if (const auto* g = w.group(GGroup::kPathControl)) set_path_control(*g, unit);
  // 21 distance mode, 22 arc distance mode
  if (const auto* g = w.group(GGroup::kDistance)) modal_.absolute = g->code10 == 900;
  if (const auto* g = w.group(GGroup::kArcDistance)) modal_.arc_absolute = g->code10 == 901;
  // 23 G98/G99: the canned cycles' retract mode
  if (const auto* g = w.group(GGroup::kCannedReturn)) modal_.retract_to_r = g->code10 == 990;

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
  const Words::Code* tool_word = w.group(GGroup::kToolLength);
  const int axes_user =
      (tool_word != nullptr && tool_word->code10 != 430 && tool_word->code10 != 490)
          ? tool_word->code10  // G43.1, G43.2 take offsets from axis words
          : nm;
  const bool axes_for_nonmodal = axes_user == 100 || axes_user == 280 || axes_user == 300 ||
                                 axes_user == 520 || axes_user == 920 || axes_user == 431 ||
                                 axes_user == 432;
  if (axes_for_nonmodal && motion_word != nullptr && motion_word->code10 != 800 && have_axes) {
    fail(motion_word->col,
         fmt::format("{} and {} both use the axis words", code_text('G', axes_user),
                     code_text('G', motion_word->code10)));
  }

  // 24 offsets and homing
  if (nm == 100 || nm == 520 || nm == 920 || nm == 921 || nm == 922 || nm == 923) set_offsets();
  if (nm == 280 || nm == 281 || nm == 300 || nm == 301) go_home(nm);

  // 25 motion
  execute_motion(nonmodal, axes_for_nonmodal, have_axes, first_axis_col);

  // 26 stops
  execute_stops();
}

// Step 25: the motion mode of the block, and the move its axis words ask for (unless a
// non-modal code of the block took them).
void Interpreter::Impl::execute_motion(const Words::Code* nonmodal, bool axes_for_nonmodal,
                                       bool have_axes, std::uint32_t first_axis_col) {
  const Words& w = words_;
  const int nm = nonmodal != nullptr ? nonmodal->code10 : -1;
  const Words::Code* motion_word = w.group(GGroup::kMotion);
  if (motion_word != nullptr) set_motion_mode(motion_word->code10);
  if (motion_word != nullptr && modal_.motion == Motion::kProbe && !have_axes) {
    fail(motion_word->col, fmt::format("G38.{} without axis words", motion_word->code10 - 380));
  }
  const bool arc_mode = modal_.motion == Motion::kArcCw || modal_.motion == Motion::kArcCcw;
  const bool have_centre = w.has('i') || w.has('j') || w.has('k');
  const bool cycle_mode = modal_.motion == Motion::kCycle;
  const bool spline_ij =
      modal_.motion == Motion::kCubicSpline || modal_.motion == Motion::kQuadSpline;
  const bool sync_mode =
      modal_.motion == Motion::kSpindleSync || modal_.motion == Motion::kRigidTap;
  if (!arc_mode && !threading_block() && !lathe_cycle_block()) {
    for (char c : {'i', 'j', 'k', 'r'}) {
      const bool sync_word =
          sync_mode && (c == 'k' || (c == 'i' && modal_.motion == Motion::kRigidTap));
      const bool back_bore_word = cycle_mode && modal_.cycle == 870 && c != 'r';
      const bool orient_word = c == 'r' && w.has_m(190);  // M19 R: the angle
      const Words::Code* path = w.group(GGroup::kPathControl);
      const bool planner_word = c == 'r' && path != nullptr && path->code10 == 640;
      if (orient_word && planner_word && w.has('r')) {
        fail(w['r'].col,
             "R is ambiguous with G64 and M19 in one block: put them on separate lines");
      }
      if (w.has(c) && !(c == 'r' && (nm == 100 || cycle_mode)) && !(spline_ij && c != 'r') &&
          !sync_word && !back_bore_word && !orient_word && !planner_word) {
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
    if (spline_motion(motion_word, have_axes, col)) return;
    if (threading_block()) {
      threading_cycle(motion_word->col);
      modal_.motion = Motion::kNone;  // G76 acts on its own block
      return;
    }
    if (lathe_cycle_block()) {
      lathe_cycle(motion_word->col);
      return;
    }
    const bool cycle_words = cycle_mode && (w.has('r') || motion_word != nullptr);
    if (have_axes || (arc_mode && (have_centre || w.has('r'))) || cycle_words) {
      if (modal_.motion == Motion::kNone) {
        fail(have_axes ? first_axis_col : w.first_col,
             "axis words without a motion mode: program G0, G1, G2 or G3 first");
      }
      if (cycle_mode) {
        if (machine_coords) fail(nonmodal->col, "G53 with a canned cycle");
        canned_cycle(motion_word != nullptr ? motion_word->col : col);
      } else if (const AxisVec target = target_from_words(machine_coords); arc_mode) {
        arc(target, modal_.motion == Motion::kArcCcw, col);
      } else if (modal_.motion == Motion::kProbe) {
        probe_motion(target, col);
      } else if (modal_.motion == Motion::kSpindleSync) {
        spindle_sync_motion(target, col);
      } else if (modal_.motion == Motion::kRigidTap) {
        rigid_tap(target, col);
      } else {
        line_motion(target, col);
      }
    }
  }
}

// Step 3: G93, G94, G95. A change of mode asks for a new F (its meaning changed).
void Interpreter::Impl::set_feed_mode(int code10) {
  const FeedMode mode = code10 == 930   ? FeedMode::kInverseTime
                        : code10 == 950 ? FeedMode::kPerRevolution
                                        : FeedMode::kPerMinute;
  if (mode != modal_.feed_mode) modal_.feed_set = false;
  modal_.feed_mode = mode;
}

// Steps 4 and 5: F (in the feed mode's units: the block's length unit per minute or per
// revolution; in G93 the inverse of the move's time in minutes, read by the move) and S.
void Interpreter::Impl::feed_and_speed(double unit) {
  const Words& w = words_;
  if (w.has('f')) {
    if (w['f'].value < 0) fail(w['f'].col, "negative feed rate F");
    if (modal_.feed_mode == FeedMode::kPerRevolution) {
      modal_.feed_mm_rev = w['f'].value * unit;
    } else if (modal_.feed_mode == FeedMode::kPerMinute) {
      modal_.feed_mm_min = w['f'].value * unit;
    }
    modal_.feed_set = true;
  }
  spindle_speed_words(unit);
}

// G4 P<seconds>.
void Interpreter::Impl::dwell(std::uint32_t col) {
  const Words& w = words_;
  if (!w.has('p')) fail(col, "G4 dwell without P (seconds)");
  if (w['p'].value < 0) fail(w['p'].col, "negative dwell time P");
  Block b = base_block(BlockKind::kDwell);
  b.dwell_s = w['p'].value;
  out_.push_back(b);
}

// Everything beyond cncore's dialect is refused first, naming the feature.
void Interpreter::Impl::refuse_unsupported() const {
  const Words& w = words_;
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
  // E: G76's taper and G70's last allowance only; U W: the lathe cycles' allowances.
  const Words::Code* motion = w.group(GGroup::kMotion);
  const bool finishing = motion != nullptr && motion->code10 == 700;
  if (w.has('e') && !threading_block() && !finishing) fail(w['e'].col, "unknown word 'E'");
  for (const char c : {'u', 'w'}) {
    if (w.has(c) && !lathe_cycle_block()) {
      fail(w[c].col, fmt::format("{} axis is not supported (cncore axes: X Y Z A B C)",
                                 static_cast<char>(c - 'a' + 'A')));
    }
  }
}

// Step 10 of the order of execution: M52 adaptive feed control (spec 04), P1 or no P on, P0
// off. An aux event that does not stop the motion: it takes effect where the tool passes it.
void Interpreter::Impl::adaptive_feed_events() {
  const Words& w = words_;
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
}

// Step 20: G61 exact path, G61.1 exact stop, G64 [P tolerance] [Q smoothing tolerance] [R].
void Interpreter::Impl::set_path_control(const Words::Code& g, double unit) {
  const Words& w = words_;
  if (g.code10 == 610) {
    modal_.path_mode = PathMode::kExactPath;
    modal_.tolerance_mm = -1;
  } else if (g.code10 == 611) {
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
    // G64 R: another planner's peak-acceleration scale (LinuxCNC-derived controls); cncore's
    // planner keeps its own limits, so the word is read and checked but changes nothing.
    if (w.has('r') && w['r'].value < 0) fail(w['r'].col, "negative G64 R");
  }
}

void Interpreter::Impl::set_motion_mode(int code10) {
  // A new series of canned cycles starts at the next cycle block (its initial level).
  if (modal_.motion != Motion::kCycle || modal_.cycle != code10) modal_.cycle_initial_set = false;
  switch (code10) {
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
    case 800:
    case 53:  // G5.3 closes a NURBS block (spline_motion.cpp)
      modal_.motion = Motion::kNone;
      break;
    case 382:
    case 383:
    case 384:
    case 385:
      modal_.motion = Motion::kProbe;
      modal_.probe_code = code10;
      break;
    case 50:
      modal_.motion = Motion::kCubicSpline;
      break;
    case 51:
      modal_.motion = Motion::kQuadSpline;
      break;
    case 52:
      modal_.motion = Motion::kNurbs;
      break;
    case 330:
      modal_.motion = Motion::kSpindleSync;
      break;
    case 331:
      modal_.motion = Motion::kRigidTap;
      break;
    default:
      modal_.motion = Motion::kCycle;
      modal_.cycle = code10;
      break;
  }
}

// Step 26: program stops and ends, M99 return, M98 call.
void Interpreter::Impl::execute_stops() {
  const Words& w = words_;
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

// ---------------------------------------------------------------------------------------------

Interpreter::Interpreter(const std::string& path, const MachineConfig& machine,
                         const Options& options)
    : impl_(std::make_unique<Impl>(LineReader::open_file(path), path, machine, options)) {
  // The program's own folder is searched first for the files of its subroutines.
  impl_->sub_dirs_.insert(impl_->sub_dirs_.begin(),
                          std::filesystem::path(path).parent_path().string());
}

Interpreter::Interpreter(FromText, std::string text, std::string name, const MachineConfig& machine,
                         const Options& options)
    : impl_(std::make_unique<Impl>(LineReader::from_text(std::move(text)), std::move(name), machine,
                                   options)) {}

Interpreter::Interpreter(FromLines, LineReader::Pull pull, std::string name,
                         const MachineConfig& machine, const Options& options)
    : impl_(std::make_unique<Impl>(LineReader::pulled(std::move(pull)), std::move(name), machine,
                                   options)) {
  impl_->reader_->set_name(impl_->file_);
}

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

CanonFrame Interpreter::canon_frame() const {
  return impl_->canon_frame();
}

}  // namespace cncore::interp
