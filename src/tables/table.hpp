// Table-format operation (spec 02, seed CN106066630A): axes follow tables of control points
// against a common reference (time, a master axis, the spindle angle), with the reference
// shift SFT / SFTCAN.
//
// Pipeline (the seed's Fig. 3): reader (parse_table) → reference-value analysis (shift flag,
// accumulated amount, cancel mode; indirect amounts read when the row is read) → distribution
// once per interpolation cycle (run_tables). Tables are small and are held in memory; the run
// itself streams: one TableSample per cycle goes to a callback and memory does not grow with
// the length of the run.
//
// Typical use (what `cncore table` does; docs/tables.md has the full example):
//   std::vector<Table> tables{load_table(path1), load_table(path2)};   // InputError
//   options.reference = default_reference(tables.front(), machine, rpm, master_mm_min);
//   TablePlan plan = plan_tables(tables, machine, options);            // InputError
//   if (print_effective) std::cout << format_effective(plan);
//   for (const auto& d : plan.diagnostics) std::cerr << d.formatted() << '\n';
//   if (plan.has_errors()) return 1;
//   auto write = [&](const TableSample& ts) { observer.on_sample(to_motion_sample(ts)); };
//   RunSummary s = run_tables(plan, write);  // ts.ref for the `ref` column
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "config/machine_config.hpp"
#include "core/geometry.hpp"
#include "motion/kernel.hpp"

namespace cncore::tables {

enum class RefKind : std::uint8_t {
  kTime,     // REF TIME: milliseconds since the start
  kAxis,     // REF AXIS X: position of a master axis (mm, or deg for a rotary axis)
  kSpindle,  // REF SPINDLE: spindle angle in degrees, counted across revolutions
};

enum class Interp : std::uint8_t {
  kLinear,  // the seed: coordinate proportional to the reference between control points
  kCubic,   // monotone cubic Hermite (Fritsch–Carlson): velocity continuous, no overshoot
};

// What SFTCAN does with the accumulated shift (a machine setting, [tables] cancel_mode).
enum class CancelMode : std::uint8_t {
  kClear,   // amount := 0: the SFTCAN row and later rows use their written reference values
  kRebase,  // the running reference is reset by the amount: later gaps stay shifted
};

// Settings the machine configuration carries (section [tables]).
struct TableSettings {
  CancelMode cancel_mode = CancelMode::kClear;
  // When a table would exceed an axis speed (or, for CUBIC, acceleration) limit: false → the
  // violations are errors and the run is refused; true → the whole reference is slowed by one
  // constant factor so that every segment fits, and the violations become warnings.
  bool slow_to_fit = false;
};

// ---------------------------------------------------------------------------------------------
// Table data (reader output)

struct Shift {
  enum class Kind : std::uint8_t { kNone, kDirect, kParam, kMacro, kSignal };
  Kind kind = Kind::kNone;
  double amount = 0;      // kDirect
  int number = 0;         // P<n>, #<n>, R<n>
  std::uint32_t col = 0;  // column of "SFT"
};

struct Row {
  std::uint32_t line = 0;
  std::uint32_t col = 0;  // column of the L word
  double ref_written = 0;
  std::uint32_t axis_mask = 0;  // bit i set: axis slot i is written in this row
  AxisVec target;               // written coordinates (slots in axis_mask)
  std::vector<int> m_codes;
  Shift shift;
  bool cancel = false;  // SFTCAN
  std::uint32_t cancel_col = 0;
};

struct Table {
  std::string file;
  RefKind ref_kind = RefKind::kTime;
  std::size_t ref_axis = 0;  // kAxis: the master axis slot
  std::uint32_t ref_line = 0, ref_col = 0;
  std::uint32_t axis_mask = 0;  // axes this table drives (AXES header)
  std::uint32_t axes_line = 0;
  std::array<std::uint32_t, kMaxAxes> axis_cols{};  // column of each axis letter in AXES
  Interp interp = Interp::kLinear;
  bool cyclic = false;
  std::uint32_t cyclic_repeats = 0;  // CYCLIC <n>; 0: RunOptions::cyclic_repeats
  std::vector<Row> rows;
};

// Reader. Syntax errors (unknown address, missing amount, header problems) → InputError.
Table parse_table(std::string_view text, const std::string& file);
Table load_table(const std::string& path);

// ---------------------------------------------------------------------------------------------
// Indirect amounts and the reference

// A signal change while the table runs: from time t_s on, R<number> reads value.
struct SignalChange {
  double t_s = 0;
  int number = 0;
  double value = 0;
};

struct Values {
  std::map<int, double> params;              // SFT=P<n>
  std::map<int, double> macros;              // SFT=#<n>
  std::map<int, double> signals;             // SFT=R<n>, value at t = 0
  std::vector<SignalChange> signal_changes;  // applied at the first read with t >= t_s
};

// "R1001=2.5" (--signal) and "1.5:R1001=2.5" (--signal-at, time in s). Errors name `option`.
std::pair<int, double> parse_signal(std::string_view text, const std::string& option);
SignalChange parse_signal_at(std::string_view text, const std::string& option);

struct ReferenceSource {
  // Reference value at t = 0 (ms, mm or deg) and its rate (units per second). The time clock
  // is 0 and 1000; a master axis at F mm/min is its start position and F/60; a spindle at S
  // rpm is its start angle and 6·S (360°/rev / 60 s/min).
  double start = 0;
  double rate_per_s = 1000;
  // Master axis moved by someone else (e.g. a part program): its position per cycle. When set,
  // it replaces start + rate·t; the rate is then only used for the limit check (0: skip it).
  // plan_tables calls it once with t = 0 (the start reference); run_tables then calls it once
  // per cycle with increasing t from the second cycle on, so it may step a simulation. The plan
  // keeps a copy of the options: capture a stateful master by reference.
  // The table follows the master forwards only: when the master goes back, the reference
  // holds at the highest value reached until the master passes it again.
  std::function<double(double t_s)> position;

  static ReferenceSource time_clock() { return {0, 1000, {}}; }
  static ReferenceSource master_axis(double start_mm, double speed_mm_min) {
    return {start_mm, speed_mm_min / 60.0, {}};
  }
  static ReferenceSource spindle(double rpm, double start_deg = 0) {
    return {start_deg, rpm * 6.0, {}};
  }
};

// The reference source for the tables' REF kind, as the command line would build it: the time
// clock for REF TIME; the spindle at spindle_rpm for REF SPINDLE; for REF AXIS the master axis
// from its machine start position at master_speed_mm_min. Throws InputError (at the REF line)
// when the speed it needs is not > 0.
ReferenceSource default_reference(const Table& first, const MachineConfig& machine,
                                  double spindle_rpm, double master_speed_mm_min);

struct RunOptions {
  TableSettings settings;
  ReferenceSource reference = ReferenceSource::time_clock();
  Values values;
  std::uint32_t cyclic_repeats = 1;  // repetitions of a CYCLIC table without a count
  // With a master position function (which may stall): a run that has not ended by then stops
  // with finished = false. Clock and constant-rate references always reach the end.
  double max_time_s = 3600;
};

// ---------------------------------------------------------------------------------------------
// Plan: validation, effective tables (values at t = 0), limit check

struct Diagnostic {
  enum class Severity : std::uint8_t { kWarning, kError };
  Severity severity = Severity::kWarning;
  std::string file;
  std::uint32_t line = 0, col = 0;
  std::string message;
  std::string formatted() const;  // FILE:LINE:COL: error|warning: MESSAGE
};

// One control point after reference-value analysis.
struct EffectivePoint {
  double ref = 0;               // in source terms (what the reference source delivers)
  AxisVec position;             // positions of the table's axes (modal: unwritten axes stay)
  std::int32_t row = -1;        // index into Table::rows; -1: implicit start point
  std::int32_t extra_row = -1;  // cyclic: first row of the next repetition, same point
  double shift = 0;             // accumulated amount when the row was read
  bool shifting = false;        // shift flag after the row
};

struct TablePlan {
  std::vector<Table> tables;
  MachineConfig machine;
  RunOptions options;
  // One repetition of each table, analysed with the values at t = 0 (for printing and for the
  // limit check; the run re-reads rows when it reaches them, so signals changed later apply).
  std::vector<std::vector<EffectivePoint>> effective;
  std::vector<Diagnostic> diagnostics;
  double slow_factor = 1;  // ≥ 1: the reference runs 1/slow_factor as fast (slow_to_fit)
  AxisVec start_position;  // where the run starts (first points at the start reference)
  double start_ref = 0;    // the reference value at t = 0

  bool has_errors() const;
};

// Validates the tables against the machine (configured axes, one table per axis, one
// reference kind, master axis), analyses them and checks the axis limits. Bad input →
// InputError (FILE:LINE:COL). Limit violations → diagnostics (see TableSettings::slow_to_fit).
TablePlan plan_tables(std::vector<Table> tables, const MachineConfig& machine,
                      const RunOptions& options);

// Cycles of the post-interpolation moving average that run_tables applies to the table axes
// ([motion] post_filter_s, the seed's acc/dec after interpolation): round(post_filter_s / τ),
// at least 1 (1: no filter).
std::size_t post_filter_cycles(const MachineConfig& machine);

// The effective (shifted) tables as table text that reads back as the same motion.
std::string format_effective(const TablePlan& plan);

// ---------------------------------------------------------------------------------------------
// Run

struct MEvent {
  std::uint8_t table = 0;
  std::uint32_t line = 0;
  int code = 0;
};

struct TableSample {
  double t_s = 0;
  double ref = 0;          // reference value from the source (ms, mm or deg)
  AxisVec position;        // every axis: table axes, master axis, others at start
  double feed_mm_min = 0;  // path speed of X, Y, Z over the last cycle
  std::uint32_t line = 0;  // active row (segment end) of the first table
  std::array<std::uint32_t, kMaxAxes> lines{};  // active row of each table
  std::vector<MEvent> m_codes;  // M codes of the control points reached in this cycle
};

struct RunSummary {
  std::uint64_t cycles = 0;
  double duration_s = 0;
  double end_ref = 0;
  bool finished = true;  // false: stopped at max_time_s
  std::vector<std::string> warnings;
};

// Runs the plan to completion, one sample per interpolation period from t = 0. Refuses a plan
// with errors (throws InputError of the first one). Rows are read as the reference reaches
// them; a signal change that makes a row's reference go backwards throws InputError (samples
// delivered before stay delivered). The callback's sample is reused: copy what you keep.
RunSummary run_tables(const TablePlan& plan,
                      const std::function<void(const TableSample&)>& on_sample);

// For the trajectory writers: a table sample as a motion sample (path_position = position;
// aux = first M code of the cycle).
motion::Sample to_motion_sample(const TableSample& sample);

}  // namespace cncore::tables
