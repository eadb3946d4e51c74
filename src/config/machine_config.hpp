// The machine a program runs on: interpolation period, path and axis limits, acc/dec and
// tolerances. Loaded from TOML (load_machine_config) or the built-in default 3-axis mill.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "config/correction_law.hpp"
#include "config/cutting_config.hpp"
#include "core/geometry.hpp"
#include "feedcontrol/settings.hpp"

namespace cncore {

struct AxisConfig {
  bool enabled = false;
  bool rotary = false;  // A, B, C: degrees instead of mm
  double min_mm = 0;    // travel limits, machine coordinates
  double max_mm = 0;
  double max_speed_mm_min = 0;  // axis speed limit
  double max_accel_mm_s2 = 0;   // axis acceleration limit

  friend bool operator==(const AxisConfig&, const AxisConfig&) = default;
};

// [tables] cancel_mode (spec 02): what SFTCAN does with the accumulated reference shift. The
// command maps it onto tables::CancelMode (the config library does not depend on the tables).
// [motion] accdec: the acc/dec type of look-ahead mode. The app maps it onto
// motion::AccDecType (the config library does not depend on the motion stage).
enum class AccDecKind : std::uint8_t {
  kMovingAverage,  // "moving_average": the seed's look-ahead + moving average of T cycles
  kAcceleration,   // "acceleration": constant-acceleration planning before interpolation
  kSearch,         // "search": samples searched ahead of the tool (no jerk limit, no filter)
};

enum class TableCancelMode : std::uint8_t {
  kClear,   // "clear": the amount becomes 0, later rows use their written reference values
  kRebase,  // "rebase": the running reference is reset by the amount, later gaps stay shifted
};

// [direction_correction] override_mode (spec 03): how the coefficient C meets the operator's
// feed override Fr.
enum class CorrectionOverrideMode : std::uint8_t {
  kMultiply,  // "multiply": C × Fr (the operator's override still acts)
  kReplace,   // "replace": C alone (the override switch is ignored on corrected moves)
};

// [direction_correction] (spec 03, seed JPH0830973B2): feed correction by direction of motion.
// FI = (unit direction of motion) · direction, in [−1, 1]; C = uphill(FI) for FI ≥ 0, downhill(FI)
// for FI < 0; the programmed feed of every G1/G2/G3 becomes F·C (arcs: per sub-arc).
struct DirectionCorrectionConfig {
  bool enabled = false;         // the seed's on/off parameter (off: the run is unchanged)
  bool active_at_start = true;  // on from the program start (M160 / M161 switch it)
  Vec3 direction{0, 0, 1};      // unit vector (Z by default; e.g. the tool axis)
  CorrectionLaw uphill{"1 + 0.5*FI", {}};    // FI ≥ 0, C ≥ 1 in the seed
  CorrectionLaw downhill{"1 + 0.5*FI", {}};  // FI < 0, C < 1 in the seed
  CorrectionOverrideMode override_mode = CorrectionOverrideMode::kMultiply;
  double tool_diameter_mm = 10;  // D in the formulas
  double arc_step_deg = 5;       // arcs and helices are corrected per sub-arc of at most this

  friend bool operator==(const DirectionCorrectionConfig&,
                         const DirectionCorrectionConfig&) = default;
};

// [servo] (`cncore serve`): the simulated axes' position loop, the following-error alarm, homing
// against the simulated switches (at each axis's travel maximum) and jogging.
struct ServoConfig {
  double kp_per_s = 300;   // position-loop gain: velocity = ff·commanded velocity + kp·error
  double feedforward = 1;  // velocity feed-forward, 0 … 1
  double following_error_limit_mm = 1;  // |commanded − actual| above this raises an alarm
  double home_search_mm_min = 1500;     // speed towards the switch
  double home_latch_mm_min = 100;       // speed off the switch (the latch)
  double home_pulloff_mm = 2;           // distance moved off the switch after the latch
  double jog_feed_mm_min = 2000;        // jog feed when the request names none

  friend bool operator==(const ServoConfig&, const ServoConfig&) = default;
};

// [probe] (G38.2–G38.5): the probe trips where the tool tip (the controlled point) enters one of
// these solids, given in machine coordinates.
struct ProbeBox {
  std::array<double, 3> min_mm{0, 0, 0};
  std::array<double, 3> max_mm{0, 0, 0};

  friend bool operator==(const ProbeBox&, const ProbeBox&) = default;
};
struct ProbeConfig {
  bool touch_stock = true;      // the [stock] box is one of them, when there is one
  std::vector<ProbeBox> boxes;  // more solids

  friend bool operator==(const ProbeConfig&, const ProbeConfig&) = default;
};

struct MachineConfig {
  std::string name = "built-in 3-axis mill";

  // [motion]
  double period_s = 0.001;         // interpolation period τ
  double max_feed_mm_min = 10000;  // Vmax for feed moves
  double rapid_mm_min = 15000;     // G0 rate
  double max_accel_mm_s2 = 2000;   // Amax, tangential and normal
  double max_jerk_mm_s3 = 0;       // 0: no jerk stage; else T2 = ⌈2·Amax/(Jmax·τ)⌉ cycles
  double contour_tolerance_mm = 0.01;  // corner rounding of the post-interpolation filter
  // Consecutive G0/G1 pieces whose vertices lie within this of one straight line run as that
  // line (planner/line_merge.hpp); 0: off. ≤ 1 µm (spec 01 P1).
  double merge_tolerance_mm = 0.0005;
  // G1 chords within this of one line, arc or helix run as that curve (planner/path_smoother.hpp;
  // G64 Q overrides it per program); 0: off. Joints turning by more than smooth_corner_deg
  // between chords longer than the tolerance stay corners.
  double smooth_tolerance_mm = 0;
  double smooth_corner_deg = 30;
  double post_filter_s = 0;                // per-axis post-interpolation moving average; 0: off
  std::uint32_t lookahead_blocks = 10000;  // capacity of the execution-data buffer
  double max_override_pct = 200;           // highest feed override accepted
  // On arcs, bound the resultant of tangential and normal acceleration by Amax (true), or each
  // of them separately (false, the seed's way: the resultant may reach √2·Amax).
  bool bound_resultant_accel = false;
  AccDecKind accdec = AccDecKind::kAcceleration;  // look-ahead acc/dec type
  std::array<double, kMaxAxes> start_position{};  // position at program start ([axes.x] start_mm)

  // [axes.x] ...
  std::array<AxisConfig, kMaxAxes> axes{};

  // [interpreter]
  std::uint64_t max_loop_iterations = 1000000;  // runaway-loop guard for while/do/repeat
  std::uint32_t max_call_depth = 64;            // O-word call nesting
  // The length unit of the offset parameters as programs read and write them (#5161…,
  // #5181…, #5211…, #5221…): LinuxCNC keeps them in the machine's units ([TRAJ]LINEAR_UNITS),
  // whatever G20/G21 is active. cncore stores mm; true: programs see them in inches.
  bool parameters_inch = false;
  // Runaway guard for the whole program: loop passes, subroutine calls and M98 repeats summed.
  std::uint64_t max_total_iterations = 10000000;

  // [tables] (table-format operation, spec 02)
  TableCancelMode table_cancel_mode = TableCancelMode::kClear;
  // A table that would exceed an axis limit: false → refused; true → the reference is slowed
  // by one constant factor so that it fits.
  bool table_slow_to_fit = false;
  // [tables.parameters], [tables.variables], [tables.signals]: values of P<n>, #<n> and R<n>
  // for indirect SFT amounts (the command line's --param/--var/--signal override them).
  std::map<int, double> table_parameters, table_variables, table_signals;

  // [direction_correction] (spec 03)
  DirectionCorrectionConfig direction_correction;

  // [stock], [[tools]], [cutting] (cutting simulation): active when stock.enabled
  CuttingConfig cutting;

  // [adaptive], [adaptive.plant] (spec 04): adaptive feed control on spindle load and its plant
  // model (used as load source when its depth profile is not empty).
  feed::AdaptiveSettings adaptive;
  feed::PlantSettings adaptive_plant;

  // [servo] (cncore serve)
  ServoConfig servo;

  // [probe] (G38.2–G38.5)
  ProbeConfig probe;

  friend bool operator==(const MachineConfig&, const MachineConfig&) = default;

  std::size_t axis_count() const {
    std::size_t n = 0;
    for (const auto& a : axes) n += a.enabled ? 1 : 0;
    return n;
  }
};

// The built-in default: 3-axis mill, X −300…300, Y −200…200, Z −200…100 mm, feed 10 000 mm/min,
// rapid 15 000 mm/min, acceleration 2 000 mm/s², period 1 ms, contour tolerance 0.01 mm.
MachineConfig default_machine_config();

// Reads a TOML file. Keys left out keep the built-in default. Unknown keys and out-of-range
// values throw InputError naming the key (FILE:LINE:COL of the offending key).
MachineConfig load_machine_config(const std::string& path);
// The configuration in `path`, or the built-in default when `path` is empty (the --machine
// option of every command and tool).
MachineConfig machine_config_or_default(const std::string& path);
MachineConfig parse_machine_config(std::string_view toml_text, const std::string& source_name);

// The configuration as TOML with a comment on every key (what `cncore machine` prints); parsing
// this text gives back the same configuration.
std::string machine_config_to_toml(const MachineConfig& config);

}  // namespace cncore
