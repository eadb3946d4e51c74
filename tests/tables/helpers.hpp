// Test helpers: a small machine, running table text and reading outcomes off the samples.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "tables/table.hpp"

namespace cncore::tables::test {

// X, Y, Z: travel ±1000 mm, 10 000 mm/min, 2 000 mm/s²; period 1 ms.
inline MachineConfig test_machine() {
  MachineConfig m;
  m.period_s = 0.001;
  for (std::size_t a : {kX, kY, kZ}) {
    m.axes[a].enabled = true;
    m.axes[a].min_mm = -1000;
    m.axes[a].max_mm = 1000;
    m.axes[a].max_speed_mm_min = 10000;
    m.axes[a].max_accel_mm_s2 = 2000;
  }
  return m;
}

// test_machine() with axes stiff enough for the seed's linear distribution: 10⁶ mm/s², so a
// velocity step of up to 1000 mm/s within one 1 ms period is within the limit. For the tests of
// what the tables do (shifts, references, rows); the limit tests use test_machine().
inline MachineConfig stiff_machine() {
  MachineConfig m = test_machine();
  for (std::size_t a : {kX, kY, kZ}) m.axes[a].max_accel_mm_s2 = 1e6;
  return m;
}

struct TableRun {
  TablePlan plan;
  std::vector<TableSample> samples;
  RunSummary summary;
};

inline TableRun run_texts(const std::vector<std::string>& texts, const RunOptions& options = {},
                          const MachineConfig& machine = stiff_machine()) {
  std::vector<Table> tables;
  for (std::size_t i = 0; i < texts.size(); ++i) {
    tables.push_back(parse_table(texts[i], "t" + std::to_string(i + 1) + ".tbl"));
  }
  TableRun r;
  r.plan = plan_tables(std::move(tables), machine, options);
  r.summary = run_tables(r.plan, [&](const TableSample& s) { r.samples.push_back(s); });
  return r;
}

// Time of the first sample at which `axis` has reached `value` (moving up: ≥, down: ≤).
inline double time_reaching(const std::vector<TableSample>& s, std::size_t axis, double value,
                            bool upwards = true) {
  for (const auto& x : s) {
    double p = x.position[axis];
    if (upwards ? p >= value - 1e-6 : p <= value + 1e-6) return x.t_s;
  }
  return NAN;
}

// Finite-difference velocity (units/s) between samples i-1 and i.
inline double fd_velocity(const std::vector<TableSample>& s, std::size_t axis, std::size_t i) {
  return (s[i].position[axis] - s[i - 1].position[axis]) / (s[i].t_s - s[i - 1].t_s);
}

}  // namespace cncore::tables::test
