// `cncore table`: run axis tables against a reference (time, master axis or program, spindle)
// with SFT/SFTCAN; write the trajectory and summary outputs.
#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "app/progress.hpp"
#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/report_table.hpp"
#include "io/summary.hpp"
#include "io/trajectory_csv.hpp"
#include "simulation/stepper.hpp"
#include "tables/table.hpp"

namespace cncore::app {
namespace {

// "N=V" with an integer N >= 0 (an optional leading prefix such as '#' or 'P' is accepted).
std::pair<int, double> numbered_value(const std::string& option, const std::string& arg,
                                      char prefix) {
  auto [name, value] = name_value(option, arg);
  std::string_view n(name);
  if (!n.empty() && std::toupper(static_cast<unsigned char>(n.front())) == prefix) {
    n.remove_prefix(1);
  }
  int number = 0;
  const auto [end, ec] = std::from_chars(n.data(), n.data() + n.size(), number);
  if (n.empty() || ec != std::errc() || end != n.data() + n.size() || number < 0) {
    throw UsageError(fmt::format("{}: '{}': the number must be an integer >= 0", option, arg));
  }
  return {number, value};
}

// Bad --signal / --signal-at text is a usage error (exit 2), not an input-file error.
template <typename F>
auto usage_on_input_error(const std::string& option, const std::string& arg, F&& f) {
  try {
    return f();
  } catch (const InputError& e) {
    throw UsageError(fmt::format("{}: '{}': {}", option, arg, e.what()));
  }
}

// The reference of the tables ("time", "axis X", "spindle") and its unit (ms, mm, deg).
std::pair<std::string, std::string> reference_name_and_unit(const tables::TablePlan& plan,
                                                            const MachineConfig& machine) {
  static constexpr const char* kUnits[] = {"ms", "mm", "deg"};
  const tables::Table& first = plan.tables.front();
  std::string ref_name = "time";
  if (first.ref_kind == tables::RefKind::kAxis) {
    ref_name = fmt::format("axis {}", kAxisLetters[first.ref_axis]);
  } else if (first.ref_kind == tables::RefKind::kSpindle) {
    ref_name = "spindle";
  }
  const char* unit = kUnits[static_cast<int>(first.ref_kind)];
  if (first.ref_kind == tables::RefKind::kAxis && machine.axes[first.ref_axis].rotary) {
    unit = "deg";
  }
  return {ref_name, unit};
}

std::string format_table_summary(const io::Summary& s, const tables::RunSummary& r,
                                 const tables::TablePlan& plan, const MachineConfig& machine) {
  const auto [ref_name, unit] = reference_name_and_unit(plan, machine);
  std::string o;
  for (const tables::Table& t : plan.tables) {
    std::string axes;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      if ((t.axis_mask >> i) & 1U) axes += kAxisLetters[i];
    }
    o += fmt::format("table         {} (axes {}, {} rows{}{})\n", t.file, axes, t.rows.size(),
                     t.interp == tables::Interp::kCubic ? ", cubic" : ", linear",
                     t.cyclic ? ", cyclic" : "");
  }
  o += fmt::format(
      "machine       {} (period {} ms, SFTCAN {})\n", machine.name, machine.period_s * 1000,
      plan.options.settings.cancel_mode == tables::CancelMode::kRebase ? "rebase" : "clear");
  o += fmt::format("cycle time    {:.3f} s ({} cycles){}\n", s.cycle_time_s, s.cycles,
                   r.finished ? "" : " — stopped before the end");
  o += fmt::format("reference     {} {:.6g} … {:.6g} {}\n", ref_name, plan.start_ref, r.end_ref,
                   unit);
  if (plan.slow_factor > 1) {
    o += fmt::format("slowed        reference runs {:.4g} times slower to fit the axis limits\n",
                     plan.slow_factor);
  }
  std::string speeds, accels;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!machine.axes[i].enabled) continue;
    speeds += fmt::format("{}{} {:.1f} (limit {:.0f})", speeds.empty() ? "" : ", ", kAxisLetters[i],
                          s.max_axis_speed_mm_min[i], machine.axes[i].max_speed_mm_min);
    accels += fmt::format("{}{} {:.1f} (limit {:.0f})", accels.empty() ? "" : ", ", kAxisLetters[i],
                          s.max_axis_accel_mm_s2[i], machine.axes[i].max_accel_mm_s2);
  }
  o += fmt::format("axis speed    {} (mm/min or deg/min)\n", speeds);
  o += fmt::format("axis accel    {} (mm/s² or deg/s²)\n", accels);
  o += fmt::format("path length   {:.3f} mm (X Y Z)\n", s.path_length_mm);
  if (s.aux_event_count > 0) {
    std::string list;
    for (std::size_t i = 0; i < s.aux_events.size() && i < 8; ++i) {
      const io::AuxEvent& e = s.aux_events[i];
      list += fmt::format("{}{}{:g} at {:.3f} s (line {})", i > 0 ? ", " : "", e.letter, e.value,
                          e.t_s, e.line);
    }
    o += fmt::format("m codes       {} fired: {}{}\n", s.aux_event_count, list,
                     s.aux_event_count > 8 ? ", …" : "");
  }
  for (const std::string& w : s.warnings) o += fmt::format("warning: {}\n", w);
  for (const std::string& w : r.warnings) o += fmt::format("warning: {}\n", w);
  return o;
}

}  // namespace

// Size: `cncore table` wires the options to the table run in order: settings from the
// configuration and the command line, the master-axis program, outputs, the summary.
int command_table(const TableArgs& a) {
  const MachineConfig machine = machine_from(a.machine);
  const ProgressMode progress_shown = progress_mode(a.progress);
  tables::RunOptions options;
  options.settings.cancel_mode = machine.table_cancel_mode == TableCancelMode::kRebase
                                     ? tables::CancelMode::kRebase
                                     : tables::CancelMode::kClear;
  options.settings.slow_to_fit = machine.table_slow_to_fit;
  options.cyclic_repeats = a.repeat;
  // Values from the configuration first; the command line overrides them number by number.
  options.values.params = machine.table_parameters;
  options.values.macros = machine.table_variables;
  options.values.signals = machine.table_signals;
  for (const std::string& p : a.params) {
    const auto [n, v] = numbered_value("--param", p, 'P');
    options.values.params[n] = v;
  }
  for (const std::string& p : a.vars) {
    const auto [n, v] = numbered_value("--var", p, '#');
    options.values.macros[n] = v;
  }
  for (const std::string& p : a.signals) {
    const auto [n, v] =
        usage_on_input_error("--signal", p, [&] { return tables::parse_signal(p, "--signal"); });
    options.values.signals[n] = v;
  }
  for (const std::string& p : a.signals_at) {
    options.values.signal_changes.push_back(usage_on_input_error(
        "--signal-at", p, [&] { return tables::parse_signal_at(p, "--signal-at"); }));
  }
  if (a.spindle_rpm && !(*a.spindle_rpm > 0)) {
    throw UsageError(fmt::format("--spindle-rpm: {} must be > 0", *a.spindle_rpm));
  }
  if (a.master_speed_mm_min && !(*a.master_speed_mm_min > 0)) {
    throw UsageError(fmt::format("--master-speed: {} must be > 0", *a.master_speed_mm_min));
  }

  std::vector<tables::Table> tabs;
  for (const std::string& path : a.tables) {
    require_readable(path, "table file");
    tabs.push_back(tables::load_table(path));
  }
  // A part program moving the master axis, stepped once per cycle by the table run (which
  // owns the clock). Its other axes follow the program too.
  std::optional<sim::ProgramStepper> master;
  motion::Sample master_sample;
  bool master_moving = true;
  std::uint32_t table_axes = 0;
  for (const tables::Table& t : tabs) table_axes |= t.axis_mask;
  if (!a.master_program.empty()) {
    if (tabs.front().ref_kind != tables::RefKind::kAxis) {
      throw UsageError("--master-program: the tables must have REF AXIS <axis>");
    }
    if (a.master_speed_mm_min) {
      throw UsageError("--master-program and --master-speed exclude each other");
    }
    require_readable(a.master_program);
    master.emplace(a.master_program, machine, motion::kernel_options_for(machine));
    const std::size_t axis = tabs.front().ref_axis;
    // rate 0: the reference rate is not known beforehand; the measured axis speeds and
    // accelerations in the summary are checked instead.
    options.reference = {0, 0, [&, axis](double /*t_s*/) {
                           if (master_moving) master_moving = master->next(master_sample);
                           return master_sample.position[axis];
                         }};
  } else {
    // 0 = not given: default_reference reports the REF line when a spindle or master speed is
    // needed and missing.
    options.reference = tables::default_reference(tabs.front(), machine, a.spindle_rpm.value_or(0),
                                                  a.master_speed_mm_min.value_or(0));
  }
  const tables::TablePlan plan = tables::plan_tables(std::move(tabs), machine, options);
  if (a.print_effective) std::cout << tables::format_effective(plan) << std::flush;
  for (const tables::Diagnostic& d : plan.diagnostics) std::cerr << d.formatted() << '\n';
  if (plan.has_errors()) return 1;

  // Outputs are temporaries until the run has finished (same as `run`).
  std::optional<io::TrajectoryCsvWriter> csv;
  if (!a.trajectory.empty()) {
    io::TrajectoryColumns cols;
    cols.ref = true;
    for (const tables::Table& t : plan.tables) {
      for (const tables::Row& r : t.rows) cols.m_code = cols.m_code || !r.m_codes.empty();
    }
    csv.emplace(a.trajectory, machine, cols);
  }
  std::optional<io::AtomicOutputFile> json;
  if (!a.summary.empty()) json.emplace(a.summary);
  std::optional<io::AtomicOutputFile> html;
  std::optional<io::TableReportObserver> report;
  if (!a.report.empty()) {
    html.emplace(a.report);
    // The table axes, and the master axis of REF AXIS (it moves too).
    std::uint32_t charted = table_axes;
    if (plan.tables.front().ref_kind == tables::RefKind::kAxis) {
      charted |= 1U << plan.tables.front().ref_axis;
    }
    report.emplace(machine, charted);
  }

  io::SummaryObserver summary(machine, "table");
  summary.set_record_sample_events(false);  // every M code of a cycle, added below
  ProgressObserver progress(progress_shown, "");
  std::vector<sim::SampleObserver*> observers{&summary};
  if (progress.enabled()) observers.push_back(&progress);
  if (csv) observers.push_back(&*csv);
  if (report) observers.push_back(&*report);
  const tables::RunSummary result = tables::run_tables(plan, [&](const tables::TableSample& ts) {
    motion::Sample m = tables::to_motion_sample(ts);
    m.ref = ts.ref;
    if (master) {
      for (std::size_t i = 0; i < kMaxAxes; ++i) {
        if (((table_axes >> i) & 1U) == 0) m.position[i] = master_sample.position[i];
      }
      m.path_position = m.position;
    }
    for (const tables::MEvent& e : ts.m_codes) {
      summary.add_event({ts.t_s, e.line, 'M', static_cast<double>(e.code)});
      if (report) report->add_m_code(ts.t_s, e.table, e.line, e.code, ts.ref);
    }
    for (sim::SampleObserver* o : observers) o->on_sample(m);
  });
  for (sim::SampleObserver* o : observers) o->on_finish();

  if (json) json->write(io::summary_to_json(summary.summary(), machine));
  if (html) {
    io::TableReportInput in;
    for (const tables::Table& t : plan.tables) in.tables.push_back(t.file);
    std::tie(in.ref_name, in.ref_unit) = reference_name_and_unit(plan, machine);
    in.start_ref = plan.start_ref;
    in.end_ref = result.end_ref;
    in.slow_factor = plan.slow_factor;
    in.finished = result.finished;
    in.warnings = result.warnings;
    html->write(io::render_table_report_html(*report, summary.summary(), machine, in));
  }
  if (csv) csv->commit();
  if (json) json->commit();
  if (html) html->commit();
  std::cout << format_table_summary(summary.summary(), result, plan, machine);
  if (master && master_moving) {
    std::cout << "master        the program was still running when the tables ended (line "
              << master_sample.line << ", t = " << master_sample.t_s << " s)\n";
  }
  if (csv) std::cout << "trajectory    " << a.trajectory << "\n";
  if (json) std::cout << "summary       " << a.summary << "\n";
  if (html) std::cout << "report        " << a.report << "\n";
  return 0;
}

}  // namespace cncore::app
