// `cncore run`: interpret, plan and interpolate a program on the simulated machine, with the
// optional direction correction, adaptive feed control and cutting simulation; write the
// trajectory, summary, report and height-map outputs.
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "app/progress.hpp"
#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "feedcontrol/adaptive_run.hpp"
#include "io/atomic_file.hpp"
#include "io/report.hpp"
#include "io/summary.hpp"
#include "io/trajectory_csv.hpp"
#include "simulation/cutting/cutting_controller.hpp"
#include "simulation/run.hpp"

namespace cncore::app {
namespace {

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

}  // namespace

// Size: `cncore run` wires the options to the run in order: machine and modes, adaptive feed,
// cutting simulation, outputs (temporaries renamed on success), the summary's comparisons.
int command_run(const RunArgs& a) {
  const MachineConfig machine = with_correction_option(machine_from(a.machine), a.correction);
  sim::RunOptions options;
  options.kernel = motion::kernel_options_for(machine);
  options.kernel.mode = a.mode == "stop" ? motion::Mode::kStop : motion::Mode::kLookahead;
  if (!a.accdec.empty()) {
    options.kernel.accdec = a.accdec == "acceleration" ? motion::AccDecType::kAcceleration
                            : a.accdec == "search"     ? motion::AccDecType::kSearch
                                                       : motion::AccDecType::kMovingAverage;
  }
  if (options.kernel.mode == motion::Mode::kLookahead &&
      options.kernel.accdec == motion::AccDecType::kSearch &&
      (machine.max_jerk_mm_s3 > 0 || machine.post_filter_s > 0)) {
    throw UsageError(
        "acc/dec type \"search\" runs without a jerk limit and without a post filter: set "
        "[motion] max_jerk_mm_s3 and post_filter_s to 0, or use --accdec acceleration");
  }
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
  options.interpreter = interpreter_options(a.vars, a.params, a.tool_table);
  options.interpreter.subroutine_path = a.subroutine_path;
  if (a.dry_run_feed_mm_min) {
    if (!(*a.dry_run_feed_mm_min > 0) || !std::isfinite(*a.dry_run_feed_mm_min))
      throw UsageError("--dry-run: the feed must be a number > 0 (mm/min)");
    options.operator_modes.dry_run_feed_mm_min = *a.dry_run_feed_mm_min;
  }
  if (a.single_block_wait_s) {
    if (!(*a.single_block_wait_s >= 0) || !std::isfinite(*a.single_block_wait_s))
      throw UsageError("--single-block: the wait must be a number >= 0 (s)");
    options.operator_modes.single_block = true;
    options.operator_modes.single_block_wait_s = *a.single_block_wait_s;
  }
  require_readable(a.program);
  const ProgressMode progress_shown = progress_mode(a.progress);
  if (!a.load_csv.empty()) require_readable(a.load_csv, "load file");

  // Adaptive feed control (spec 04): runs in the loop when there is a load source.
  const feed::SelectedLoadSource load = feed::make_load_source(machine, {a.load_csv});
  // Cutting simulation: on with a [stock] section. It is the load source of adaptive
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
  io::SummaryObserver summary(machine, a.mode);
  std::optional<io::AtomicOutputFile> html;
  std::optional<io::ReportObserver> report;
  if (!a.report.empty()) html.emplace(a.report);
  if (html || json) {
    // The report explains the summary's own time lost (the summary is observed first); its
    // accounting by cause also goes into the summary JSON.
    report.emplace(machine, a.mode, io::ReportOptions{}, &summary);
  }

  // Stop mode always runs the moving average (the seed's conventional method).
  summary.set_accdec(options.kernel.mode == motion::Mode::kStop ||
                             options.kernel.accdec == motion::AccDecType::kMovingAverage
                         ? "moving_average"
                     : options.kernel.accdec == motion::AccDecType::kSearch ? "search"
                                                                            : "acceleration");
  summary.set_operator_modes(options.operator_modes);
  ProgressObserver progress(progress_shown, a.program);
  std::vector<sim::SampleObserver*> observers{&summary};
  if (progress.enabled()) observers.push_back(&progress);  // else one virtual call per cycle less
  if (csv) observers.push_back(&*csv);
  if (report) observers.push_back(&*report);
  if (cutting_stage) observers.push_back(&*cutting_stage);  // checks T words against the table
  const sim::RunCounts counts = sim::run_program(a.program, machine, options, observers);
  summary.set_program_blocks(counts.blocks);
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
    text = io::summary_json_with_losses(text, report->losses());
    json->write(text);
  }
  // The height map's PNG, for its file and the report.
  const std::string map_png =
      cutting && (heightmap_png || html) ? cut::heightmap_png(cutting->map()) : std::string();
  if (heightmap_png) heightmap_png->write(map_png);
  if (heightmap_grid) {
    const bool csv_grid = a.heightmap_grid.size() >= 4 &&
                          a.heightmap_grid.compare(a.heightmap_grid.size() - 4, 4, ".csv") == 0;
    heightmap_grid->write(cut::heightmap_grid(cutting->map(), csv_grid));
  }
  if (html) {
    io::ReportInput input{a.program, "", {}};
    if (cutting) {
      input.heightmap = {map_png, cutting->map().bottom_z_mm(), cutting->map().top_z_mm(), {}};
      for (const double u : {0.0, 0.25, 0.5, 0.75, 1.0}) {
        const auto c = cut::heightmap_colour(u);
        input.heightmap.scale.push_back(fmt::format("rgb({},{},{})", c[0], c[1], c[2]));
      }
    }
    html->write(io::render_report_html(*report, summary.summary(), machine, input));
  }
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

}  // namespace cncore::app
