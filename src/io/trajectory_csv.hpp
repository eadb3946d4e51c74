// Trajectory CSV (spec 05): a header row, then one row per interpolation cycle from t = 0 to the
// final stop. Required columns t, line, one per configured axis (x y z a b c, machine
// coordinates), feed; optional override, correction, load, load_target, ref (table runs) when
// active. Streamed through a fixed buffer into an AtomicOutputFile: memory does not grow with the
// run.
#pragma once

#include <fmt/format.h>

#include <array>
#include <cstddef>
#include <string>

#include "config/machine_config.hpp"
#include "io/atomic_file.hpp"
#include "simulation/run.hpp"

namespace cncore::io {

// Which optional columns to write (a feature is "active" when the run uses it).
struct TrajectoryColumns {
  bool override_pct = false;  // `override`, %
  bool correction = false;    // `correction`, spec 03 coefficient
  bool load = false;          // `load`, % (spec 04)
  bool load_target = false;   // `load_target`, %
  bool ref = false;           // `ref`, table reference value (spec 02: ms, mm or deg)
  bool m_code = false;        // `m`, number of the M code fired in this cycle, empty when none
};

class TrajectoryCsvWriter : public sim::SampleObserver {
 public:
  // Creates the temporary output file and writes the header. Throws InputError if the file
  // cannot be created.
  TrajectoryCsvWriter(const std::string& path, const MachineConfig& machine,
                      const TrajectoryColumns& columns);

  void on_sample(const motion::Sample& sample) override;
  void on_finish() override;  // flushes the buffer
  // Flushes and renames the file into place. Without commit the file never appears.
  void commit();

  // The header row (without newline), for tests and docs.
  static std::string header(const MachineConfig& machine, const TrajectoryColumns& columns);

 private:
  void flush();

  AtomicOutputFile file_;
  TrajectoryColumns columns_;
  std::array<std::size_t, kMaxAxes> axes_{};  // slots of the enabled axes, in order
  std::size_t axis_count_ = 0;
  fmt::memory_buffer buffer_;
};

}  // namespace cncore::io
