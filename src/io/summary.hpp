// Run summary (spec 05 summary JSON and the human summary of `cncore run`), computed from the
// samples alone by finite differences: it measures what the servos were told to do and does not
// rely on the kernel's bookkeeping. Memory is bounded (no per-sample or per-line storage).
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "io/differences.hpp"
#include "io/fifo.hpp"
#include "io/programmed_path.hpp"
#include "simulation/run.hpp"

namespace cncore::io {

// A program line where the machine ran below its programmed feed. lost_s is the time spent on
// the line minus the time the same distance takes at the programmed feed (× override):
// Σ dt·(1 − v/F) over the line's cycles. A cycle that passes several blocks gives each the part
// of dt its share of the cycle's travel takes. Lines are ranked by lost_s.
struct SlowSpot {
  std::uint32_t line = 0;
  // A line merged from collinear pieces (Block::last_line): the source line of its last piece,
  // so the spot is lines line…last_line; 0: the single line `line`.
  std::uint32_t last_line = 0;
  double lost_s = 0;
  double time_s = 0;                  // time spent on the line
  double length_mm = 0;               // distance travelled on the line
  double programmed_feed_mm_min = 0;  // F × override (rapid rate for G0), last seen
  std::uint64_t visits = 0;           // separate executions (loops, subroutines)
  bool rapid = false;                 // a G0 move (target: the rapid rate)
  double average_feed_mm_min() const { return time_s > 0 ? length_mm / time_s * 60 : 0; }
};

// An auxiliary function (M, S, T …) reached during the run.
struct AuxEvent {
  double t_s = 0;
  std::uint32_t line = 0;
  char letter = 'M';
  double value = 0;
};

// Spindle load and adaptive feed control (spec 04): present when the run had a load source.
// The observer measures the load columns; the caller fills in the rest.
struct LoadSummary {
  bool present = false;
  double peak_load_pct = 0;
  double mean_load_pct = 0;             // over every cycle of the run (air time included)
  double time_above_target_s = 0;       // cycles with load > load_target, × period
  double time_above_target_band_s = 0;  // load > load_target + kBandPct
  static constexpr double kBandPct = 5;
  // Set by the caller (cncore run):
  bool adaptive = false;   // the controller ran (enabled at start, or by M52 P1)
  std::string antiwindup;  // adaptive.antiwindup
  std::string source;      // "plant model", "recorded FILE"
  double target_load_pct = 0;
  double time_without_adaptive_s = 0;  // the same run again with the operator's override only
  double time_saved_s = 0;             // time_without_adaptive_s − cycle_time_s
  std::uint64_t switches = 0;          // M52 events
};

struct Summary {
  double cycle_time_s = 0;                // time of the last sample
  std::uint64_t blocks = 0;               // motion blocks (G0, G1, G2/G3) executed
  std::uint64_t cycles = 0;               // samples
  double path_length_mm = 0;              // Σ |ΔP| of the linear axes' set-points
  double max_feed_mm_min = 0;             // max |ΔP|/Δt of the linear axes
  double max_tangential_accel_mm_s2 = 0;  // max |Δ|v||/Δt (change of speed)
  double max_path_accel_mm_s2 = 0;        // max |Δv|/Δt (resultant, incl. normal at arcs/corners)
  std::array<double, kMaxAxes> max_axis_speed_mm_min{};
  std::array<double, kMaxAxes> max_axis_accel_mm_s2{};  // max |Δ²p|/Δt² per axis
  // Servo set-point to the path as programmed (lines, arcs as arcs; not the merged or rounded
  // path the kernel ran), see summary.cpp.
  double max_contour_error_mm = 0;
  double max_servo_lag_mm = 0;  // servo set-point to the same cycle's on-path point
  // Direction feed correction (spec 03): range of the coefficient C over the run (NaN: not
  // active), and the cycle time of the same program without it (a second run; NaN: not run).
  double correction_min = std::numeric_limits<double>::quiet_NaN();
  double correction_max = std::numeric_limits<double>::quiet_NaN();
  double time_without_correction_s = std::numeric_limits<double>::quiet_NaN();
  std::string mode;
  std::string accdec;  // look-ahead acc/dec type ("acceleration", "moving_average"); "" = n/a
  sim::OperatorModes operator_modes;  // dry run, single-block stop (as the run had them)
  std::vector<std::string> warnings;
  std::vector<SlowSpot> slowest;     // worst first, at most 5
  double time_lost_s = 0;            // Σ lost_s over every block of the run (not only the slowest)
  std::uint64_t blocks_timed = 0;    // motion block executions given a share of the cycles' time
  std::vector<AuxEvent> aux_events;  // the first kMaxAuxEvents, in order
  std::uint64_t aux_event_count = 0;                  // all of them
  static constexpr std::size_t kMaxAuxEvents = 1000;  // bounded: memory flat in program length
  LoadSummary load;
};

// One block's share of one cycle, as the summary accounts it (see SummaryObserver::share): the
// HTML report ranks and explains the time lost from these, so both give the same figures.
struct TimeShare {
  const motion::Sample* sample = nullptr;  // the sample that closes the cycle
  std::uint32_t line = 0;
  std::uint32_t last_line = 0;  // Block::last_line
  bool rapid = false;
  double dt_s = 0;               // the block's part of the cycle
  double length_mm = 0;          // the distance travelled on the block in it
  double programmed_mm_min = 0;  // F as written (the rapid rate for G0), before the cap
  double cap_mm_min = 0;         // the machine's limit of the move
  double target_mm_min = 0;      // min(F × override, cap)
  double lost_s = 0;             // max(0, dt − length/target); 0 when the target is 0
};

class TimeShareListener {
 public:
  virtual ~TimeShareListener() = default;
  virtual void on_share(const TimeShare& share) = 0;
};

class SummaryObserver : public sim::SampleObserver {
 public:
  SummaryObserver(const MachineConfig& machine, std::string mode);
  // Spec 03: the cycle time of the same program with the direction correction off.
  void set_time_without_correction_s(double t_s) { summary_.time_without_correction_s = t_s; }
  void set_accdec(std::string accdec) { summary_.accdec = std::move(accdec); }
  void set_operator_modes(const sim::OperatorModes& m) { summary_.operator_modes = m; }
  // The motion blocks of the program (the kernel may get fewer: collinear pieces merged, or
  // more: arcs split by the direction correction).
  void set_program_blocks(std::uint64_t n) { summary_.blocks = n; }
  // Receives every share of every cycle given to a motion block (nullptr: none).
  void set_share_listener(TimeShareListener* listener) { listener_ = listener; }

  void on_block(const Block& block) override;
  void on_sample(const motion::Sample& sample) override;
  void on_samples(std::span<const motion::Sample> samples) override;
  void on_finish() override;

  const Summary& summary() const { return summary_; }
  // The load part, for the caller to fill in what it knows (adaptive control, time saved).
  LoadSummary& load_summary() { return summary_.load; }
  // Records an auxiliary event. on_sample records the sample's own event unless the caller
  // delivers events itself (a table cycle can fire several M codes; a sample carries one).
  void add_event(const AuxEvent& event);
  void set_record_sample_events(bool on) { record_sample_events_ = on; }

 private:
  struct Pending {
    std::uint32_t line;
    double programmed_mm_min;  // F as written (the rapid rate for G0)
    double cap_mm_min;         // the limit itself (max feed, or rapid rate for G0)
    bool rapid;
    bool motion;              // a motion block (else a dwell: no geometry)
    bool timed;               // given a share of some cycle's time already
    std::uint32_t last_line;  // Block::last_line
    ProgrammedMove move;      // as programmed
  };
  // A programmed move the tool has passed, and when (the contour error's window).
  struct Passed {
    ProgrammedMove move;
    double t_s;
  };
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t match(std::uint32_t line, Vec3 pos) const;
  void share(const motion::Sample& s, std::size_t j, double dt_s, double len_mm);
  void credit(Pending& b, double dt_s, double len_mm, const motion::Sample& s);
  void pass(std::size_t j, double t_s);
  double programmed_distance(Vec3 pos, std::size_t j, double t_s) const;
  double path_ring_distance(Vec3 pos, double lag_mm);
  void close_group();
  template <std::size_t N>
  void sample(const motion::Sample& s);  // on_sample with axes N… disabled
  template <std::size_t N>
  void travel_check(const motion::Sample& s);
  [[gnu::noinline, gnu::cold]] void travel_warn(const motion::Sample& s);

  MachineConfig machine_;
  Summary summary_;
  // The programmed blocks handed to the kernel and not yet passed (the pieces of merged lines
  // too: bounded by the kernel's buffer and its ring of pieces).
  GrowingFifo<Pending> pending_;
  std::size_t pending_max_;
  // The programmed moves passed in the last window_s_ (at most kRecent).
  static constexpr std::size_t kRecent = 1024;
  std::vector<Passed> recent_;
  std::size_t recent_next_ = 0, recent_size_ = 0;
  double window_s_ = 0;
  Vec3 prev_path_;          // the previous sample's on-path point
  FiniteDifferences diff_;  // velocities and accelerations of the set-points
  // Tangential acceleration: the previous sample's speed along the path (see on_sample).
  double prev_speed_t_ = 0;
  bool prev_on_path_ = false;
  // Recent on-path points: the servo set-point lags behind on the path (post-interpolation
  // filter), so its contour error is the distance to the nearest of these path segments.
  std::vector<Vec3> path_ring_;
  std::size_t ring_next_ = 0, ring_size_ = 0;
  // Current line group (consecutive samples on one line) for the slowest spots.
  SlowSpot group_;
  std::vector<SlowSpot> top_;  // bounded candidate set, merged by line
  // How many candidates have a line ≡ i (mod kLineFilter): 0 = the line is surely not there.
  static constexpr std::size_t kLineFilter = 1024;
  std::array<std::uint8_t, kLineFilter> top_lines_{};
  // Index of the candidate with the least lost_s; kNoLeast: to be searched again.
  static constexpr std::size_t kNoLeast = static_cast<std::size_t>(-1);
  std::size_t least_ = kNoLeast;
  // travel_check: bit i set while enabled axis i has not left its travel yet; the limits with
  // their slack, computed once (the same doubles as computing them per sample); ±∞ for an axis
  // not checked (disabled, or already warned).
  unsigned travel_unwarned_ = 0;
  std::array<double, kMaxAxes> travel_lo_mm_{}, travel_hi_mm_{};
  bool record_sample_events_ = true;
  TimeShareListener* listener_ = nullptr;
  double load_sum_pct_ = 0;  // Σ load over the cycles with a reading
  std::uint64_t load_cycles_ = 0;
  // The last target feed of the slowest spots and what it was computed from (NaN: none yet).
  double target_feed_ = std::numeric_limits<double>::quiet_NaN();
  double target_cap_ = 0, target_override_ = 0, target_ = 0;
  bool have_previous_t_ = false;
  double previous_t_s_ = 0;
};

// Spec 05 summary JSON (plus extra keys: max_path_accel_mm_s2, max_axis_speed_mm_min,
// slowest_spots, machine).
std::string summary_to_json(const Summary& summary, const MachineConfig& machine);
// Writes the JSON atomically (temporary file + rename).
void write_summary_json(const std::string& path, const Summary& summary,
                        const MachineConfig& machine);
// The human summary printed by `cncore run`.
std::string format_human_summary(const Summary& summary, const MachineConfig& machine,
                                 const std::string& program);

}  // namespace cncore::io
