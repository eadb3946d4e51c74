// Private state of the Interpreter, shared by interpreter.cpp (reading and executing blocks)
// and flow.cpp (O-words, M98/M99).
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "interpreter/codes.hpp"
#include "interpreter/cutter_comp.hpp"
#include "interpreter/expression.hpp"
#include "interpreter/interpreter.hpp"
#include "interpreter/lathe_profile.hpp"
#include "interpreter/lexer.hpp"
#include "interpreter/modal_state.hpp"
#include "interpreter/parameters.hpp"
#include "interpreter/reader.hpp"

namespace cncore::interp {

class PlaneSpline;
struct ThreadPass;
struct LatheCapture;

inline constexpr std::size_t kLinearAxes = 3;
inline constexpr double kZeroMoveMm = 1e-9;  // moves shorter than this are not emitted

// LinuxCNC CENTER_ARC_RADIUS_TOLERANCE_{MM,INCH} = 2·0.01·√2 mm, 2·0.001·√2 in, and the
// relative tolerance 0.1 % (both must be exceeded for an error, or 100× the absolute one).
inline constexpr double kArcAbsTolMm = 2 * 0.01 * 1.4142135623730951;
inline constexpr double kArcAbsTolInch = 2 * 0.001 * 1.4142135623730951;
inline constexpr double kArcRelTol = 0.001;
// R-form: half-chord may exceed |R| by this much (LinuxCNC TOLERANCE_MM / TOLERANCE_INCH).
inline constexpr double kRadiusTolMm = 0.005;
inline constexpr double kRadiusTolInch = 0.0005;
inline constexpr std::array<char, kMaxAxes> kAxisWords = {'x', 'y', 'z', 'a', 'b', 'c'};

inline bool is_rotary(std::size_t axis) {
  return axis >= kLinearAxes;
}

// Parameter numbers (LinuxCNC) for state kept in the parameter table; lengths in mm.
inline constexpr int kParamG28Home = 5161;
inline constexpr int kParamG30Home = 5181;
inline constexpr int kParamG92Applied = 5210;
inline constexpr int kParamG92 = 5211;
inline constexpr int kParamCoordSystem = 5220;
inline constexpr int kParamWorkOffsets = 5221;  // + 20·(system − 1) + axis
inline constexpr int kParamTool = 5400;
inline constexpr int kParamPosition = 5420;
inline constexpr int kParamMachinePosition = 5021;  // current machine position X…C
inline constexpr int kParamProbe = 5061;            // G38 trip point X…W, program coordinates
// The XY rotation (G10 L2 R, degrees) of a system is its tenth number, after X Y Z A B C U V W:
// work_param(system, kRotationSlot), #5230 for G54.
inline constexpr std::size_t kRotationSlot = 9;

bool offset_length_param(int n);  // see frame.cpp

inline int work_param(int system, std::size_t axis) {
  return kParamWorkOffsets + 20 * (system - 1) + static_cast<int>(axis);
}

// The words of one block after evaluation (values as written, program units).
struct Words {
  struct Value {
    double value = 0;
    std::uint32_t col = 0;
    bool present = false;
  };
  struct Code {
    int code10 = 0;  // ten times the value: G59.1 → 591
    std::uint32_t col = 0;
  };
  struct Assignment {
    ParamRef ref;
    double value = 0;
  };
  static constexpr int kMaxCodes = 16;

  std::array<Value, 26> letter{};  // indexed by letter − 'a'
  std::array<Code, kMaxCodes> g{};
  std::array<Code, kMaxCodes> m{};
  int g_count = 0, m_count = 0;
  std::array<int, kGroupSlots> g_group{};   // index into g, or −1
  std::array<int, kMGroupSlots> m_group{};  // index into m, or −1 (coolant: the last one)
  std::vector<Assignment> assignments;
  std::uint32_t first_col = 1;

  void clear() {
    letter.fill({});
    g_count = m_count = 0;
    g_group.fill(-1);
    m_group.fill(-1);
    assignments.clear();
  }
  const Value& operator[](char c) const { return letter[static_cast<std::size_t>(c - 'a')]; }
  bool has(char c) const { return (*this)[c].present; }
  bool has_g(int code10) const {
    for (int i = 0; i < g_count; ++i) {
      if (g[static_cast<std::size_t>(i)].code10 == code10) return true;
    }
    return false;
  }
  bool has_m(int code10) const {
    for (int i = 0; i < m_count; ++i) {
      if (m[static_cast<std::size_t>(i)].code10 == code10) return true;
    }
    return false;
  }
  const Code* group(GGroup grp) const {
    const int i = g_group[static_cast<std::size_t>(grp)];
    return i < 0 ? nullptr : &g[static_cast<std::size_t>(i)];
  }
  const Code* mgroup(MGroup grp) const {
    const int i = m_group[static_cast<std::size_t>(grp)];
    return i < 0 ? nullptr : &m[static_cast<std::size_t>(i)];
  }
};

// O-word keywords.
enum class OKeyword : std::uint8_t {
  kNone,  // "O1000" alone: Fanuc program / subprogram number
  kSub,
  kEndSub,
  kCall,
  kReturn,
  kIf,
  kElseIf,
  kElse,
  kEndIf,
  kWhile,
  kEndWhile,
  kDo,
  kRepeat,
  kEndRepeat,
  kBreak,
  kContinue,
};

struct OWord {
  std::string label;  // "100" for o100 / O0100, "<name>" for o<name>
  OKeyword keyword = OKeyword::kNone;
  std::uint32_t col = 0;
  std::size_t args = 0;  // position in the normalised text after the keyword
};

struct SubDef {
  LinePos body;  // the line after "oN sub" (or after the Fanuc "O1000" line)
  std::uint32_t line = 0;
  std::size_t source = 0;  // the file it is in (Impl::sources_)
};

// A file the interpreter reads: the program (sources_[0]), or the file of a subroutine that
// `o<name> call` found on the subroutine path (name.ngc).
struct Source {
  LineReader reader;
  std::string file;
};

struct Frame {
  std::string label;
  LinePos return_to;              // the line after the call
  std::size_t return_source = 0;  // the file of the call
  LinePos body;                   // for M98 repeats
  std::size_t loop_depth = 0;
  std::uint32_t line = 0, col = 0;  // the call
  std::uint32_t def_line = 0;       // where the subroutine is defined
  std::uint64_t repeats_left = 0;   // M98 L
  bool fanuc = false;               // M98/M99 (no new parameter scope)
};

struct Loop {
  enum class Kind : std::uint8_t { kWhile, kDo, kRepeat };
  std::string label;
  Kind kind = Kind::kWhile;
  LinePos head;  // kWhile: the while line; kDo/kRepeat: the first body line
  std::uint64_t iterations = 0;
  double remaining = 0;  // kRepeat
  std::uint32_t line = 0, col = 0;
};

struct Interpreter::Impl final : LiveParameters {
  Impl(LineReader r, std::string name, MachineConfig m, const Options& options);

  bool next(Block& out);
  bool recover();

  // interpreter.cpp
  void step();                        // read and execute one line
  void parse_words(std::size_t pos);  // fills words_ from line_.text
  void exponent_or_unknown(std::size_t pos, std::size_t value_start, char last_letter) const;
  void execute_words();  // LinuxCNC order of execution
  void refuse_unsupported() const;
  void adaptive_feed_events();  // M52
  void set_path_control(const Words::Code& g, double unit);
  void set_motion_mode(int code10);
  void dwell(std::uint32_t col);  // G4
  void feed_and_speed(double unit);
  void set_feed_mode(int code10);  // G93, G94, G95
  // The path feed of a programmed feed move of `length_mm` in the feed mode (motion.cpp).
  double move_feed_mm_min(double length_mm, std::uint32_t col) const;
  void execute_motion(const Words::Code* nonmodal, bool axes_for_nonmodal, bool have_axes,
                      std::uint32_t first_axis_col);
  void execute_stops();
  void line_motion(const AxisVec& target, std::uint32_t col);        // G0 / G1 (G96 aware)
  void plain_line_motion(const AxisVec& target, std::uint32_t col);  // G0 / G1 as one block
  void arc(const AxisVec& target, bool ccw, std::uint32_t col);
  void probe_motion(const AxisVec& target, std::uint32_t col);  // G38.2 … G38.5 (probe.cpp)
  void emit_arc(const AxisVec& target, Vec2 c, bool ccw, std::uint32_t turns, std::uint32_t col);
  // An arc from pos_ about `c` (plane coordinates, radius growing by dr): travel, feed, block.
  void arc_move(const AxisVec& target, Vec2 c, double dr, bool ccw, std::uint32_t turns,
                std::uint32_t col);
  // A G18/G19 arc in a rotated system turns with it (0 otherwise), about Z.
  double arc_turn_deg() const;
  static AxisVec turned(AxisVec p, double deg);  // X Y turned by deg about Z
  void check_turned_arc_travel(const AxisVec& target, Vec2 c, bool ccw, std::uint32_t turns,
                               std::uint32_t col);
  void check_arc_travel(const AxisVec& target, Vec2 c, double dr, bool ccw, std::uint32_t turns,
                        std::uint32_t col);
  void emit_motion(BlockKind kind, const AxisVec& target, std::uint32_t col);
  PathMode block_path_mode() const;    // G9 or the modal path mode
  void set_path_mode(Block& b) const;  // with G64's tolerance
  // The move to `target` sweeps lo … hi: an error if that leaves the travel (not while the
  // program continues beyond it after such an error, see recover()).
  void check_travel(const AxisVec& lo, const AxisVec& hi, const AxisVec& target, std::uint32_t col);
  void set_offsets();                          // G10, G92 family
  void set_work_offset(int system, bool l20);  // G10 L2 / L20
  void go_home(int code10);                    // G28 / G30 (and .1)
  double offset(std::size_t axis) const;       // work + G92 offset of the active system (mm)

  // frame.cpp: machine = R(θ)·(program + g92) + work + tool
  AxisVec target_from_words(bool machine_coords) const;
  double rotation_deg(int system) const;  // G10 L2 R of a system
  static Vec2 rotated(Vec2 v, double deg);
  AxisVec g92_offset() const;  // the G92/G52 offset while applied, else zero (mm)
  // The program position of machine position `m` with the tool offset `tool`, and back (with
  // the active tool offset).
  AxisVec to_program(const AxisVec& m, const AxisVec& tool) const;
  AxisVec from_program(const AxisVec& p) const;
  bool read_live_named(std::string_view name, double& value) const override;
  bool read_modal_named(std::string_view name, double& value) const;  // named_parameters.cpp
  CanonFrame canon_frame() const;
  Block base_block(BlockKind kind) const;
  void emit_aux(char letter, double value, bool waits);
  bool read_live(int number, double& value) const override;
  void show_message();  // the line's (msg,…) / (debug,…) comment (messages.cpp)
  // A "/" line while the block delete switch is on.
  bool skipped() const { return line_.block_delete && block_delete_; }
  [[noreturn]] void fail(std::uint32_t col, const std::string& message) const {
    ctx_.fail(col, message);
  }

  // spline_motion.cpp: G5, G5.1, G5.2/G5.3 (true: the block was a spline's)
  bool spline_motion(const Words::Code* motion_word, bool have_axes, std::uint32_t col);
  void bezier_spline(bool cubic, std::uint32_t col);
  void nurbs_point(bool opens, bool have_axes);
  void nurbs_end(std::uint32_t col);
  void emit_spline(const PlaneSpline& curve, const AxisVec& target, std::uint32_t col);
  double spline_tolerance_mm() const;
  // lathe_mode.cpp: G7/G8, and the X words of the block as radii
  void apply_lathe_mode();

  // threading.cpp: G33, G33.1, G76, G96/G97
  bool threading_block() const {
    const Words::Code* m = words_.group(GGroup::kMotion);
    return m != nullptr && m->code10 == 760;
  }
  double work_radius_mm(const AxisVec& m) const;
  double css_rpm(double radius_mm, std::uint32_t col) const;
  void spindle_speed_words(double unit);
  void orient_words() const;  // M19 R Q P
  void css_update(const AxisVec& at, std::uint32_t col);
  void css_line(const AxisVec& target, std::uint32_t col);
  double sync_rpm(std::uint32_t col, const char* what) const;
  void emit_sync_line(const AxisVec& target, double mm_rev, std::uint32_t col, const char* what);
  double pitch_word(const char* what) const;
  void spindle_sync_motion(const AxisVec& target, std::uint32_t col);
  void rigid_tap(const AxisVec& target, std::uint32_t col);
  void threading_pass(const ThreadPass& t, double depth, std::uint32_t col);
  void threading_cycle(std::uint32_t col);
  bool in_sync_ = false;  // the last move emitted followed the spindle
  // Stamped on the synchronised lines emitted: G33/G76 D (degrees past the index, NaN: none)
  // and which move of a G33.1 rigid tap is being emitted.
  double sync_start_deg_ = std::numeric_limits<double>::quiet_NaN();
  RigidTap sync_tap_ = RigidTap::kNone;
  double start_angle_word() const;

  // lathe_cycles.cpp: G70, G71, G72 (the profile's subroutine is read while lathe_capture_ is
  // set: its lines add to the profile instead of executing)
  bool lathe_cycle_block() const;
  void lathe_cycle(std::uint32_t col);
  lathe::Profile read_profile(const Words::Value& q, lathe::Pt from);
  void capture_profile_block();
  lathe::Pt profile_centre(lathe::Pt from, lathe::Pt end) const;
  lathe::Pt program_zx() const;  // program position in program units, X a radius
  AxisVec lathe_target(lathe::Pt p) const;
  void lathe_move(bool rapid, lathe::Pt end, std::uint32_t col);
  void lathe_arc(bool ccw, lathe::Pt centre, lathe::Pt end, std::uint32_t col);
  LatheCapture* lathe_capture_ = nullptr;

  // canned_cycles.cpp
  void canned_cycle(std::uint32_t col);
  void cycle_move(bool rapid, const AxisVec& target, std::uint32_t col);
  void cycle_body(std::size_t drill_axis, double r_mm, double bottom_mm, double clear_mm,
                  std::uint32_t col);
  void back_bore(std::size_t drill_axis, double bottom_mm, double clear_mm, std::uint32_t col);
  void back_bore_words(std::uint32_t col);

  // tool_offsets.cpp
  void init_tools(const Options& options);
  const ToolEntry& tool_entry(double number, std::uint32_t col, const char* what);
  void select_tool();                      // T
  void change_tool(const Words::Code& m);  // M6, M61
  void tool_length(const Words::Code& g);  // G43, G43.1, G43.2, G49
  void set_tool_data(int l);               // G10 L1, L10, L11
  // Step 17: G40, G41/G42 [D tool], G41.1/G42.1 D diameter; what cannot run with it on.
  void cutter_comp(double unit);
  void refuse_with_comp() const;
  bool read_tool_param(int number, double& value) const;

  // flow.cpp
  // line_ starts with an O word. `evaluate`: compute "o[expr] call" labels (only when the line
  // runs, never while skipping).
  bool parse_oword(OWord& o, bool evaluate = false) const;
  void execute_oword(const OWord& o);
  void return_from_sub(const OWord& o);  // endsub, return
  void call_sub(const OWord& o);
  void run_if(const OWord& o);
  void run_while(const OWord& o);  // while, and the end of do … while
  void run_repeat(const OWord& o);
  void end_repeat(const OWord& o);
  void leave_loop(const OWord& o);  // break, continue
  OKeyword skip_to(const OWord& from, std::initializer_list<OKeyword> stops, const char* what);
  void skip_fanuc_sub(std::uint32_t def_line);
  const SubDef* find_sub(const std::string& key, std::uint32_t col);
  const SubDef* scan_for_sub(const std::string& key);
  bool next_oword(OWord& o);  // the next line starting with an O word, not executed
  // sub_files.cpp: the subroutine `key` ("<name>") from name.ngc on the subroutine path; null
  // when no such file exists.
  const SubDef* load_sub_file(const std::string& key, std::uint32_t col);
  void enter(std::size_t source, LinePos pos);  // reads on from `pos` in sources_[source]
  void call_fanuc(std::uint32_t col);           // M98
  void return_fanuc(std::uint32_t col);         // M99
  void end_of_file();
  double condition(const OWord& o);
  [[noreturn]] void loop_limit(const Loop& loop) const;
  void count_iteration(Loop& loop);
  void spend(std::uint32_t line, std::uint32_t col);  // one pass of the program's budget

  std::string file_;  // the file being read (the program, or a subroutine's file)
  // The program (sources_[0]). Blocks made in a subroutine's file carry the line and column of
  // the call that entered it from the program, so that everything after the interpreter (the
  // run's report, the operator's current line, cutter compensation's errors) names the program.
  std::string program_file_;
  std::uint32_t entry_line_ = 0, entry_col_ = 0;
  MachineConfig machine_;
  bool block_delete_ = true;
  std::function<void(const std::string&)> on_message_;
  bool zero_length_moves_ = false;
  // The files read (the program first); reader_ is the one being read, sources_[source_].
  std::vector<std::unique_ptr<Source>> sources_;
  std::size_t source_ = 0;
  LineReader* reader_ = nullptr;
  std::vector<std::string> sub_dirs_;  // where o<name> call looks for name.ngc, in order
  NormLine line_;
  ErrorContext ctx_;
  Parameters params_;
  ModalState modal_;
  Words words_;
  AxisVec pos_;  // machine coordinates, mm / deg
  // A move found beyond the travel (its target), for recover(); and whether the interpreter
  // continues from such a target: later blocks are written from there, and their travel is not
  // judged again until the program comes back inside it.
  bool travel_failed_ = false;
  AxisVec travel_target_;
  bool beyond_travel_ = false;

  ToolTable tools_;
  ToolTable implicit_tools_;
  double move_feed_mm_min_ = 0;    // the feed of the programmed move being emitted         // tools
                                   // used without a table: zero offsets
  bool tool_table_given_ = false;  // a table was configured: T of an unlisted tool is an error
  std::uint32_t selected_tool_ = 0;  // T: the tool the next M6 loads
  int comp_code_ = 400;              // G40, G41, G41.1, G42, G42.1 as 400 … 421
  AxisVec tool_offset_{};            // the active tool length offset (G43…), mm / deg
  // Cutter radius compensation: the stage the blocks of each line pass through (from
  // out_[comp_from_]; the blocks before were made under the mode before this line's G40/G41).
  CutterComp comp_{&program_file_};
  std::size_t comp_from_ = 0;

  // A series of G5: where the last one ended and its second control point's offset P Q from
  // there (the next G5 without I J starts along −(P, Q)), machine XY, mm.
  bool g5_chain_ = false;
  AxisVec g5_end_;
  Vec3 g5_pq_;
  // The NURBS being defined between G5.2 and G5.3: control points (the start first), weights.
  bool nurbs_open_ = false;
  int nurbs_order_ = 3;
  std::vector<Vec3> nurbs_ctrl_;
  std::vector<double> nurbs_weights_;

  std::vector<Block> out_;  // blocks of the current line, handed out by next()
  std::size_t out_head_ = 0;
  bool finished_ = false;
  bool at_eof_ = false;          // the reader has reached the end of the file
  bool started_ = false;         // some program line has been executed
  bool produced_ = false;        // some block has been handed out
  bool main_titled_ = false;     // the main program began with a Fanuc "O1234" line
  bool percent_framed_ = false;  // the program began with a "%" line

  std::unordered_map<std::string, SubDef> subs_;
  std::vector<Frame> frames_;
  std::vector<Loop> loops_;
  std::uint64_t passes_ = 0;  // loop passes and calls so far (max_total_iterations)
};

}  // namespace cncore::interp
