// Progress of a run on stderr (`--progress[=auto|on|off|json]`): how much of the program the tool
// has run (lines; the look-ahead reads further), the simulated time, the speed against real time
// and the time left. stdout keeps the summary, so progress never mixes with it.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "simulation/run.hpp"

namespace cncore::app {

enum class ProgressMode {
  kOff,
  kLine,  // one human-readable line: rewritten in place on a terminal, one line per update else
  kJson,  // one JSON object per line and update, the last with "done": true
};

// "auto" (on when stderr is a terminal), "on", "off" or "json"; anything else is a UsageError.
ProgressMode progress_mode(const std::string& option);

// The observer checks the clock every 4096 cycles. The line shows once the run has taken a second
// (short runs print nothing) and then every half second; json writes an update every half second
// from the start and a last one when the run ends.
class ProgressObserver : public sim::SampleObserver {
 public:
  // program_path: the file whose lines are counted for the percentage (one pass over it before the
  // run); empty: no percentage (e.g. tables).
  ProgressObserver(ProgressMode mode, const std::string& program_path);
  ~ProgressObserver() override { clear(); }
  ProgressObserver(const ProgressObserver&) = delete;
  ProgressObserver& operator=(const ProgressObserver&) = delete;
  void on_sample(const motion::Sample& s) override;
  void on_finish() override;
  bool enabled() const { return mode_ != ProgressMode::kOff; }

 private:
  using Clock = std::chrono::steady_clock;
  void show(double wall_s, bool done);
  void clear();

  ProgressMode mode_;
  bool terminal_;
  bool shown_ = false;
  std::uint32_t lines_total_ = 0;  // 0: no percentage
  std::uint32_t line_ = 0;         // furthest source line the tool has run
  std::uint64_t cycles_ = 0;
  double sim_s_ = 0;
  double next_update_s_;
  Clock::time_point start_;
};

}  // namespace cncore::app
