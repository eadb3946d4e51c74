// Splines of the XY plane (G5 cubic, G5.1 quadratic, G5.2/G5.3 NURBS) and their conversion into
// tangent-continuous circular arcs within a tolerance, so that the planner runs them as curves
// with their curvature (speed √(R·Amax)) instead of chords with corners.
//
// Evaluation. A Bézier curve of degree d with control points P0 … Pd (G5: d = 3, G5.1: d = 2):
//   C(t) = Σ B_i,d(t)·Pi,  B_i,d(t) = (d choose i)·t^i·(1 − t)^(d−i),  t ∈ [0, 1],
//   C'(t) = d·Σ B_i,d−1(t)·(P(i+1) − Pi).
// A NURBS of order k (degree p = k − 1) with control points Pi, weights wi and the clamped
// uniform knot vector of LinuxCNC (k zeros, 1 … n − k, k times n − k + 1, divided by n − k + 1):
//   C(u) = A(u) / w(u),  A = Σ N_i,p(u)·wi·Pi,  w = Σ N_i,p(u)·wi,  C' = (A' − w'·C) / w,
// with the basis N_i,p by the Cox–de Boor recursion and N'_i,p = p·(N_i,p−1 / (u(i+p) − ui) −
// N_i+1,p−1 / (u(i+p+1) − u(i+1))).
//
// Arcs (biarcs). For a piece [ta, tb] of the curve with end points A, B and unit tangents Ta, Tb,
// the joints J of every pair of tangent-continuous arcs from (A, Ta) to (B, Tb) lie on one circle
// through A and B: the turn from the chord AJ to the chord JB is half the turn from Ta to Tb.
// Taking J where that circle crosses the curve (a root of sin(turn(AJ, JB) − turn(Ta, Tb)/2) in
// t), both arcs run between points of the curve, so each is tested against the curve's own
// samples with geometry::fit_tangent_curve (every point of the arc within the tolerance of the
// sampled curve and back). A piece whose biarc does not fit is halved; after kMaxDepth halvings
// (or where the curve is straight) it goes out as a line.
#pragma once

#include <cstdint>
#include <vector>

#include "core/geometry.hpp"

namespace cncore::interp {

// A curve of the XY plane at constant Z, parameter t ∈ [0, 1].
class PlaneSpline {
 public:
  // A Bézier curve through its control points (3 for G5.1, 4 for G5).
  static PlaneSpline bezier(const std::vector<Vec3>& control);
  // A NURBS of `order` (2 ≤ order ≤ control.size()) with positive weights.
  static PlaneSpline nurbs(const std::vector<Vec3>& control, const std::vector<double>& weights,
                           int order);

  Vec3 point(double t) const;
  Vec3 derivative(double t) const;
  // The parameters where the curve may lose smoothness (NURBS knots), 0 and 1 included.
  std::vector<double> breaks() const;

 private:
  void eval(double t, Vec3& p, Vec3& d) const;
  void eval_nurbs(double t, Vec3& p, Vec3& d) const;

  std::vector<Vec3> ctrl_;
  std::vector<double> weights_;  // empty: a Bézier curve
  std::vector<double> knots_;
  int order_ = 0;
};

// One arc or line of the conversion, starting where the one before it ends.
struct SplinePiece {
  bool arc = false;
  Vec3 end;
  Vec3 center;           // arc: in the plane of its start
  Vec3 normal{0, 0, 1};  // arc: the motion turns counter-clockwise about it
};

struct SplineFit {
  std::vector<SplinePiece> pieces;
  Vec3 lo, hi;  // bounds of the curve's sampled points (travel check)
  double length_mm = 0;
  std::uint32_t lines = 0;  // pieces where no arc fitted
};

// Arcs within `tolerance_mm` of `curve` from curve.point(0) to curve.point(1), leaving along
// `start_dir` (a unit vector; zero: the curve's own start tangent).
SplineFit fit_arcs(const PlaneSpline& curve, double tolerance_mm, Vec3 start_dir = {});

}  // namespace cncore::interp
