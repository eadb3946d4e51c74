// The control interface of `cncore serve`: one object every front end (the command line, the
// Grbl endpoint, the web page, telemetry) drives and reads. Front ends never reach into the
// motion kernel: they send commands here and poll the published status.
//
// Threads behind it (docs/runtime.md): a cycle thread runs the motion kernel once per
// interpolation period, paced by absolute-time sleeps, and never allocates, locks, logs or
// blocks; a planning thread interprets programs and feeds their blocks ahead through a
// lock-free ring. The methods below may be called from any thread (they serialise among
// themselves) and return once the cycle thread has taken the command (within a cycle or two),
// so a status read after a call sees its effect; none of them waits for the machine to move.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "config/machine_config.hpp"
#include "core/geometry.hpp"
#include "interpreter/modal_state.hpp"
#include "motion/kernel.hpp"
#include "runtime/state_machine.hpp"

namespace cncore::runtime {

// Operator switches. Optional stop acts at once; single block from the next block the kernel
// takes in (the blocks it already plans ahead run on); block delete on programs started after
// the change.
struct Switches {
  bool optional_stop = false;  // M1 pauses like M0
  bool single_block = false;   // pause after every motion block (cycle start goes on)
  bool block_delete = true;    // lines starting with "/" are skipped
  friend bool operator==(const Switches&, const Switches&) = default;
};

// How the current or last program / MDI job ended.
enum class JobEnd : std::uint8_t {
  kRunning,    // not yet (or no job so far)
  kCompleted,  // its last block ran
  kReset,      // a reset stopped it
  kAlarm,      // an alarm (E-stop, program error, soft limit, …) stopped it
};

// What the cycle thread publishes every cycle (a consistent copy: see Controller::status()).
struct Status {
  MachineState state = MachineState::kIdle;
  bool hold_complete = false;  // Hold: the tool has stopped (false: still decelerating)
  bool resetting = false;      // a reset is stopping the tool; Idle follows
  AlarmCode alarm = AlarmCode::kNone;
  std::uint32_t alarm_line = 0;  // program line of a program or soft-limit alarm
  bool homed = false;
  bool program_loaded = false;
  bool check_mode = false;
  std::uint64_t cycle = 0;             // cycles since the controller started
  std::uint64_t applied_commands = 0;  // commands the cycle has taken (see Controller)
  std::uint64_t job = 0;  // serial number of the program / MDI / jog / homing running or last run
  // The program or MDI job running or last run, as the cycle ran it: cycles of its first and
  // latest sample (its cycle time is (last − first) · period, as `cncore run` counts it).
  bool job_mdi = false;
  JobEnd job_end = JobEnd::kRunning;
  std::uint64_t job_first_cycle = 0;
  std::uint64_t job_last_cycle = 0;
  AxisVec commanded;    // set-points sent to the servos (machine coordinates, mm or deg)
  AxisVec actual;       // the servos' feedback
  AxisVec work_offset;  // active work offset (G54…G59.3 + G92), as the planner last saw it
  double following_error_mm = 0;  // largest |commanded − actual| over the axes this cycle
  std::uint32_t line = 0;         // program line under the tool (0: none)
  double feed_mm_min = 0;         // path speed this cycle
  double feed_override_pct = 100;
  double rapid_override_pct = 100;
  double load_pct = 0;                // spindle load (0 without a load source)
  double spindle_rpm = 0;             // the last S word the tool has reached
  bool spindle_on = false;            // M3/M4 reached, M5 not since
  bool spindle_ccw = false;           // the last of M3/M4 was M4
  bool coolant_mist = false;          // M7 reached, M9 not since
  bool coolant_flood = false;         // M8 reached, M9 not since
  std::uint32_t tool = 0;             // the tool in the spindle (T word, then M6), 0: none
  std::uint32_t blocks_queued = 0;    // blocks planned ahead of the kernel (ring)
  std::uint64_t overruns = 0;         // cycles that started after their deadline
  std::uint64_t starved_cycles = 0;   // cycles whose kernel wanted a block the planner lacked
  std::uint64_t samples_dropped = 0;  // samples the reader of read_samples() did not take in time
  double cycle_work_max_us = 0;       // longest cycle work so far
  Switches switches;
  // The cutting simulation (a machine with [stock]; docs/runtime.md): cycles whose sample waited
  // in the cycle thread because the simulation's ring was full (merged into the next one), and
  // how many cycles behind the cycle the load it reports is.
  std::uint64_t cutting_coalesced = 0;
  std::uint64_t cutting_lag_cycles = 0;
  std::uint64_t heightmap_version = 0;  // changes when a new height map is ready (0: none)
};

// The stock's height map as the cutting simulation last published it (at most twice a second,
// when it changed): cell centres at x0 + (i + ½)·cell, y0 + (j + ½)·cell, row-major by Y. A map
// larger than kMaxSide cells a side is shown by the lowest cell of each k×k block.
struct HeightMapGrid {
  static constexpr std::size_t kMaxSide = 256;
  std::uint64_t version = 0;
  std::size_t nx = 0, ny = 0;
  double x0_mm = 0, y0_mm = 0, cell_mm = 0;
  double bottom_z_mm = 0, top_z_mm = 0;
  std::vector<float> heights_mm;
};

// A jog: a straight move of the axes at a feed, incremental or to an absolute machine position,
// or continuous along a direction until cancelled; it stops at the travel limits.
struct JogRequest {
  AxisVec target;  // absolute: machine position; incremental: distance; continuous: direction
  std::uint32_t axes = 0;  // bit per axis slot that the jog moves
  bool incremental = true;
  bool continuous = false;
  double feed_mm_min = 0;  // 0: [servo] jog_feed_mm_min
};

struct Result {
  bool ok = true;
  std::string error;  // why not, for the operator (a program error: FILE:LINE:COL: error: …)
  static Result fail(std::string why) { return {false, std::move(why)}; }
};

// A command as the cycle thread applied it, with the cycle at which it took effect (what a test
// replays against `cncore run` to compare set-points cycle by cycle).
struct AppliedCommand {
  std::uint64_t cycle = 0;  // the first cycle that ran with it
  Command command = Command::kStart;
  double value = 0;  // overrides: percent; hold: 1 hold / 0 resume
};

// What the cycle thread measured of itself since the figures were last reset: how late it woke
// after each cycle's due time, and how long each cycle's work took (µs).
struct CycleFigures {
  std::uint64_t cycles = 0;
  double wake_p50_us = 0, wake_p99_us = 0, wake_p999_us = 0, wake_max_us = 0;
  double work_p50_us = 0, work_p99_us = 0, work_p999_us = 0, work_max_us = 0;
  std::uint64_t overruns = 0;
};

enum class ServoKind : std::uint8_t { kSim, kUdp, kShm };

struct ControllerOptions {
  ServoKind servo = ServoKind::kSim;
  std::string servo_address;      // udp: HOST:PORT; shm: NAME
  std::string state_dir;          // persistent machine state; empty: none kept
  bool realtime = true;           // try SCHED_FIFO + mlockall (reported when not allowed)
  bool paced = true;              // false: cycles run back to back (tests: same set-points, faster)
  std::size_t block_ring = 4096;  // planner → cycle (power of two)
  std::size_t sample_ring = 1U << 16;  // cycle → read_samples() (power of two; 0: no samples)
  // Tests with paced = false: the cycle waits for the reader instead of dropping samples. Never
  // on a machine: it makes the cycle wait on another thread.
  bool lossless_samples = false;
  // Simulated machine: where the axes really are relative to the controller's belief at start
  // (homing finds it), mm per axis slot.
  AxisVec sim_position_error;
  // Streamed lines (Controller::stream_line): the queue's capacity, and how long the stream
  // waits for a line, once the tool stands at the end of what it was given, before it ends.
  std::size_t stream_lines = 64;
  int stream_idle_end_ms = 100;
  // Where `o<name> call` finds name.ngc when the program or line does not define o<name> (a
  // program's own folder comes first).
  std::vector<std::string> subroutine_path;
};

// What became of a streamed line.
enum class StreamOutcome : std::uint8_t {
  kAccepted,  // checked and queued: it will run (after the lines before it)
  kRefused,   // an error in the line (Result::error); the stream goes on without it
  kWait,      // no room now (the queue is full, or a job that is not this stream still runs)
};

struct StreamReply {
  StreamOutcome outcome = StreamOutcome::kAccepted;
  std::string error;
};

// Room in the stream's queue (lines): what a sender's buffer report shows.
struct StreamRoom {
  std::size_t free_lines = 0;
  std::size_t capacity = 0;
};

// The machine values that may change while cncore runs (a sender's Grbl settings $11, $24, $25,
// $27, $110…, $120…, $130…): the rest of the configuration is fixed at start.
struct MachineLimits {
  double contour_tolerance_mm = 0;
  double home_latch_mm_min = 0, home_search_mm_min = 0, home_pulloff_mm = 0;
  std::array<double, kMaxAxes> max_speed_mm_min{}, max_accel_mm_s2{}, min_mm{}, max_mm{};
  bool operator==(const MachineLimits&) const = default;
};
MachineLimits limits_of(const MachineConfig& machine);
void apply_limits(MachineConfig& machine, const MachineLimits& limits);
// Empty when the limits are usable (every speed, acceleration and tolerance > 0, finite, each
// travel min < max), else what is wrong.
std::string limits_error(const MachineLimits& limits, const MachineConfig& machine);

class Controller {
 public:
  // Starts the threads. Throws InputError on a bad state file, std::runtime_error when a servo
  // output cannot be opened.
  Controller(const MachineConfig& machine, const ControllerOptions& options);
  // Stops the machine in a controlled way (a running program decelerates on its path), saves the
  // state and joins the threads.
  ~Controller();
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;

  // A consistent copy of the latest published status (wait-free for the cycle thread).
  Status status() const;
  // The configuration the controller started with (set_limits() does not change it).
  const MachineConfig& machine() const;
  // The limits in force now: the configuration's, as set_limits() last changed them.
  MachineLimits limits() const;
  // Changes the running machine's limits. Only when nothing moves (Idle, Alarm or Check); the
  // next program, MDI line, stream, jog and homing use them.
  Result set_limits(const MachineLimits& limits);
  // Messages for the operator that arose outside a command (a program error met while running,
  // the real-time set-up): taken once each.
  std::optional<std::string> take_message();

  // The program checked as a whole before anything moves (travel limits, syntax): the first
  // error is returned at its line and nothing is loaded.
  Result load_program(const std::string& path);
  Result cycle_start();  // Idle with a program: run it; Hold: resume
  Result feed_hold();
  Result reset();        // controlled stop; the program ends; alarms other than E-stop clear
  Result estop();        // set-points frozen from the next cycle; alarm latched
  Result clear_alarm();  // unlock after an alarm (the E-stop too)
  Result jog(const JogRequest& request);
  Result jog_cancel();
  Result home();
  Result mdi(const std::string& line);  // one or more lines of G-code, run at once
  // One line of a stream (a sender's program sent line by line): interpreted at once from the
  // state the lines before it left (an error refuses this line only, before anything moves),
  // then queued into one running job, so the look-ahead plans across the lines as it does for
  // a program file. The stream ends when the queue has drained, the tool stands at the end of
  // what it was given and no line came for `stream_idle_end_ms`, or after a line with M2/M30; the
  // next line starts a new stream once the machine is idle. Reset, E-stop and alarms drop the
  // queued lines. In Check, lines are interpreted and nothing moves.
  StreamReply stream_line(const std::string& line);
  StreamRoom stream_room() const;
  // The interpreter's modal state after the last line it took: a stream's last checked line
  // while a stream is open, else what the last completed program or MDI line left (the start
  // state when none). What a sender's `$G` shows.
  interp::ModalState parser_state() const;
  // The last line stream_line() took was a probe move (G38.2 … G38.5): whether the probe trips
  // on it (the simulated probe, [probe] in the configuration); nullopt: not a probe move.
  std::optional<bool> last_line_probe() const;
  // The next program, MDI line or stream starts from the start modes (G80 G54 G17 G21 G90 G94,
  // no F, S or T), as a Grbl board's soft reset leaves its parser. Offsets and parameters stay.
  void forget_modes();
  Result set_feed_override(double pct);
  Result set_rapid_override(double pct);
  Result set_switches(const Switches& switches);
  Result set_check_mode(bool on);  // Check: programs are interpreted, nothing moves

  // Samples of the cycles run so far, oldest first, as many as fit (one reader only). Samples the
  // reader leaves too long are dropped (Status::samples_dropped).
  std::size_t read_samples(std::span<motion::Sample> out);
  std::size_t read_applied(std::span<AppliedCommand> out);
  // The cutting simulation's latest height map (null without [stock]), and a fresh stock (the
  // map is also made fresh when a program starts).
  std::shared_ptr<const HeightMapGrid> heightmap() const;
  Result reset_stock();
  // The cycle thread's figures (it computes them between two cycles when asked; waits ≤ 1 s).
  // reset: start counting afresh after this reading.
  CycleFigures cycle_figures(bool reset);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cncore::runtime
