// `cncore estimate`: the result of one program and the batch outputs (CSV, HTML ranking page).
// src/app only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cncore::app::estimate {

// A program line that lost time against its programmed feed (from `cncore run --summary`).
struct SlowLine {
  std::uint32_t line = 0, last_line = 0;
  double lost_s = 0, time_s = 0;
};

struct ProgramResult {
  std::string program;
  bool ok = false;
  std::string error;  // first line of the run's error output (FILE:LINE:COL: error: …)
  double cycle_time_s = 0;
  double path_length_mm = 0;
  std::uint64_t blocks = 0, cycles = 0;
  // Time lost against the programmed feed on the slowest lines run reports (at most five),
  // Σ dt·(1 − v/F) over their cycles (docs/cli.md, slowest spots).
  double time_lost_s = 0;
  std::vector<SlowLine> slowest;
  double wall_s = 0;  // wall-clock time of the program's worker process
};

// Fills the result's figures from `cncore run --summary` JSON text; false when it does not parse.
bool read_summary_json(const std::string& text, ProgramResult& r);

// One row per program, in the order given: program,status,cycle_time_s,path_length_mm,blocks,
// cycles,time_lost_s,slowest_lines,error.
std::string results_csv(const std::vector<ProgramResult>& results);

// One self-contained page ranking the programs by cycle time (failed programs last).
std::string results_html(const std::vector<ProgramResult>& results, const std::string& machine,
                         double wall_s, unsigned jobs);

}  // namespace cncore::app::estimate
