// One line, circular arc or helix through the first and last of a run of points, accepted only
// when the polyline through all the points and the curve stay within a tolerance of each other
// (both ways: every point of either lies within tol of the other). The geometry of path
// smoothing (planner/path_smoother.hpp) and of the G5 splines (interpreter/spline.hpp); no
// blocks, no G-code.
//
// The test, for the points p0 … pn and a curve C through p0 and pn: each vertex vi has a curve
// parameter φi (its angle about the centre, or its projection on a line), strictly increasing,
// and the point C(φi) at distance ei = |vi − C(φi)|. Between two vertices the curve lies within
// the sagitta si = R·(1 − cos(Δφ/2)) of its own chord C(φi)C(φi+1) (0 for a line), and that chord
// within max(ei, ei+1) of the programmed chord vi vi+1 (both ends are, and the distance of two
// segments' corresponding points is linear along them). So
//
//     si + max(ei, ei+1) ≤ tol   for every chord
//
// bounds the distance of every curve point to the polyline and of every polyline point to the
// curve (a chord of a circle lies inside it, within si of the arc).
#pragma once

#include <cstdint>
#include <span>

#include "core/geometry.hpp"

namespace cncore::geometry {

struct CurveFit {
  enum class Kind : std::uint8_t { kLine, kArc };
  Kind kind = Kind::kLine;
  // kArc: the centre in the plane of p0 (normal to `normal`), the unit normal about which the
  // motion turns counter-clockwise, the radius and the sweep (0, max_sweep]; the rise along the
  // normal (a helix) is (pn − p0)·normal.
  Vec3 center, normal{0, 0, 1};
  double radius_mm = 0;
  double sweep_rad = 0;

  // The unit tangents at p0 and pn of the curve fitted through them.
  void end_tangents(const Vec3& p0, const Vec3& pn, Vec3& t0, Vec3& tn) const;
};

struct CurveFitLimits {
  double tolerance_mm = 0.01;
  double max_sweep_rad = 3.14159265358979;  // an arc turns by at most this
  double max_radius_mm = 1e4;               // flatter than this: a line or nothing
};

// An arc in the plane of p0, the middle point and pn if one fits, else a line through p0 and
// pn, else a helix about the X, Y or Z axis through the same three points projected
// along it. p.size() ≥ 3. O(p.size()) per candidate, stopping at the first vertex that fails.
bool fit_curve(std::span<const Vec3> p, const CurveFitLimits& limits, CurveFit& out);

// The arc through p0 and pn that leaves p0 along the unit tangent t0 (a line when pn lies along
// t0), if it fits: the curve after another one without a kink at their joint.
bool fit_tangent_curve(std::span<const Vec3> p, const Vec3& t0, const CurveFitLimits& limits,
                       CurveFit& out);

}  // namespace cncore::geometry
