// The programmed path as exact geometry, built from interpreted Blocks only (never from the
// motion kernel): straight segments and arcs/helices with their lengths, tangents, stop points
// and the exact distance from any point to them. Used by the trajectory checker (distance to
// the path, progress along it) and by the time-optimal bound (lengths, curvature, corners).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/block.hpp"
#include "core/geometry.hpp"

namespace cncore::testing {

struct PathSegment {
  bool arc = false;
  bool rapid = false;
  std::size_t block_index = 0;  // index in the Block vector it came from
  std::uint32_t line = 0;       // source line of the block
  AxisVec start, end;
  double feed_mm_min = 0;  // programmed feed (0 for rapids)
  double length_mm = 0;    // XYZ length (helix: √((r·Φ)² + rise²), r the mean radius)
  double s0_mm = 0;        // XYZ path length from the program start to this segment's start

  // Arc / helix: H(φ) = c + r(φ)(cos φ·e1 + sin φ·e2) + rise·(φ/Φ)·n, φ ∈ [0, Φ],
  // r(φ) = r0 + (r1 − r0)·φ/Φ (a start/end radius mismatch is spread linearly).
  Vec3 center, e1, e2, n;
  double r0 = 0, r1 = 0, sweep_rad = 0, rise_mm = 0;

  // The program stops at the end of this segment (exact stop, dwell, waiting M-code, end).
  bool stop_after = false;
  double dwell_after_s = 0;

  // Point at parameter u ∈ [0, 1] (all axes; axes other than the helix's move linearly).
  AxisVec point_at(double u) const;
  // Unit XYZ tangent at parameter u (zero vector for a segment without XYZ motion).
  Vec3 tangent_at(double u) const;
  // Radius of the arc (mean of start and end radii); 0 for lines.
  double radius_mm() const { return arc ? 0.5 * (r0 + r1) : 0; }

  // Nearest point to p with parameter in [u_min, 1]: returns u, writes the distance over all
  // axes (mm and degrees alike). Exact for lines; for arcs and helices the in-plane angle gives
  // the start and Newton's method on |p − H(φ)|² finishes it (every turn of a multi-turn helix
  // is a candidate).
  double project(const AxisVec& p, double u_min, double& distance_mm) const;
};

struct Path {
  std::vector<PathSegment> segments;
  double length_mm = 0;  // total XYZ length
  AxisVec start;         // where the motion starts
  AxisVec end;           // the programmed end point (last motion block's end)
  bool empty() const { return segments.empty(); }
};

// The segment of one motion block (kRapid, kLine, kArc); false when the block does not move
// (or is not a motion block). s0_mm and the stop flags are left for the caller.
bool make_segment(const Block& block, std::size_t block_index, PathSegment& out);

// Segments of every motion block with motion (zero-length blocks are dropped; their stop
// flags move to the previous segment). Dwell and waiting aux blocks mark a stop at the end of
// the previous segment; exact-stop blocks (G9, G61.1) at their own end; the last segment stops.
Path build_path(const std::vector<Block>& blocks);

// Angle θ (rad) between the end tangent of a and the start tangent of b; 0 when either has no
// XYZ motion.
double corner_angle_rad(const PathSegment& a, const PathSegment& b);

}  // namespace cncore::testing
