// The `cncore` command (spec 05): run, check, table, machine. CLI11 is included here only.
// Exit codes: 0 success, 1 the program or another input is wrong (FILE:LINE:COL: error: ...),
// 2 wrong usage (including bad command-line values), 3 internal failure.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "feedcontrol/adaptive_run.hpp"
#include "interpreter/interpreter.hpp"
#include "io/atomic_file.hpp"
#include "io/report.hpp"
#include "io/summary.hpp"
#include "io/trajectory_csv.hpp"
#include "simulation/cutting/cutting_controller.hpp"
#include "simulation/run.hpp"
#include "simulation/stepper.hpp"
#include "tables/table.hpp"

namespace {

using namespace cncore;

// A command-line value that is wrong (exit code 2).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return std::string(s);
}

// The whole text must be a finite number.
std::optional<double> to_number(std::string_view text) {
  const std::string s = trim(text);
  if (s.empty()) return std::nullopt;
  double v = 0;
  const char* first = s.data();
  if (*first == '+') ++first;
  const auto [end, ec] = std::from_chars(first, s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

double override_value(const std::string& option, std::string_view text, double max_pct) {
  const auto v = to_number(text);
  if (!v) throw UsageError(fmt::format("{}: '{}' is not a number", option, text));
  if (*v < 0 || *v > max_pct) {
    throw UsageError(fmt::format("{}: override {} % is outside 0 … {} % (machine max_override_pct)",
                                 option, *v, max_pct));
  }
  return *v;
}

// "T:PCT[,T:PCT…]", possibly given several times.
std::vector<std::pair<double, double>> parse_override_steps(const std::vector<std::string>& args,
                                                            double max_pct) {
  std::vector<std::pair<double, double>> steps;
  for (const std::string& arg : args) {
    std::size_t pos = 0;
    while (pos <= arg.size()) {
      std::size_t comma = arg.find(',', pos);
      if (comma == std::string::npos) comma = arg.size();
      const std::string item = arg.substr(pos, comma - pos);
      const std::size_t colon = item.find(':');
      if (colon == std::string::npos) {
        throw UsageError(fmt::format(
            "--override-at: '{}' is not TIME:PCT (time in s, feed override in %)", item));
      }
      const auto t = to_number(std::string_view(item).substr(0, colon));
      if (!t || *t < 0) {
        throw UsageError(
            fmt::format("--override-at: '{}': the time must be a number >= 0 s", item));
      }
      steps.emplace_back(
          *t, override_value("--override-at", std::string_view(item).substr(colon + 1), max_pct));
      pos = comma + 1;
    }
  }
  return steps;
}

std::pair<std::string, double> name_value(const std::string& option, const std::string& arg) {
  const std::size_t eq = arg.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw UsageError(fmt::format("{}: '{}' is not NAME=VALUE", option, arg));
  }
  const auto v = to_number(std::string_view(arg).substr(eq + 1));
  if (!v) throw UsageError(fmt::format("{}: '{}': the value must be a number", option, arg));
  return {trim(std::string_view(arg).substr(0, eq)), *v};
}

interp::Options interpreter_options(const std::vector<std::string>& vars,
                                    const std::vector<std::string>& params) {
  interp::Options o;
  for (const std::string& a : vars) {
    auto [name, value] = name_value("--var", a);
    for (const char c : name) {
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) {
        throw UsageError(fmt::format("--var: '{}': a name has letters, digits and _ only", a));
      }
    }
    o.named_params[name] = value;
  }
  for (const std::string& a : params) {
    auto [name, value] = name_value("--param", a);
    int n = 0;
    const auto [end, ec] = std::from_chars(name.data(), name.data() + name.size(), n);
    if (ec != std::errc() || end != name.data() + name.size() || n < 1) {
      throw UsageError(
          fmt::format("--param: '{}': the parameter number must be an integer >= 1", a));
    }
    o.params[n] = value;
  }
  return o;
}

MachineConfig machine_from(const std::string& path) {
  return machine_config_or_default(path);
}

void require_readable(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, 0, 0, "cannot open: it is a directory");
  }
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, 0, "cannot open");
}

// A one-line progress display on stderr (spec 05): only when stderr is a terminal, and only once
// the run has taken more than a second. Checks the clock every 4096 cycles.
class ProgressObserver : public sim::SampleObserver {
 public:
  ProgressObserver() : enabled_(::isatty(STDERR_FILENO) == 1), start_(Clock::now()) {}
  ~ProgressObserver() override { clear(); }
  void on_sample(const motion::Sample& s) override {
    if (!enabled_ || (++cycles_ & 4095) != 0) return;
    const double wall_s = std::chrono::duration<double>(Clock::now() - start_).count();
    if (wall_s < 1.0) return;
    std::fprintf(stderr, "\rcncore: simulated %.1f s, line %u, %.0f cycles/s   ", s.t_s, s.line,
                 static_cast<double>(cycles_) / wall_s);
    std::fflush(stderr);
    shown_ = true;
  }
  void on_finish() override { clear(); }

 private:
  using Clock = std::chrono::steady_clock;
  void clear() {
    if (!shown_) return;
    std::fprintf(stderr, "\r%60s\r", "");
    std::fflush(stderr);
    shown_ = false;
  }
  bool enabled_;
  bool shown_ = false;
  std::uint64_t cycles_ = 0;
  Clock::time_point start_;
};

struct RunArgs {
  std::string program, machine, trajectory, summary, mode = "lookahead";
  std::string accdec;  // --accdec; empty: the machine's [motion] accdec
  std::optional<double> override_pct;
  std::vector<std::string> override_at, vars, params;
  std::string correction;  // --correction on|off; empty: [direction_correction] enabled
  std::string report;      // --report FILE.html
  std::string adaptive;    // --adaptive on|off; empty: adaptive.enabled of the configuration
  std::string load_csv;    // --load FILE.csv
  std::string heightmap, heightmap_grid;  // cutting simulation: --heightmap, --heightmap-grid
};

// The machine with `--correction on|off` applied over [direction_correction] enabled (spec 03).
MachineConfig with_correction_option(MachineConfig m, const std::string& option) {
  if (!option.empty()) m.direction_correction.enabled = option == "on";
  return m;
}

// Spec 03: cycle time of the same program with the direction correction off (a second run with
// no outputs), for the time the correction added or saved. Without the cycle controller: it holds
// state (adaptive control, the cutting simulation's stock) that a second run must not touch.
double cycle_time_without_correction_s(const std::string& program, MachineConfig machine,
                                       sim::RunOptions options) {
  machine.direction_correction.enabled = false;
  options.cycle_controller = nullptr;
  struct LastTime : sim::SampleObserver {
    double t_s = 0;
    void on_sample(const motion::Sample& s) override { t_s = s.t_s; }
  } last;
  sim::run_program(program, machine, options, {&last});
  return last.t_s;
}

int command_run(const RunArgs& a) {
  const MachineConfig machine = with_correction_option(machine_from(a.machine), a.correction);
  sim::RunOptions options;
  options.kernel.mode = a.mode == "stop" ? motion::Mode::kStop : motion::Mode::kLookahead;
  options.kernel.bound_resultant_accel = machine.bound_resultant_accel;
  const bool accel_type =
      a.accdec.empty() ? machine.accdec == AccDecKind::kAcceleration : a.accdec == "acceleration";
  options.kernel.accdec =
      accel_type ? motion::AccDecType::kAcceleration : motion::AccDecType::kMovingAverage;
  if (a.override_pct) {
    options.kernel.override_pct =
        override_value("--override", fmt::format("{}", *a.override_pct), machine.max_override_pct);
  }
  options.override_steps = parse_override_steps(a.override_at, machine.max_override_pct);
  {
    // With the override at 0 for good the machine never reaches the end: refuse to start.
    double last = options.kernel.override_pct, last_t = -1;
    for (const auto& [t, pct] : options.override_steps) {
      if (t >= last_t) {
        last = pct;
        last_t = t;
      }
    }
    if (last <= 0) {
      throw UsageError("the feed override ends at 0 %: the program would never finish");
    }
  }
  options.interpreter = interpreter_options(a.vars, a.params);
  require_readable(a.program);

  // Adaptive feed control (spec 04): runs in the loop when there is a load source.
  const feed::SelectedLoadSource load = feed::make_load_source(machine, {a.load_csv});
  // Cutting simulation (issue 7): on with a [stock] section. It is the load source of adaptive
  // control unless --load names a recorded signal.
  std::optional<cut::CuttingSimulator> cutting;
  if (machine.cutting.stock.enabled) {
    cutting.emplace(machine, a.program);
  } else if (!a.heightmap.empty() || !a.heightmap_grid.empty()) {
    throw UsageError(
        "--heightmap and --heightmap-grid need a [stock] section in the machine "
        "configuration (docs/cutting-simulation.md)");
  }
  feed::LoadSource* load_source = load.source.get();
  std::string load_description = load.description;
  if (cutting && a.load_csv.empty()) {
    load_source = &*cutting;
    load_description = "cutting simulation";
  }
  feed::AdaptiveSettings adaptive_settings = machine.adaptive;
  if (!a.adaptive.empty()) adaptive_settings.enabled = a.adaptive == "on";
  if (a.adaptive == "on" && load_source == nullptr) {
    throw UsageError(
        "--adaptive on needs a load source: --load FILE.csv, or an [adaptive.plant] depth "
        "profile in the machine configuration");
  }
  std::optional<feed::AdaptiveCycleController> adaptive;
  if (load_source != nullptr) {
    // A cutting simulation alone (adaptive control not switched on) must not fail on adaptive
    // settings the user never asked for (e.g. upper_pct above a lowered max_override_pct).
    const bool cutting_only = cutting && load_source == &*cutting && !adaptive_settings.enabled;
    try {
      adaptive.emplace(machine, adaptive_settings, *load_source,
                       a.machine.empty() ? std::string("built-in machine") : a.machine);
    } catch (const InputError&) {
      if (!cutting_only) throw;
    }
    if (adaptive) options.cycle_controller = &*adaptive;
  }
  // The simulator sweeps first each cycle, then hands the sample to the adaptive controller.
  std::optional<cut::CuttingCycleController> cutting_stage;
  if (cutting) {
    cutting_stage.emplace(*cutting, adaptive ? &*adaptive : nullptr);
    options.cycle_controller = &*cutting_stage;
  }

  // Output files are created (as temporaries) before the run, so a bad path fails at once, and
  // renamed into place only after the run succeeded.
  std::optional<io::TrajectoryCsvWriter> csv;
  if (!a.trajectory.empty()) {
    io::TrajectoryColumns cols;
    cols.override_pct = a.override_pct.has_value() || !options.override_steps.empty();
    cols.override_pct = cols.override_pct || adaptive.has_value();
    cols.load = adaptive.has_value() || cutting.has_value();
    cols.load_target = adaptive.has_value();
    cols.correction = machine.direction_correction.enabled;
    csv.emplace(a.trajectory, machine, cols);
  }
  std::optional<io::AtomicOutputFile> json;
  if (!a.summary.empty()) json.emplace(a.summary);
  std::optional<io::AtomicOutputFile> heightmap_png, heightmap_grid;
  if (!a.heightmap.empty()) heightmap_png.emplace(a.heightmap);
  if (!a.heightmap_grid.empty()) heightmap_grid.emplace(a.heightmap_grid);
  std::optional<io::AtomicOutputFile> html;
  std::optional<io::ReportObserver> report;
  if (!a.report.empty()) {
    html.emplace(a.report);
    report.emplace(machine, a.mode);
  }

  io::SummaryObserver summary(machine, a.mode);
  ProgressObserver progress;
  std::vector<sim::SampleObserver*> observers{&summary, &progress};
  if (csv) observers.push_back(&*csv);
  if (report) observers.push_back(&*report);
  if (cutting_stage) observers.push_back(&*cutting_stage);  // checks T words against the table
  sim::run_program(a.program, machine, options, observers);
  if (adaptive) {
    io::LoadSummary& l = summary.load_summary();
    l.adaptive = adaptive->ever_enabled();
    l.antiwindup = feed::antiwindup_name(adaptive_settings.antiwindup);
    l.source = load_description;
    l.target_load_pct = adaptive_settings.target_load_pct;
    l.switches = adaptive->switch_count();
    if (l.adaptive) {
      // Time saved: the same program again with the operator's override alone (no outputs).
      l.time_without_adaptive_s = feed::cycle_time_without_adaptive_s(a.program, machine, options);
      l.time_saved_s = l.time_without_adaptive_s - summary.summary().cycle_time_s;
    }
  }
  // With adaptive control running, a run without its controller would mix both effects: the
  // correction's time is then not measured.
  if (machine.direction_correction.enabled && !(adaptive && adaptive->ever_enabled())) {
    summary.set_time_without_correction_s(
        cycle_time_without_correction_s(a.program, machine, options));
  }

  if (json) {
    std::string text = io::summary_to_json(summary.summary(), machine);
    if (cutting) text = cut::summary_json_with_cutting(text, *cutting, machine.cutting);
    json->write(text);
  }
  if (heightmap_png) heightmap_png->write(cut::heightmap_png(cutting->map()));
  if (heightmap_grid) {
    const bool csv_grid = a.heightmap_grid.size() >= 4 &&
                          a.heightmap_grid.compare(a.heightmap_grid.size() - 4, 4, ".csv") == 0;
    heightmap_grid->write(cut::heightmap_grid(cutting->map(), csv_grid));
  }
  if (html)
    html->write(io::render_report_html(*report, summary.summary(), machine, {a.program, ""}));
  if (csv) csv->commit();
  if (json) json->commit();
  if (html) html->commit();
  if (heightmap_png) heightmap_png->commit();
  if (heightmap_grid) heightmap_grid->commit();
  std::cout << io::format_human_summary(summary.summary(), machine, a.program);
  if (cutting) std::cout << cut::format_cutting_summary(*cutting, machine.cutting);
  if (heightmap_png) std::cout << "heightmap     " << a.heightmap << "\n";
  if (heightmap_grid) std::cout << "height grid   " << a.heightmap_grid << "\n";
  if (csv) std::cout << "trajectory    " << a.trajectory << "\n";
  if (json) std::cout << "summary       " << a.summary << "\n";
  if (html) std::cout << "report        " << a.report << "\n";
  return 0;
}

struct CheckArgs {
  std::string program, machine;
  bool blocks = false;
  std::vector<std::string> vars, params;
};

int command_check(const CheckArgs& a) {
  const MachineConfig machine = machine_from(a.machine);
  const interp::Options options = interpreter_options(a.vars, a.params);
  require_readable(a.program);
  interp::Interpreter interpreter(a.program, machine, options);
  Block b;
  std::uint64_t blocks = 0, motion = 0;
  std::string out;
  auto flush = [&out] {
    std::fwrite(out.data(), 1, out.size(), stdout);
    out.clear();
  };
  // Every error is reported: after one, the interpreter goes on with the next line. Errors
  // after the first may be its consequences; a repeated error or too many end the check.
  constexpr int kMaxErrors = 50;
  int errors = 0;
  std::string last_error;
  for (;;) {
    try {
      if (!interpreter.next(b)) break;
    } catch (const InputError& e) {
      flush();  // the blocks before the error are listed, then the error goes to stderr
      std::fflush(stdout);
      const std::string text = e.formatted();
      if (text == last_error) break;
      std::cerr << text << "\n";
      last_error = text;
      if (++errors >= kMaxErrors) {
        std::cerr << a.program << ": too many errors, stopping the check\n";
        break;
      }
      if (!interpreter.recover()) break;
      continue;
    }
    ++blocks;
    if (b.kind == BlockKind::kRapid || b.kind == BlockKind::kLine || b.kind == BlockKind::kArc) {
      ++motion;
    }
    if (a.blocks) {
      out += interp::format_block(b, machine);
      out += '\n';
      if (out.size() > (1 << 16)) flush();
    }
  }
  if (errors > 0) {
    flush();
    std::fflush(stdout);
    return 1;
  }
  if (!a.blocks) out = fmt::format("{}: ok, {} blocks ({} motion)\n", a.program, blocks, motion);
  std::fwrite(out.data(), 1, out.size(), stdout);
  std::fflush(stdout);
  return 0;
}

struct TableArgs {
  std::vector<std::string> tables;
  std::string machine, trajectory, summary;
  bool print_effective = false;
  std::optional<double> spindle_rpm, master_speed_mm_min;
  std::uint32_t repeat = 1;
  std::vector<std::string> vars, params, signals, signals_at;
  std::string master_program;  // REF AXIS: a part program moves the master axis
};

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

std::string format_table_summary(const io::Summary& s, const tables::RunSummary& r,
                                 const tables::TablePlan& plan, const MachineConfig& machine) {
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

int command_table(const TableArgs& a) {
  const MachineConfig machine = machine_from(a.machine);
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
    require_readable(path);
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
    master.emplace(a.master_program, machine, motion::KernelOptions{});
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

  io::SummaryObserver summary(machine, "table");
  summary.set_record_sample_events(false);  // every M code of a cycle, added below
  ProgressObserver progress;
  std::vector<sim::SampleObserver*> observers{&summary, &progress};
  if (csv) observers.push_back(&*csv);
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
    }
    for (sim::SampleObserver* o : observers) o->on_sample(m);
  });
  for (sim::SampleObserver* o : observers) o->on_finish();

  if (json) json->write(io::summary_to_json(summary.summary(), machine));
  if (csv) csv->commit();
  if (json) json->commit();
  std::cout << format_table_summary(summary.summary(), result, plan, machine);
  if (master && master_moving) {
    std::cout << "master        the program was still running when the tables ended (line "
              << master_sample.line << ", t = " << master_sample.t_s << " s)\n";
  }
  if (csv) std::cout << "trajectory    " << a.trajectory << "\n";
  if (json) std::cout << "summary       " << a.summary << "\n";
  return 0;
}

int main_cli(int argc, char** argv) {
  CLI::App app{
      "cncore: a CNC numerical-control kernel on a simulated machine.\n"
      "G-code -> look-ahead feed planning -> per-cycle interpolation -> axis set-points.",
      "cncore"};
  app.set_version_flag("--version", std::string("cncore ") + CNCORE_VERSION);
  app.require_subcommand(1);

  RunArgs ra;
  CLI::App* run = app.add_subcommand(
      "run", "Interpret, plan and interpolate a program; print a summary of the motion.");
  run->add_option("PROGRAM", ra.program, "Part program (G-code)")
      ->required()
      ->type_name("FILE.ngc");
  run->add_option("--machine", ra.machine, "Machine configuration (TOML); default: built-in")
      ->type_name("FILE.toml");
  run->add_option("--trajectory", ra.trajectory, "Write one CSV row per interpolation cycle")
      ->type_name("FILE.csv");
  run->add_option("--summary", ra.summary, "Write the machine-readable summary (JSON)")
      ->type_name("FILE.json");
  run->add_option("--report", ra.report,
                  "Write a self-contained HTML page: speed, acceleration, top view, slowest lines")
      ->type_name("FILE.html");
  run->add_option("--correction", ra.correction,
                  "Feed correction by direction of motion (spec 03): on or off (default: "
                  "[direction_correction] enabled of the machine; M160 / M161 switch it)")
      ->check(CLI::IsMember({"on", "off"}))
      ->type_name("on|off");
  run->add_option("--adaptive", ra.adaptive,
                  "Adaptive feed control at program start: on or off (default: adaptive.enabled "
                  "of the machine; M52 P1 / M52 P0 in the program switch it)")
      ->check(CLI::IsMember({"on", "off"}))
      ->type_name("on|off");
  run->add_option("--load", ra.load_csv,
                  "Recorded spindle load (CSV t_s,load_pct or s_mm,load_pct): the load source "
                  "of adaptive feed control (default: [adaptive.plant] of the machine)")
      ->type_name("FILE.csv");
  run->add_option("--heightmap", ra.heightmap,
                  "Cutting simulation ([stock] in the machine): write the final stock as a PNG "
                  "top view shaded by height")
      ->type_name("FILE.png");
  run->add_option("--heightmap-grid", ra.heightmap_grid,
                  "Cutting simulation: write the final height map as a grid (FILE.csv text, "
                  "any other name binary; docs/cutting-simulation.md)")
      ->type_name("FILE");
  run->add_option("--mode", ra.mode, "lookahead (default) or stop (stop at every block)")
      ->check(CLI::IsMember({"lookahead", "stop"}))
      ->type_name("MODE");
  run->add_option("--accdec", ra.accdec,
                  "Look-ahead acc/dec type: acceleration or moving_average (default: the "
                  "machine's [motion] accdec)")
      ->check(CLI::IsMember({"acceleration", "moving_average"}))
      ->type_name("TYPE");
  run->add_option("--override", ra.override_pct, "Constant feed override, %")->type_name("PCT");
  run->add_option("--override-at", ra.override_at,
                  "Override steps TIME:PCT[,TIME:PCT...] (time in s, override in %)")
      ->allow_extra_args(false)
      ->type_name("T:PCT[,T:PCT...]");
  run->add_option("--var", ra.vars, "Named parameter #<NAME> = VALUE (NAME=VALUE, repeatable)")
      ->allow_extra_args(false)
      ->type_name("NAME=V");
  run->add_option("--param", ra.params, "Numbered parameter #N = VALUE (N=VALUE, repeatable)")
      ->allow_extra_args(false)
      ->type_name("N=V");

  CheckArgs ca;
  CLI::App* check = app.add_subcommand("check", "Interpret a program only and report every error.");
  check->add_option("PROGRAM", ca.program, "Part program (G-code)")
      ->required()
      ->type_name("FILE.ngc");
  check->add_flag("--blocks", ca.blocks, "List the interpreted blocks, one per line");
  check->add_option("--machine", ca.machine, "Machine configuration (TOML); default: built-in")
      ->type_name("FILE.toml");
  check->add_option("--var", ca.vars, "Named parameter #<NAME> = VALUE (NAME=VALUE, repeatable)")
      ->allow_extra_args(false)
      ->type_name("NAME=V");
  check->add_option("--param", ca.params, "Numbered parameter #N = VALUE (N=VALUE, repeatable)")
      ->allow_extra_args(false)
      ->type_name("N=V");

  TableArgs ta;
  CLI::App* table = app.add_subcommand(
      "table", "Run axis tables against a reference (time, master axis, spindle) with SFT/SFTCAN.");
  table->add_option("TABLE", ta.tables, "Table files (one or more, same reference)")
      ->required()
      ->type_name("FILE.tbl");
  table->add_option("--machine", ta.machine, "Machine configuration (TOML); default: built-in")
      ->type_name("FILE.toml");
  table->add_option("--trajectory", ta.trajectory, "Write one CSV row per interpolation cycle")
      ->type_name("FILE.csv");
  table->add_option("--summary", ta.summary, "Write the machine-readable summary (JSON)")
      ->type_name("FILE.json");
  table->add_flag("--print-effective", ta.print_effective,
                  "Print the effective tables (shifts applied) before running");
  table->add_option("--param", ta.params, "Parameter P<N> = VALUE for SFT=P<N> (repeatable)")
      ->allow_extra_args(false)
      ->type_name("N=V");
  table->add_option("--var", ta.vars, "Macro variable #<N> = VALUE for SFT=#<N> (repeatable)")
      ->allow_extra_args(false)
      ->type_name("N=V");
  table->add_option("--signal", ta.signals, "Signal R<N> = VALUE at the start (repeatable)")
      ->allow_extra_args(false)
      ->type_name("R<N>=V");
  table
      ->add_option("--signal-at", ta.signals_at,
                   "Signal R<N> becomes VALUE at time T s while running (repeatable)")
      ->allow_extra_args(false)
      ->type_name("T:R<N>=V");
  table->add_option("--spindle-rpm", ta.spindle_rpm, "Spindle speed for REF SPINDLE, rev/min")
      ->type_name("RPM");
  table
      ->add_option("--master-speed", ta.master_speed_mm_min,
                   "Master axis speed for REF AXIS, mm/min (deg/min for a rotary axis)")
      ->type_name("MM_MIN");
  table
      ->add_option("--master-program", ta.master_program,
                   "REF AXIS: a part program moves the master axis (its other axes too)")
      ->type_name("FILE.ngc");
  table->add_option("--repeat", ta.repeat, "Repetitions of a CYCLIC table without a count")
      ->check(CLI::Range(1U, 1000000000U))
      ->type_name("N");

  std::string machine_path;
  CLI::App* machine = app.add_subcommand(
      "machine", "Print the machine configuration as TOML (built-in, or the effective one).");
  machine
      ->add_option("--machine", machine_path,
                   "Print this configuration file with every default filled in")
      ->type_name("FILE.toml");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (*run) return command_run(ra);
  if (*check) return command_check(ca);
  if (*table) return command_table(ta);
  if (*machine) {
    std::cout << machine_config_to_toml(machine_from(machine_path));
    return 0;
  }
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return main_cli(argc, argv);
  } catch (const InputError& e) {
    std::fflush(stdout);
    std::cerr << e.formatted() << "\n";
    return 1;
  } catch (const UsageError& e) {
    std::cerr << "cncore: error: " << e.what() << "\nRun with --help for more information.\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "cncore: internal error: " << e.what() << "\n";
    return 3;
  } catch (...) {
    std::cerr << "cncore: internal error: unknown exception\n";
    return 3;
  }
}
