// The `cncore` command (spec 05): run, check, table, machine. CLI11 is included here only: this
// file defines the command line; each command is in its own file (commands.hpp).
// Exit codes: 0 success, 1 the program or another input is wrong (FILE:LINE:COL: error: ...),
// 2 wrong usage (including bad command-line values), 3 internal failure.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <exception>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "app/suggest.hpp"
#include "core/error.hpp"

namespace {

using namespace cncore;
using namespace cncore::app;

// After a failed parse: a misspelled command or long option, named with the closest known one
// ("did you mean …?"), or nothing when the error is of another kind.
std::optional<std::string> misspelling(const CLI::App& app, int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return std::nullopt;
  const std::string command = argv[1];
  std::vector<std::string> commands;
  const CLI::App* sub = nullptr;
  for (const CLI::App* s : app.get_subcommands([](const CLI::App*) { return true; })) {
    commands.push_back(s->get_name());
    if (s->get_name() == command) sub = s;
  }
  if (sub == nullptr) {
    const auto near = closest_name(command, commands);
    return fmt::format("unknown command '{}'{} (commands: {})", command,
                       near ? fmt::format("; did you mean '{}'?", *near) : "",
                       fmt::join(commands, ", "));
  }
  std::vector<std::string> options;
  for (const CLI::Option* o : sub->get_options()) {
    for (const std::string& name : o->get_lnames()) options.push_back("--" + name);
  }
  for (int i = 2; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--") break;
    if (arg.rfind("--", 0) != 0) continue;
    arg = arg.substr(0, arg.find('='));
    if (std::find(options.begin(), options.end(), arg) != options.end()) continue;
    const auto near = closest_name(arg, options);
    return fmt::format("{}: unknown option {}{}", command, arg,
                       near ? fmt::format("; did you mean {}?", *near) : "");
  }
  return std::nullopt;
}

void add_progress_option(CLI::App& command, std::string& mode) {
  command
      .add_option(
          "--progress", mode,
          "Progress on stderr: share of the program run (lines), simulated time, speed against "
          "real time, time left; json: one JSON object per line (auto: on when stderr is "
          "a terminal; --progress alone: on)")
      ->check(CLI::IsMember({"auto", "on", "off", "json"}))
      ->type_name("auto|on|off|json");
}

void add_subroutine_path_option(CLI::App& command, std::vector<std::string>& dirs) {
  command
      .add_option("--subroutine-path", dirs,
                  "Folder where `o<name> call` finds name.ngc when the program does not define "
                  "o<name>, after the program's own folder (repeatable, searched in order)")
      ->allow_extra_args(false)
      ->type_name("DIR");
}

// `--progress` alone means `--progress=on`: rewritten before parsing, so that it never takes the
// program's name as its value.
std::vector<std::string> with_bare_progress_on(int argc, char** argv) {
  std::vector<std::string> args;
  for (int i = argc - 1; i > 0; --i) {  // CLI11 parses a vector given in reverse order
    const std::string a = argv[i];
    args.push_back(a == "--progress" ? "--progress=on" : a);
  }
  return args;
}

// Size: CLI11's declarations of every command and option in one place, one statement per
// option, so `--help`, the man page and the completions read from one list.
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
  add_progress_option(*run, ra.progress);
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
  add_subroutine_path_option(*run, ra.subroutine_path);

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
  add_subroutine_path_option(*check, ca.subroutine_path);

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
  add_progress_option(*table, ta.progress);
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

  ServeArgs sa;
  CLI::App* serve = app.add_subcommand(
      "serve", "Run the controller: a paced motion cycle driven through its control interface.");
  serve->add_option("--machine", sa.machine, "Machine configuration (default: built-in mill)")
      ->type_name("FILE.toml");
  serve->add_option("--servo", sa.servo, "Where set-points go: sim, udp:HOST:PORT or shm:NAME")
      ->type_name("KIND");
  serve
      ->add_option("--state-dir", sa.state_dir,
                   "Persistent machine state (default: $XDG_STATE_HOME/cncore)")
      ->type_name("DIR");
  serve->add_flag("--no-state", sa.no_state, "Keep no machine state between runs");
  serve->add_option("--program", sa.program, "Load this program at start")->type_name("FILE.ngc");
  serve->add_flag("--start", sa.start, "Start the --program at once");
  add_subroutine_path_option(*serve, sa.subroutine_path);
  serve->add_option("--trajectory", sa.trajectory, "Record every served cycle as CSV")
      ->type_name("FILE.csv");
  serve->add_flag("--no-realtime", sa.no_realtime, "Do not ask for SCHED_FIFO and mlockall");
  serve->add_option("--grbl-tcp", sa.grbl_tcp, "Grbl 1.1 protocol over TCP")->type_name("ADDR");
  serve->add_option("--grbl-pty", sa.grbl_pty, "Grbl 1.1 protocol on a pseudo-terminal")
      ->type_name("PATH");
  serve
      ->add_option("--http", sa.http, "Operator web page (loopback; another address needs a token)")
      ->type_name("HOST:PORT");
  auto* token_opt = serve
                        ->add_option("--http-token", sa.http_token,
                                     "Token every control of the web page must carry")
                        ->type_name("TOKEN");
  serve->add_option("--http-token-file", sa.http_token_file, "Read the web page's token from FILE")
      ->type_name("FILE")
      ->excludes(token_opt);
  serve->add_option("--mtconnect", sa.mtconnect, "MTConnect SHDR adapter (read-only telemetry)")
      ->type_name("HOST:PORT");
  serve
      ->add_option("--mqtt", sa.mqtt,
                   "Publish telemetry to an MQTT broker (mqtts:// for TLS; subscribes to nothing)")
      ->type_name("URL");
  serve->add_option("--mqtt-user", sa.mqtt_user, "MQTT user name")->type_name("NAME");
  serve
      ->add_option("--mqtt-password-file", sa.mqtt_password_file,
                   "File whose first line is the MQTT password")
      ->type_name("FILE");
  serve->add_option("--mqtt-ca", sa.mqtt_ca, "CA certificates of the broker (mqtts://)")
      ->type_name("FILE.pem");
  serve->add_option("--mqtt-rate", sa.mqtt_rate_hz, "MQTT samples per second (default 10)")
      ->check(CLI::Range(0.1, 100.0))
      ->type_name("HZ");

  LatencyArgs la;
  CLI::App* latency = app.add_subcommand(
      "latency", "Measure the cycle thread's wake-up latency and work, idle and with a program.");
  latency->add_option("--seconds", la.seconds, "Total measuring time (half idle, half loaded)")
      ->check(CLI::Range(0.2, 86400.0));
  latency->add_option("--period-us", la.period_us, "Interpolation period")
      ->check(CLI::Range(100U, 100000U));
  latency->add_option("--program", la.program, "Program run in the loaded phase")
      ->type_name("FILE.ngc");
  latency->add_option("--machine", la.machine, "Machine configuration")->type_name("FILE.toml");

  EstimateArgs ea;
  CLI::App* estimate = app.add_subcommand(
      "estimate", "Cycle time of every program of a batch, each run in its own process.");
  estimate
      ->add_option("FILES", ea.files, "Part programs, or folders of them (.ngc .nc .gcode .tap)")
      ->required()
      ->type_name("FILE.ngc|DIR");
  estimate->add_option("-j,--jobs", ea.jobs, "Parallel worker processes (default: the cores)")
      ->check(CLI::Range(1U, 1024U))
      ->type_name("N");
  estimate->add_option("--machine", ea.machine, "Machine configuration (TOML); default: built-in")
      ->type_name("FILE.toml");
  estimate->add_option("--csv", ea.csv, "Write one row per program")
      ->required()
      ->type_name("FILE.csv");
  estimate->add_option("--report", ea.report, "Write one HTML page ranking the programs")
      ->type_name("FILE.html");

  try {
    std::vector<std::string> args = with_bare_progress_on(argc, argv);
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() != 0) {
      if (const auto message = misspelling(app, argc, argv)) {
        std::cerr << "cncore: error: " << *message << "\nRun with --help for more information.\n";
        return 2;
      }
    }
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (*run) return command_run(ra);
  if (*check) return command_check(ca);
  if (*table) return command_table(ta);
  if (*machine) return command_machine(machine_path);
  if (*serve) return command_serve(sa);
  if (*latency) return command_latency(la);
  if (*estimate) return command_estimate(ea);
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
