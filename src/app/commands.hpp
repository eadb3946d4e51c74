// The `cncore` commands (spec 05), one source file each: the arguments CLI11 fills in (main.cpp)
// and the function that runs the command and returns the exit code. They throw InputError
// (exit 1) and UsageError (exit 2); main() turns them into messages.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cncore::app {

struct RunArgs {
  std::string program, machine, trajectory, summary, mode = "lookahead";
  std::string accdec;  // --accdec; empty: the machine's [motion] accdec
  std::optional<double> override_pct;
  std::vector<std::string> override_at, vars, params;
  std::string tool_table;                    // --tool-table FILE.tbl (LinuxCNC format)
  std::vector<std::string> subroutine_path;  // --subroutine-path DIR (repeatable)
  std::string correction;  // --correction on|off; empty: [direction_correction] enabled
  std::string report;      // --report FILE.html
  std::string adaptive;    // --adaptive on|off; empty: adaptive.enabled of the configuration
  std::string load_csv;    // --load FILE.csv
  std::string heightmap, heightmap_grid;      // cutting simulation: --heightmap, --heightmap-grid
  std::optional<double> dry_run_feed_mm_min;  // --dry-run FEED
  std::optional<double> single_block_wait_s;  // --single-block WAIT_S
  std::string progress = "auto";              // --progress auto|on|off|json
};

int command_run(const RunArgs& a);

struct CheckArgs {
  std::string program, machine;
  bool blocks = false;
  bool canon = false;  // --canon: LinuxCNC's canonical-machine calls
  std::vector<std::string> vars, params;
  std::string tool_table;                    // --tool-table FILE.tbl (LinuxCNC format)
  std::vector<std::string> subroutine_path;  // --subroutine-path DIR (repeatable)
};

int command_check(const CheckArgs& a);

struct TableArgs {
  std::vector<std::string> tables;
  std::string machine, trajectory, summary;
  bool print_effective = false;
  std::optional<double> spindle_rpm, master_speed_mm_min;
  std::uint32_t repeat = 1;
  std::vector<std::string> vars, params, signals, signals_at;
  std::string master_program;     // REF AXIS: a part program moves the master axis
  std::string report;             // --report FILE.html
  std::string progress = "auto";  // --progress auto|on|off|json
};

int command_table(const TableArgs& a);

struct ServeArgs {
  std::string machine, servo = "sim", state_dir, program, trajectory;
  std::string grbl_tcp, grbl_pty, http;     // front ends that plug into the control interface
  std::string http_token, http_token_file;  // --http: the token controls must carry
  std::string mtconnect;                    // --mtconnect HOST:PORT: MTConnect SHDR adapter
  std::string mqtt;                         // --mqtt mqtt://HOST:PORT/PREFIX: MQTT publisher
  std::string mqtt_user, mqtt_password_file, mqtt_ca;
  double mqtt_rate_hz = 10;  // --mqtt-rate: samples per second
  bool start = false, no_state = false, no_realtime = false;
  std::vector<std::string> subroutine_path;  // --subroutine-path DIR (repeatable)
};

int command_serve(const ServeArgs& a);

struct LatencyArgs {
  std::string machine, program;
  double seconds = 10;
  std::uint32_t period_us = 1000;
};

int command_latency(const LatencyArgs& a);

struct EstimateArgs {
  std::vector<std::string> files;  // programs, or folders of programs
  unsigned jobs = 0;               // -j: worker processes; 0: the number of cores
  std::string machine, csv, report;
};

int command_estimate(const EstimateArgs& a);

// Prints the configuration (the built-in one for an empty path) as TOML.
int command_machine(const std::string& machine_path);

}  // namespace cncore::app
