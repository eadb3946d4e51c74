// Execution data (spec 01, stage 1–2): one entry of the execution-data buffer per block, with
// its shape, path length, feed and passing speeds, and the passing speed at the joint between
// two motion segments. Speeds are in mm per interpolation cycle ("pc"), accelerations in mm per
// cycle² ("pc2"), path positions in mm.
//
// Path length: XYZ length for moves with an XYZ component (rotary axes follow linearly);
// rotary-only moves use their length in degrees as the path length (1° counts as 1 mm, the feed
// is then in degrees per minute).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "core/geometry.hpp"

namespace cncore::planner {

// Machine limits in per-cycle units, derived once from the MachineConfig.
struct Limits {
  double period_s = 0.001;
  std::uint32_t t_cycles = 1;     // T: first moving average, ceil(Vmax / (Amax·τ))
  std::uint32_t t2_cycles = 1;    // T2: second stage, ceil(2·Amax / (Jmax·τ)); 1 = none
  std::uint32_t post_cycles = 0;  // Tp: post-interpolation moving average; 0 or 1 = off
  double vmax_pc = 0;             // max feed
  double rapid_pc = 0;            // rapid rate, at most amax·T (the filter's ramp bound)
  double amax_pc2 = 0;
  double contour_tolerance_mm = 0.01;
  bool bound_resultant = false;  // arcs: bound √(a_t² + a_n²) by Amax instead of each
  std::array<bool, kMaxAxes> axis_on{};
  std::array<double, kMaxAxes> axis_vmax_pc{};   // ≤ 0: no limit
  std::array<double, kMaxAxes> axis_amax_pc2{};  // ≤ 0: no limit

  // M: span of the acc/dec filter in cycles (T + T2 − 1).
  std::uint32_t span_cycles() const { return t_cycles + t2_cycles - 1; }
  bool post_filter() const { return post_cycles > 1; }
};
Limits make_limits(const MachineConfig& machine, bool bound_resultant);

enum class ItemKind : std::uint8_t { kMotion, kDwell, kAux };

struct Segment {
  ItemKind kind = ItemKind::kMotion;
  bool arc = false;
  bool rapid = false;
  std::uint32_t line = 0;
  AxisVec start, end;  // events: both are the position where they happen
  double length_mm = 0;
  double s0_mm = 0;  // path position of the start (global, along the commanded path)

  // Arc / helix: H(φ) = center + r(φ)(cos φ·e1 + sin φ·e2) + rise·(φ/Φ)·n, r linear in φ.
  // A line merged from pieces (planner/line_merge.hpp) keeps its first and last pieces'
  // directions in e1 and e2 (zero: not merged, or an arc: see first_piece_dir()), whose corners
  // with the segments before and after joint_speed_pc() keeps too. (In the arc's fields, unused
  // on a line: a Segment of 6 cache lines instead of 5¼ cost 2 % of the cycle rate.)
  Vec3 center, e1, e2, n;
  double r0 = 0, r1 = 0, sweep_rad = 0, rise_mm = 0;
  double rho_mm = 0;  // radius of curvature (r² + p²)/r, p = rise/Φ

  double feed_pc = 0;  // F at 100 % override (rapids: the rapid rate)
  double vb_pc = 0;    // shape passing speed Vb
  double tol_mm = 0;   // contour tolerance for the post filter at its end
  PathMode mode = PathMode::kBlend;
  // Direction correction (spec 03), from the Block: C (already in feed_pc; reported in the
  // samples) and whether the operator's override is ignored on this segment.
  double correction = std::numeric_limits<double>::quiet_NaN();
  bool override_fixed = false;

  // Events
  bool barrier = false;  // the motion must stop and settle before the event (dwell, M0, G9 …)
  std::uint32_t dwell_cycles = 0;
  char aux_letter = 0;
  double aux_value = 0;
  double aux_p = 0;   // Block::aux_p
  bool done = false;  // event handled (set by the interpolator)

  double end_mm() const { return s0_mm + length_mm; }
  Vec3 first_piece_dir() const { return arc ? Vec3{} : e1; }
  Vec3 last_piece_dir() const { return arc ? Vec3{} : e2; }
  // Point at path distance u from the start (clamped to [0, L]); u ≥ L gives `end` exactly.
  AxisVec point_at(double u_mm) const;
  // Direction per path mm of every axis at the start / end (axis displacement per path mm).
  AxisVec start_direction() const { return direction_at(0); }
  AxisVec end_direction() const { return direction_at(sweep_rad); }

 private:
  AxisVec direction_at(double phi) const;
};

// Inline: the motion cycle calls it once per cycle, and a call returns the 48-byte point
// through memory (the caller's reload of it stalled on store forwarding).
inline AxisVec Segment::point_at(double u_mm) const {
  if (u_mm >= length_mm) return end;
  if (u_mm <= 0) return start;
  const double f = u_mm / length_mm;
  const AxisVec p = start + f * (end - start);
  if (!arc) return p;
  const double phi = f * sweep_rad;
  const double r = r0 + (r1 - r0) * f;
  const Vec3 q = center + (r * std::cos(phi)) * e1 + (r * std::sin(phi)) * e2 + (rise_mm * f) * n;
  // Built whole rather than by overwriting x, y, z of p: the caller copies the point in 16-byte
  // pairs, and a pair loaded over two separate 8-byte stores (z, a) cannot be forwarded.
  return AxisVec{{q.x, q.y, q.z, p[kA], p[kB], p[kC]}};
}

// Builds a motion segment (kRapid, kLine, kArc) with its length and Vb. Zero-length moves give
// length 0 (the caller drops them).
Segment make_motion_segment(const Block& block, const Limits& limits);

// Passing speed Vg at the joint from a to b (both motion segments): corner limit
// Amax·τ/(2 sin θ/2) = Amax·τ/|S − E| from the unit tangents, per-axis corner limits
// a_i·τ/|S_i − E_i|, min with both Vb's and, with the post filter, the contour-tolerance limit.
// slow_corner_stops: the moving-average rule that turns corners much slower than the speed
// around them into stops (see segment.cpp); the acceleration-limited type passes false.
double joint_speed_pc(const Segment& a, const Segment& b, const Limits& limits,
                      bool slow_corner_stops = true);
// The same, also giving the directions it computed at the joint (a's end, b's start), for a
// caller that needs them too (the acceleration type's joint zones).
double joint_speed_pc(const Segment& a, const Segment& b, const Limits& limits,
                      bool slow_corner_stops, AxisVec& a_end, AxisVec& b_start);

// Corner limit alone for a turn from direction e to direction s within one cycle; `curvature`
// (1/mm): the arcs' own turning next to the corner (0 between lines).
double turn_speed_pc(const AxisVec& e, const AxisVec& s, const Limits& limits,
                     double curvature = 0);

// Contour error of a corner of angle θ passed at speed ≤ v (mm/cycle) for Tp cycles on both
// sides, through a Tp-cycle moving average: e ≤ v·(Tp + 1)·sin θ / 8.
double corner_rounding_mm(double v_pc, double sin_theta, std::uint32_t tp_cycles);

}  // namespace cncore::planner
