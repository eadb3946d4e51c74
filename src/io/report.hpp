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

#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "io/differences.hpp"
#include "io/programmed_path.hpp"
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

// One point of the path views (X, Y, Z of the servo set-point) with the path speed there.
struct ReportPathPoint {
  double x_mm = 0, y_mm = 0, z_mm = 0;
  float speed_mm_min = 0;
  bool rapid = false;
};

// A slow program line: where and how slow it got, and why.
struct ReportSlowSpot {
  std::uint32_t line = 0;
  bool rapid = false;           // a G0 move: ranked apart from the cutting moves
  std::uint32_t last_line = 0;  // a merged line (Block::last_line): lines line…last_line
  std::uint64_t visits = 0;
  double lost_s = 0;  // Σ of the summary's shares (TimeShare::lost_s) of the line
  double time_s = 0, length_mm = 0;
  double min_speed_mm_min = 0;  // at the slowest cycle of the worst visit
  double target_mm_min = 0;     // programmed feed × override there (capped by the machine)
  double t_min_s = 0, x_mm = 0, y_mm = 0;
  double override_pct = 100;
  double correction = std::nan(""), load_pct = std::nan(""), load_target_pct = std::nan("");
  std::string why;  // causes, the most limiting first ("corner 90° into the next line; …")
};

// A direction change at least this large between two blocks is a corner the planner slows for
// (the chords of a fine curve turn by less).
inline constexpr double kCornerDeg = 0.5;

// What the time lost against the program as written went to (the rule is in
// report_losses.cpp, where each share of a cycle is attributed).
enum class LossCause : std::uint8_t {
  kCorners,
  kArcs,
  kShortSegments,
  kStops,
  kAcceleration,
  kFeedLimit,
  kOverride,
};
inline constexpr std::size_t kLossCauses = 7;
const char* loss_cause_name(LossCause cause);
// Its key in the summary JSON and the estimate CSV: the name with '_' for ' '.
std::string loss_cause_key(LossCause cause);

struct ReportLosses {
  // Time lost against F as written, by cause; the causes add up to total_s().
  std::array<double, kLossCauses> cause_s{};
  // The summary's time lost (against F × override, capped) on cutting moves and on rapids:
  // cutting_s + rapid_s = Summary::time_lost_s.
  double cutting_s = 0, rapid_s = 0;
  double total_s() const {
    double t = 0;
    for (const double c : cause_s) t += c;
    return t;
  }
};

// The summary JSON text with `time_lost_by_cause_s` added: an object with one key per cause
// (loss_cause_name with '_' for ' ') and `total`, their sum.
std::string summary_json_with_losses(const std::string& summary_json, const ReportLosses& losses);

struct ReportOptions {
  std::size_t buckets = 2048;       // time-series buckets after a merge (2× before)
  std::size_t path_points = 16384;  // top-view points kept at most
  std::size_t slow_spots = 10;      // rows of the slowest-lines table
};

// The time lost is the summary's own accounting (TimeShare): with `accounting` the observer
// listens to that SummaryObserver (which must see every block and sample before this one);
// without, it runs one of its own.
class ReportObserver : public sim::SampleObserver, public TimeShareListener {
 public:
  ReportObserver(const MachineConfig& machine, std::string mode, ReportOptions options = {},
                 SummaryObserver* accounting = nullptr);

  void on_block(const Block& block) override;
  void on_sample(const motion::Sample& sample) override;
  void on_finish() override;
  void on_share(const TimeShare& share) override;

  const std::vector<ReportBucket>& buckets() const { return buckets_; }
  const std::vector<ReportPathPoint>& path() const { return path_; }
  // The slowest cutting lines (G1, G2/G3), worst (most time lost) first; complete after
  // on_finish().
  std::vector<ReportSlowSpot> slowest() const;
  // The slowest rapid (G0) lines, the same way.
  std::vector<ReportSlowSpot> slowest_rapids() const;
  const ReportLosses& losses() const { return losses_; }
  // The cutting moves' speed range (mm/min), for the colour scale; 0 … 0 when none.
  double cutting_speed_max_mm_min() const { return cutting_vmax_mm_min_; }
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
    double arc_limit_mm_min = 0;  // arcs: √(A·R)
    ProgrammedMove move;
    // The nearest limits behind the block's start (distance along the path; ∞: none yet): the
    // last stop, corner and arc (its limit).
    double from_stop_mm = 0, from_corner_mm = INFINITY, from_arc_mm = INFINITY;
    double from_arc_limit_mm_min = 0;
    // Ahead of its end, within the distance it can slow the tool (see scan_ahead()).
    bool scanned = false;
    double to_stop_mm = INFINITY, to_corner_mm = INFINITY, to_arc_mm = INFINITY;
    double to_arc_limit_mm_min = 0;
  };
  struct Group {  // consecutive shares on one line
    ReportSlowSpot spot;
    bool active = false;
    double t_start_s = 0, t_end_s = 0;
    double first_speed_mm_min = -1, last_speed_mm_min = 0;
  };
  SummaryObserver& accounting() { return accounting_ ? *accounting_ : *own_accounting_; }
  static Pending* current_block(std::deque<Pending>& pending, std::uint32_t line);
  void scan_ahead(Pending& b, double within_mm);
  void push_block(std::deque<Pending>& pending, Pending p);
  void attribute(const TimeShare& share, const Pending* b);
  LossCause dynamic_cause(const TimeShare& share, const Pending& b) const;
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
  double path_step_mm_ = 0.005;          // minimum spacing of kept points (doubles when full)
  double path_dv_mm_min_ = 0;            // speed change that keeps a point although close
  std::deque<Pending> pending_;          // the samples' blocks
  std::deque<Pending> explain_pending_;  // the shares' blocks (the summary may run ahead)
  SummaryObserver* accounting_ = nullptr;
  std::unique_ptr<SummaryObserver> own_accounting_;
  Vec3 last_tangent_{};
  std::size_t pending_max_ = 0;
  bool have_tangent_ = false;
  bool stop_pending_ = true;
  FiniteDifferences diff_;  // same definitions as the summary
  bool have_prev_ = false;
  double prev_t_ = 0;  // time of the last sample
  Group group_;
  std::vector<ReportSlowSpot> top_, top_rapid_;  // bounded, merged by line
  ReportLosses losses_;
  double cutting_vmax_mm_min_ = 0;
  std::uint64_t samples_ = 0;
  bool has_correction_ = false, has_load_ = false, has_override_ = false;
};

// The cutting simulation's final height map (docs/cutting-simulation.md), shown in the page.
struct ReportHeightMap {
  std::string png;  // PNG bytes (cut::heightmap_png); empty: none
  double bottom_z_mm = 0, top_z_mm = 0;
  std::vector<std::string> scale;  // CSS colours of the map from the bottom to the top
};

struct ReportInput {
  std::string program;  // path of the part program (its lines are quoted in the table)
  std::string title;    // page title; default: "cncore report: PROGRAM"
  ReportHeightMap heightmap;
};

// The whole page. Deterministic for the same inputs (no dates).
std::string render_report_html(const ReportObserver& report, const Summary& summary,
                               const MachineConfig& machine, const ReportInput& input);

}  // namespace cncore::io
