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
  // The whole program's time lost against the programmed feed × override (the summary's
  // `time_lost_s`); the slowest lines are a part of it.
  double time_lost_s = 0;
  // Time lost against F as written, by cause (the summary's `time_lost_by_cause_s`, in the order
  // of io::LossCause); empty when the summary has none.
  std::vector<double> lost_by_cause_s;
  std::vector<SlowLine> slowest;
  double wall_s = 0;  // wall-clock time of the program's worker process
};

// Fills the result's figures from `cncore run --summary` JSON text; false when it does not parse.
bool read_summary_json(const std::string& text, ProgramResult& r);

// One row per program, in the order given: program,status,cycle_time_s,path_length_mm,blocks,
// cycles,time_lost_s,lost_<cause>_s for each cause,slowest_lines,error.
std::string results_csv(const std::vector<ProgramResult>& results);

// One self-contained page ranking the programs by cycle time (failed programs last).
std::string results_html(const std::vector<ProgramResult>& results, const std::string& machine,
                         double wall_s, unsigned jobs);

}  // namespace cncore::app::estimate
