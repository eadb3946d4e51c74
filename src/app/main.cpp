// The `cncore` command (spec 05): run, check, table, machine. CLI11 is included here only: this
// file defines the command line; each command is in its own file (commands.hpp).
// Exit codes: 0 success, 1 the program or another input is wrong (FILE:LINE:COL: error: ...),
// 2 wrong usage (including bad command-line values), 3 internal failure.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "core/error.hpp"

namespace {

using namespace cncore;
using namespace cncore::app;

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
                  "Look-ahead acc/dec type: acceleration, moving_average or search (default: "
                  "the machine's [motion] accdec)")
      ->check(CLI::IsMember({"acceleration", "moving_average", "search"}))
      ->type_name("TYPE");
  run->add_option("--override", ra.override_pct, "Constant feed override, %")->type_name("PCT");
  run->add_option("--override-at", ra.override_at,
                  "Override steps TIME:PCT[,TIME:PCT...] (time in s, override in %)")
      ->allow_extra_args(false)
      ->type_name("T:PCT[,T:PCT...]");
  run->add_option("--dry-run", ra.dry_run_feed_mm_min,
                  "Dry run: every feed move (G1 G2 G3) at this feed instead of its F, mm/min "
                  "(rapids at the rapid rate; override and limits apply)")
      ->type_name("FEED");
  run->add_option("--single-block", ra.single_block_wait_s,
                  "Single-block stop: stop at the end of every motion block and wait this long "
                  "before the next (the operator's cycle start; 0: at once), s")
      ->type_name("WAIT_S");
  run->add_option("--var", ra.vars, "Named parameter #<NAME> = VALUE (NAME=VALUE, repeatable)")
      ->allow_extra_args(false)
      ->type_name("NAME=V");
  run->add_option("--param", ra.params, "Numbered parameter #N = VALUE (N=VALUE, repeatable)")
      ->allow_extra_args(false)
      ->type_name("N=V");
  run->add_option(
         "--tool-table", ra.tool_table,
         "Tool table in LinuxCNC's format (T1 P1 Z12.5 D6), mm; replaces [[tools]] entries")
      ->type_name("FILE.tbl");

  CheckArgs ca;
  CLI::App* check = app.add_subcommand("check", "Interpret a program only and report every error.");
  check->add_option("PROGRAM", ca.program, "Part program (G-code)")
      ->required()
      ->type_name("FILE.ngc");
  check->add_flag("--blocks", ca.blocks, "List the interpreted blocks, one per line");
  check->add_flag("--canon", ca.canon,
                  "List LinuxCNC's canonical-machine calls (as rs274 -g), in program units");
  check->add_option("--machine", ca.machine, "Machine configuration (TOML); default: built-in")
      ->type_name("FILE.toml");
  check->add_option("--var", ca.vars, "Named parameter #<NAME> = VALUE (NAME=VALUE, repeatable)")
      ->allow_extra_args(false)
      ->type_name("NAME=V");
  check->add_option("--param", ca.params, "Numbered parameter #N = VALUE (N=VALUE, repeatable)")
      ->allow_extra_args(false)
      ->type_name("N=V");
  check
      ->add_option("--tool-table", ca.tool_table,
                   "Tool table in LinuxCNC's format (T1 P1 Z12.5 D6), mm; replaces [[tools]] "
                   "entries")
      ->type_name("FILE.tbl");

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
  table
      ->add_option("--report", ta.report,
                   "Write a self-contained HTML page: axis speeds and accelerations, reference "
                   "value and M codes against time")
      ->type_name("FILE.html");
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
  if (*machine) return command_machine(machine_path);
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
