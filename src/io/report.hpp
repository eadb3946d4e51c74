// HTML report of a run (`cncore run … --report FILE.html`, spec 05): one self-contained page with
// the summary, speed and acceleration against time, a top view of the tool path coloured by
// speed and the slowest program lines with the reason they are slow.
//
// ReportObserver streams: memory does not grow with the program or the run. Time series go into
// at most 2·kBuckets fixed-size buckets that keep the minimum and maximum of every channel (two
// neighbours merge when the buckets are full, so a peak is never averaged away); the top view
// keeps at most kPathPoints points (the spacing doubles when full); the slow spots are a bounded
// candidate set merged by line.
#pragma once

#include <cmath>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "io/differences.hpp"
#include "io/summary.hpp"
#include "simulation/run.hpp"

namespace cncore::io {

// Extremes of every channel over a run of consecutive samples.
struct ReportBucket {
  double t_first_s = 0, t_last_s = 0;
  std::uint64_t samples = 0;
  double speed_min_mm_min = 0, speed_max_mm_min = 0;
  bool speed_min_first = true;  // the minimum came before the maximum (drawing order)
  double accel_min_mm_s2 = 0, accel_max_mm_s2 = 0;  // tangential, signed
  bool accel_min_first = true;
  double path_accel_max_mm_s2 = 0;  // resultant |Δv|/Δt (normal acceleration included)
  double feed_max_mm_min = 0;       // programmed feed (F; rapid rate for G0)
  double limit_max_mm_min = 0;      // machine limit of the move (max feed; rapid rate for G0)
  double override_min_pct = 100, override_max_pct = 100;
  double correction_min = std::nan(""), correction_max = std::nan("");
  double load_max_pct = std::nan(""), load_target_pct = std::nan("");
};

// One point of the top view (X, Y of the servo set-point) with the path speed there.
struct ReportPathPoint {
  double x_mm = 0, y_mm = 0;
  float speed_mm_min = 0;
  bool rapid = false;
};

// A slow program line: where and how slow it got, and why.
struct ReportSlowSpot {
  std::uint32_t line = 0;
  std::uint32_t last_line = 0;  // a merged line (Block::last_line): lines line…last_line
  std::uint64_t visits = 0;
  double lost_s = 0;  // Σ dt·(1 − v/target), target = programmed feed × override (capped)
  double time_s = 0, length_mm = 0;
  double min_speed_mm_min = 0;  // at the slowest cycle of the worst visit
  double target_mm_min = 0;     // programmed feed × override there (capped by the machine)
  double t_min_s = 0, x_mm = 0, y_mm = 0;
  double override_pct = 100;
  double correction = std::nan(""), load_pct = std::nan(""), load_target_pct = std::nan("");
  std::string why;  // causes, the most limiting first ("corner 90° into the next line; …")
};

struct ReportOptions {
  std::size_t buckets = 2048;       // time-series buckets after a merge (2× before)
  std::size_t path_points = 16384;  // top-view points kept at most
  std::size_t slow_spots = 10;      // rows of the slowest-lines table
};

class ReportObserver : public sim::SampleObserver {
 public:
  ReportObserver(const MachineConfig& machine, std::string mode, ReportOptions options = {});

  void on_block(const Block& block) override;
  void on_sample(const motion::Sample& sample) override;
  void on_finish() override;

  const std::vector<ReportBucket>& buckets() const { return buckets_; }
  const std::vector<ReportPathPoint>& path() const { return path_; }
  // The slowest lines, worst (most time lost) first; complete after on_finish().
  std::vector<ReportSlowSpot> slowest() const;
  bool has_correction() const { return has_correction_; }
  bool has_load() const { return has_load_; }
  bool has_override() const { return has_override_; }
  std::uint64_t samples() const { return samples_; }
  // Bytes held by the observer's containers (capacity); flat in the run length.
  std::size_t memory_bytes() const;

 private:
  // A block handed to the kernel and not yet executed (bounded by the kernel's buffer).
  struct Pending {
    std::uint32_t line = 0;
    std::uint32_t last_line = 0;  // Block::last_line
    BlockKind kind = BlockKind::kLine;
    double feed_mm_min = 0;  // programmed (rapid rate for G0), before the machine's cap
    double cap_mm_min = 0;   // the machine limit of the move
    double length_mm = 0;
    double radius_mm = 0;          // arcs
    double entry_corner_deg = -1;  // direction change from the previous motion block; -1 none
    double exit_corner_deg = -1;   // to the next one (set when it arrives)
    bool stop_before = true;       // starts from standstill (program start, dwell, waiting M)
    bool stop_after = false;       // must end at standstill (G61.1/G9, dwell, waiting M, end)
    const char* stop_reason = "";  // why it stops at its end
    bool has_successor = false;
  };
  struct Group {  // consecutive samples on one line
    ReportSlowSpot spot;
    bool active = false;
    double t_start_s = 0;
    double first_speed_mm_min = -1, last_speed_mm_min = 0;
  };
  const Pending* current_block(std::uint32_t line);
  void add_to_bucket(const ReportBucket& b);
  void add_path_point(const ReportPathPoint& p);
  void thin_path();
  void close_group();
  std::string explain(const ReportSlowSpot& s, const Pending* b, double fraction,
                      bool start_stopped, bool end_stopped) const;

  MachineConfig machine_;
  std::string mode_;
  ReportOptions options_;
  std::vector<ReportBucket> buckets_;
  std::uint64_t bucket_samples_ = 1;  // samples per bucket (doubles at each merge)
  std::vector<ReportPathPoint> path_;
  double path_step_mm_ = 0.005;  // minimum spacing of kept points (doubles when full)
  double path_dv_mm_min_ = 0;    // speed change that keeps a point although close
  std::deque<Pending> pending_;
  Vec3 last_tangent_{};
  bool have_tangent_ = false;
  bool stop_pending_ = true;
  FiniteDifferences diff_;  // same definitions as the summary
  bool have_prev_ = false;
  double prev_t_ = 0;  // time of the last sample
  Group group_;
  std::vector<ReportSlowSpot> top_;  // bounded, merged by line
  std::uint64_t samples_ = 0;
  bool has_correction_ = false, has_load_ = false, has_override_ = false;
};

struct ReportInput {
  std::string program;  // path of the part program (its lines are quoted in the table)
  std::string title;    // page title; default: "cncore report: PROGRAM"
};

// The whole page. Deterministic for the same inputs (no dates).
std::string render_report_html(const ReportObserver& report, const Summary& summary,
                               const MachineConfig& machine, const ReportInput& input);

}  // namespace cncore::io
