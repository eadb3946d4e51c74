// HTML report of table operation (`cncore table … --report FILE.html`, spec 02/05): one
// self-contained page with the summary, the speed and the acceleration of every table axis
// against time with its limits, the reference value with the M codes that fired, and the axis
// positions. Same page machinery (uPlot inlined, error hooks, browser check) as the run report.
//
// TableReportObserver streams: at most 2·buckets fixed-size buckets that keep the minimum and
// maximum of every channel (neighbours merge when full, so a peak is never averaged away), and
// the first m_events M codes; memory does not grow with the run.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "io/differences.hpp"
#include "io/summary.hpp"
#include "simulation/run.hpp"

namespace cncore::io {

// Extremes of one channel over consecutive samples (NaN: no value yet).
struct MinMax {
  double min = std::nan(""), max = std::nan("");
  bool min_first = true;  // the minimum came before the maximum (drawing order)
  void add(double v);
  void merge(const MinMax& later);
};

struct TableReportBucket {
  double t_first_s = 0, t_last_s = 0;
  std::uint64_t samples = 0;
  std::array<MinMax, kMaxAxes> position;  // mm or deg
  std::array<MinMax, kMaxAxes> speed;     // |v|, mm/min or deg/min
  std::array<MinMax, kMaxAxes> accel;     // |a|, mm/s² or deg/s²
  MinMax ref;                             // reference value (ms, mm or deg)
  std::uint32_t m_codes = 0;              // M codes fired in the bucket
};

struct TableReportEvent {
  double t_s = 0;
  std::size_t table = 0;  // index into TableReportInput::tables
  std::uint32_t line = 0;
  int code = 0;
  double ref = 0;
};

struct TableReportOptions {
  std::size_t buckets = 2048;  // after a merge (2× before)
  std::size_t m_events = 100;  // M codes listed on the page (all are counted and marked)
};

class TableReportObserver : public sim::SampleObserver {
 public:
  // axis_mask: bit i set → axis slot i is charted (the table axes, and a master axis).
  TableReportObserver(const MachineConfig& machine, std::uint32_t axis_mask,
                      TableReportOptions options = {});

  // An M code of row `line` of table number `table` fired in the cycle at t_s, with reference
  // value ref; call before that cycle's on_sample.
  void add_m_code(double t_s, std::size_t table, std::uint32_t line, int code, double ref);
  void on_sample(const motion::Sample& sample) override;  // sample.ref: the reference value

  const std::vector<TableReportBucket>& buckets() const { return buckets_; }
  const std::vector<TableReportEvent>& events() const { return events_; }
  std::uint64_t m_code_count() const { return m_code_count_; }
  std::uint32_t axis_mask() const { return axis_mask_; }
  std::uint64_t samples() const { return samples_; }
  std::size_t memory_bytes() const;

 private:
  void add_to_bucket(const TableReportBucket& b);

  std::uint32_t axis_mask_;
  TableReportOptions options_;
  FiniteDifferences diff_;
  std::vector<TableReportBucket> buckets_;
  std::uint64_t bucket_samples_ = 1;  // samples per bucket (doubles at each merge)
  std::vector<TableReportEvent> events_;
  std::uint64_t m_code_count_ = 0;
  std::uint32_t pending_m_ = 0;  // M codes of the coming sample
  std::uint64_t samples_ = 0;
};

struct TableReportInput {
  std::vector<std::string> tables;  // paths of the table files
  std::string title;                // default: "cncore table report: FILE[, FILE…]"
  std::string ref_name;             // "time", "axis X", "spindle"
  std::string ref_unit;             // "ms", "mm", "deg"
  double start_ref = 0, end_ref = 0;
  double slow_factor = 1;             // > 1: the reference was slowed to fit the axis limits
  bool finished = true;               // false: stopped before the end
  std::vector<std::string> warnings;  // of the table run (the summary's are added)
};

// The whole page. Deterministic for the same inputs (no dates).
std::string render_table_report_html(const TableReportObserver& report, const Summary& summary,
                                     const MachineConfig& machine, const TableReportInput& input);

}  // namespace cncore::io
