// Independent trajectory checker for spec 01 (P1–P4, and P5 through P2/P3 under override steps).
// Everything is measured by finite differences of the output positions against the programmed
// geometry (Blocks); nothing comes from the planner's own variables.
//
// Measures (τ = period, P[k] the k-th sample, chords d[k] = P[k] − P[k−1] over X Y Z):
// - Progress along the path: every sample is projected onto the programmed path, walking
//   forward (never backward) over the segments, so the cost is O(samples + segments).
//   s[k] = XYZ path length from the start to the projection; dist[k] = distance (all axes).
// - Path speed v[k] of cycle k−1→k: (s[k] − s[k−1])/τ when both samples lie on the path
//   (within 1e-6 mm); otherwise the chord |d[k]|/τ (e.g. with the post-interpolation filter).
//   The path length is used on the path because a chord that straddles a corner is shorter
//   than the distance travelled, which would fake a speed dip at every corner.
// - Tangential acceleration at sample k: (v[k+1] − v[k])/τ.
// - Normal acceleration (direction change) at sample k, from the chords d1 = d[k], d2 = d[k+1]:
//   |d2 − d1|² = (|d2| − |d1|)² + 4|d1||d2| sin²(θ/2), so the normal part is
//   a_n = 2·√(|d1||d2|)·sin(θ/2)/τ² (= v²/R on an arc; at a corner passed at V within one cycle
//   it is 2V·sin(θ/2)/τ, so a_n ≤ Amax is exactly the spec's "direction change ≤ Amax·τ").
// - Resultant acceleration |d2 − d1|/τ² (reported; checked only if max_resultant_accel_mm_s2).
// - Per-axis speed |ΔP_i|/τ and acceleration |Δ²P_i|/τ² on every axis (A B C in degrees).
// - Jerk: tangential (a_t[k+1] − a_t[k])/τ is checked against max_jerk_mm_s3; the resultant
//   third difference |Δ³P|/τ³ is only reported (sharp corners make it unbounded by design).
//
// Rules (each limit gets ×(1 + margin) plus the resolution slack, see
// Limits::position_resolution_mm; a CSV with 6 decimals has q = 5e-7 mm, so its end point is
// checked to 1e-9 + 1.5e-6 mm — check in-memory samples for the strict 1e-9):
// - P1: dist[k] ≤ path_tolerance_mm for every sample.
// - P2 speed: v[k] ≤ limit at sample k, where sample k lies in segment S:
//     limit = min(Vkind, √(R·Amax) on arcs, F(S)·f[k]), Vkind = max feed or rapid rate,
//     F = programmed feed (rapid rate for G0; override applies to G0 unless configured off,
//     and never lets G0 exceed the rapid rate), and f[k] = override·correction factor.
//   Override steps: f[k] is the LARGEST factor among the samples with t ≥ t[k] − ramp
//   (Limits::ramp_s(), default max(Vfeed, Vrapid)/Amax + 2τ (+ 2·Amax/Jmax, + post filter)). So an
//   override increase raises the limit at once, and after an override DECREASE the old, higher
//   limit stays in force for one full acc/dec ramp. Feed changes between blocks get no such
//   allowance: the look-ahead knows them in advance, so the tool must already be at or below the
//   new block's feed when it enters that block (the limit of the segment where sample k lies).
// - P2 joints: the cycle whose end sample reaches or passes a joint (first sample at or beyond
//   it) has v ≤ Vg = min(Vb[a], Amax·τ/(2 sin(θ/2)), Vb[b]), Vb = min(Vkind, √(R·Amax)).
// - P2 axes: per-axis speed ≤ axis limit.
// - P3: |a_t| ≤ Amax, a_n ≤ Amax, per-axis acceleration ≤ axis limit; tangential jerk ≤ Jmax if
//   set; resultant ≤ max_resultant_accel_mm_s2 if set. Per-axis acceleration is checked at every
//   sample, corners included: a corner passed at Vg (direction change Amax·τ) in the same cycle as
//   a tangential speed change can exceed an axis limit equal to Amax, and that is reported.
// - P4: the last sample is within end_tolerance_mm of the programmed end and its arriving speed
//   is ≤ Amax·τ (one cycle of deceleration to rest); at every intermediate stop point (exact stop,
//   dwell, waiting M-code) some sample lands within stop_tolerance_mm of it with arriving speed
//   ≤ Amax·τ (a cycle that jumps over a stop point is a violation), and the tool stays there for
//   at least the dwell time (− τ).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/block.hpp"
#include "limits.hpp"
#include "path_geometry.hpp"
#include "trajectory.hpp"

namespace cncore::testing {

enum class Property : std::uint8_t {
  kPath,             // P1
  kSpeed,            // P2 path speed
  kJointSpeed,       // P2 at block joints
  kAxisSpeed,        // P2 per axis
  kTangentialAccel,  // P3
  kNormalAccel,      // P3 (arcs and direction change at corners)
  kAxisAccel,        // P3 per axis
  kResultantAccel,   // P3 (optional)
  kJerk,             // P3 (optional, tangential)
  kEndPoint,         // P4 end position
  kEndSpeed,         // P4 speed at the end / at stop points
  kStopPoint,        // P4 a stop point was passed without stopping, or the dwell was short
  kCount
};
const char* property_name(Property p);

struct Violation {
  Property property = Property::kPath;
  std::size_t index = 0;  // sample index
  double t_s = 0;
  std::uint32_t line = 0;  // source line (trajectory's line column, else the segment's)
  double value = 0;        // measured
  double limit = 0;        // allowed (without the margin)
  int axis = -1;           // for per-axis properties
  std::string to_string() const;
};

struct JointSpeed {
  std::size_t segment = 0;  // joint at the end of this segment
  std::uint32_t line = 0;   // line of the block after the joint
  double angle_deg = 0;
  double vg_mm_s = 0;      // allowed passing speed
  double speed_mm_s = -1;  // measured (−1: never reached)
  bool stop = false;
};

struct CheckReport {
  std::vector<Violation> violations;  // at most kMaxStoredPerProperty of each property
  std::array<std::size_t, static_cast<std::size_t>(Property::kCount)> counts{};
  static constexpr std::size_t kMaxStoredPerProperty = 50;

  std::size_t samples = 0;
  double duration_s = 0;
  double path_length_mm = 0;  // programmed
  double max_path_error_mm = 0;
  double max_speed_mm_s = 0;
  double max_speed_ratio = 0;  // max of speed / P2 limit
  double max_tangential_accel_mm_s2 = 0;
  double max_normal_accel_mm_s2 = 0;
  double max_resultant_accel_mm_s2 = 0;
  double max_tangential_jerk_mm_s3 = 0;
  double max_resultant_jerk_mm_s3 = 0;
  double max_direction_change_deg = 0;  // largest angle between consecutive chords (≥ 1 µm)
  std::array<double, kMaxAxes> max_axis_speed_mm_s{};
  std::array<double, kMaxAxes> max_axis_accel_mm_s2{};
  double end_error_mm = 0;
  double end_speed_mm_s = 0;
  std::vector<JointSpeed> joints;
  std::vector<double> speed_mm_s;  // v[k] per sample (v[0] = 0), for plots and extra asserts

  bool ok() const { return violations.empty(); }
  std::size_t count(Property p) const { return counts[static_cast<std::size_t>(p)]; }
  // A few lines: maxima and the counts and first violations of each property.
  std::string summary() const;
};

CheckReport check_trajectory(const Trajectory& tr, const std::vector<Block>& blocks,
                             const Limits& limits);
CheckReport check_trajectory(const Trajectory& tr, const Path& path, const Limits& limits);

}  // namespace cncore::testing
