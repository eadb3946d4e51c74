#include "interpreter/spline.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <span>

#include "geometry/curve_fit.hpp"

namespace cncore::interp {
namespace {

constexpr int kMaxOrder = 16;
constexpr std::size_t kChords = 48;  // samples of the curve per arc, less one
constexpr int kJointScan = 16;       // parameter steps searched for the biarc joint
constexpr int kMaxDepth = 12;        // halvings of a piece before it goes out as a line
constexpr double kMaxRadiusMm = 1e6;
// The sampled polyline may leave the curve by this share of the tolerance (its sagitta); the
// arcs are fitted to the rest.
constexpr double kSagShare = 0.1;

// The signed turn about +Z from a to b (radians, (−π, π]).
double turn_z(Vec3 a, Vec3 b) {
  return std::atan2(cross(a, b).z, dot(a, b));
}

// Cox–de Boor: the basis functions of degree q nonzero at u in span s (u_s ≤ u < u_s+1),
// out[j] = N_(s−q+j),q(u).
void basis(std::span<const double> knots, std::size_t s, double u, int q, double* out) {
  std::array<double, kMaxOrder + 1> left{}, right{};
  out[0] = 1;
  for (int j = 1; j <= q; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    left[uj] = u - knots[s + 1 - uj];
    right[uj] = knots[s + uj] - u;
    double saved = 0;
    for (int r = 0; r < j; ++r) {
      const auto ur = static_cast<std::size_t>(r);
      const double tmp = out[r] / (right[ur + 1] + left[uj - ur]);
      out[r] = saved + right[ur + 1] * tmp;
      saved = left[uj - ur] * tmp;
    }
    out[j] = saved;
  }
}

}  // namespace

PlaneSpline PlaneSpline::bezier(const std::vector<Vec3>& control) {
  PlaneSpline s;
  s.ctrl_ = control;
  s.order_ = static_cast<int>(control.size());
  return s;
}

PlaneSpline PlaneSpline::nurbs(const std::vector<Vec3>& control, const std::vector<double>& weights,
                               int order) {
  PlaneSpline s;
  s.ctrl_ = control;
  s.weights_ = weights;
  s.order_ = std::clamp(order, 2, kMaxOrder);
  // LinuxCNC's clamped uniform knots: k zeros, 1 … n − k, k times n − k + 1, scaled to [0, 1].
  const auto n = static_cast<int>(control.size());
  const int k = s.order_;
  const double last = n - k + 1;
  for (int i = 0; i < n + k; ++i) {
    const int v = i < k ? 0 : (i >= n ? n - k + 1 : i - k + 1);
    s.knots_.push_back(v / last);
  }
  return s;
}

std::vector<double> PlaneSpline::breaks() const {
  if (weights_.empty()) return {0.0, 1.0};
  std::vector<double> b;
  for (double u : knots_) {
    if (b.empty() || u > b.back()) b.push_back(u);
  }
  return b;
}

Vec3 PlaneSpline::point(double t) const {
  Vec3 p, d;
  eval(t, p, d);
  return p;
}

Vec3 PlaneSpline::derivative(double t) const {
  Vec3 p, d;
  eval(t, p, d);
  return d;
}

void PlaneSpline::eval(double t, Vec3& p, Vec3& d) const {
  if (!weights_.empty()) {
    eval_nurbs(t, p, d);
    return;
  }
  // de Casteljau: reduce to the two points of degree d − 1; C = their blend, C' = d·(Q1 − Q0).
  std::array<Vec3, kMaxOrder> q{};
  const std::size_t n = ctrl_.size();
  std::copy(ctrl_.begin(), ctrl_.end(), q.begin());
  for (std::size_t level = n - 1; level > 1; --level) {
    for (std::size_t i = 0; i < level; ++i) q[i] = (1 - t) * q[i] + t * q[i + 1];
  }
  p = (1 - t) * q[0] + t * q[1];
  d = static_cast<double>(n - 1) * (q[1] - q[0]);
}

void PlaneSpline::eval_nurbs(double t, Vec3& p, Vec3& d) const {
  const int deg = order_ - 1;
  const std::size_t n = ctrl_.size();
  const auto udeg = static_cast<std::size_t>(deg);
  // The span: u_s ≤ t < u_s+1, the last nonempty one at t = 1.
  std::size_t s = udeg;
  while (s + 1 < n && knots_[s + 1] <= t) ++s;
  std::array<double, kMaxOrder + 1> nb{}, lower{};
  basis(knots_, s, t, deg, nb.data());
  basis(knots_, s, t, deg - 1, lower.data());
  Vec3 a, da;
  double w = 0, dw = 0;
  for (std::size_t j = 0; j <= udeg; ++j) {
    const std::size_t i = s - udeg + j;
    // N'_i,p from the degree p − 1 functions N_i,p−1 = lower[j − 1] and N_i+1,p−1 = lower[j].
    const double left = j > 0 ? lower[j - 1] / (knots_[i + udeg] - knots_[i]) : 0;
    const double right = j < udeg ? lower[j] / (knots_[i + udeg + 1] - knots_[i + 1]) : 0;
    const double dn = deg * (left - right);
    const double wi = weights_[i];
    a = a + (nb[j] * wi) * ctrl_[i];
    w += nb[j] * wi;
    da = da + (dn * wi) * ctrl_[i];
    dw += dn * wi;
  }
  p = (1 / w) * a;
  d = (1 / w) * (da - dw * p);
}

namespace {

// The unit tangent at t; where the derivative vanishes (a control point on the end point), the
// direction of a short chord there.
Vec3 unit_tangent(const PlaneSpline& c, double t) {
  const Vec3 d = c.derivative(t);
  if (norm(d) > 1e-12) return unit_or_zero(d);
  constexpr double kStep = 1e-6;
  return t < 0.5 ? unit_or_zero(c.point(t + kStep) - c.point(t))
                 : unit_or_zero(c.point(t) - c.point(t - kStep));
}

class ArcFitter {
 public:
  ArcFitter(const PlaneSpline& c, double tol, SplineFit& out) : c_(c), tol_(tol), out_(out) {
    pts_.reserve(kChords + 1);
  }

  // The piece [ta, tb] from the current end, leaving along tin_: a biarc, else halves, else a line.
  void piece(double ta, double tb, int depth) {
    const Vec3 a = c_.point(ta), b = c_.point(tb);
    const double mid = 0.5 * (ta + tb);
    if (norm(b - a) < 1e-9) {
      // A closed loop ends where it starts: its halves do not.
      if (depth < kMaxDepth && norm(c_.point(mid) - a) >= 1e-9) {
        piece(ta, mid, depth + 1);
        piece(mid, tb, depth + 1);
      }
      return;
    }
    if (biarc(ta, tb, a, b)) return;
    if (depth < kMaxDepth && !straight(ta, tb, a, b)) {
      piece(ta, mid, depth + 1);
      piece(mid, tb, depth + 1);
      return;
    }
    line(a, b);
  }

  Vec3 tin_;

 private:
  // sin of (the turn from AJ to JB less half the turn from tin_ to tb): zero on the joint circle.
  double joint_error(double t, Vec3 a, Vec3 b, double half) const {
    const Vec3 j = c_.point(t);
    return std::sin(turn_z(j - a, b - j) - half);
  }

  bool find_joint(double ta, double tb, Vec3 a, Vec3 b, double half, double& tj) const {
    double best = 0, best_err = 2, bracket_lo = -1, bracket_dist = 2;
    double prev_t = ta, prev_e = 0;
    for (int k = 1; k < kJointScan; ++k) {
      const double t = ta + (tb - ta) * k / kJointScan;
      const double e = joint_error(t, a, b, half);
      if (std::fabs(e) < best_err) {
        best_err = std::fabs(e);
        best = t;
      }
      if (k > 1 && (e < 0) != (prev_e < 0) &&
          std::fabs(0.5 * (prev_t + t) - 0.5 * (ta + tb)) < bracket_dist) {
        bracket_dist = std::fabs(0.5 * (prev_t + t) - 0.5 * (ta + tb));
        bracket_lo = prev_t;
      }
      prev_t = t;
      prev_e = e;
    }
    if (bracket_lo < 0) {
      tj = best;
      return best_err < 1e-9;
    }
    double lo = bracket_lo, hi = bracket_lo + (tb - ta) / kJointScan;
    const bool lo_neg = joint_error(lo, a, b, half) < 0;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      ((joint_error(mid, a, b, half) < 0) == lo_neg ? lo : hi) = mid;
    }
    tj = 0.5 * (lo + hi);
    return true;
  }

  // pts_ = the curve sampled over [t0, t1] (ends exact); returns the largest sagitta of its
  // chords against the curve (the distance of a chord's middle to the curve's).
  double sample(double t0, double t1, Vec3 p0, Vec3 p1) {
    pts_.clear();
    pts_.push_back(p0);
    double sag = 0;
    Vec3 prev = p0;
    for (std::size_t i = 1; i <= kChords; ++i) {
      const double t = t0 + (t1 - t0) * static_cast<double>(i) / kChords;
      const Vec3 p = i == kChords ? p1 : c_.point(t);
      const double tm = t0 + (t1 - t0) * (static_cast<double>(i) - 0.5) / kChords;
      sag = std::max(sag, norm(c_.point(tm) - 0.5 * (prev + p)));
      pts_.push_back(p);
      prev = p;
    }
    return sag;
  }

  bool fit_half(double t0, double t1, Vec3 p0, Vec3 p1, Vec3 dir, geometry::CurveFit& f) {
    const double sag = sample(t0, t1, p0, p1);
    if (sag > kSagShare * tol_) return false;
    const geometry::CurveFitLimits lim{tol_ - 2 * sag, std::numbers::pi, kMaxRadiusMm};
    return geometry::fit_tangent_curve(pts_, dir, lim, f);
  }

  bool biarc(double ta, double tb, Vec3 a, Vec3 b) {
    const double half = 0.5 * turn_z(tin_, unit_tangent(c_, tb));
    double tj = 0;
    if (!find_joint(ta, tb, a, b, half, tj)) return false;
    const Vec3 j = c_.point(tj);
    geometry::CurveFit f1, f2;
    if (!fit_half(ta, tj, a, j, tin_, f1)) return false;
    Vec3 t0, tj_dir, tb_dir;
    f1.end_tangents(a, j, t0, tj_dir);
    if (!fit_half(tj, tb, j, b, tj_dir, f2)) return false;
    f2.end_tangents(j, b, t0, tb_dir);
    emit(a, j, f1);
    emit(j, b, f2);
    tin_ = tb_dir;
    return true;
  }

  // Samples within the tolerance of the chord, which leaves within 1 mrad of tin_.
  bool straight(double ta, double tb, Vec3 a, Vec3 b) {
    const Vec3 ch = unit_or_zero(b - a);
    if (dot(ch, tin_) < std::cos(1e-3)) return false;
    sample(ta, tb, a, b);
    return std::ranges::all_of(pts_, [&](const Vec3& p) {
      const Vec3 v = p - a;
      return norm(v - dot(v, ch) * ch) <= 0.5 * tol_;
    });
  }

  void grow(Vec3 p) {
    out_.lo = {std::min(out_.lo.x, p.x), std::min(out_.lo.y, p.y), std::min(out_.lo.z, p.z)};
    out_.hi = {std::max(out_.hi.x, p.x), std::max(out_.hi.y, p.y), std::max(out_.hi.z, p.z)};
  }

  void emit(Vec3 a, Vec3 b, const geometry::CurveFit& f) {
    SplinePiece p;
    p.end = b;
    if (f.kind == geometry::CurveFit::Kind::kArc) {
      p.arc = true;
      p.center = f.center;
      p.normal = f.normal;
      out_.length_mm += f.radius_mm * f.sweep_rad;
    } else {
      out_.length_mm += norm(b - a);
    }
    for (const Vec3& q : pts_) grow(q);
    grow(b);
    out_.pieces.push_back(p);
  }

  void line(Vec3 a, Vec3 b) {
    SplinePiece p;
    p.end = b;
    out_.length_mm += norm(b - a);
    grow(a);
    grow(b);
    out_.pieces.push_back(p);
    ++out_.lines;
    tin_ = unit_or_zero(b - a);
  }

  const PlaneSpline& c_;
  double tol_;
  SplineFit& out_;
  std::vector<Vec3> pts_;
};

}  // namespace

SplineFit fit_arcs(const PlaneSpline& curve, double tolerance_mm, Vec3 start_dir) {
  SplineFit out;
  out.lo = out.hi = curve.point(0);
  ArcFitter fitter(curve, tolerance_mm, out);
  fitter.tin_ = dot(start_dir, start_dir) > 0 ? start_dir : unit_tangent(curve, 0);
  const std::vector<double> b = curve.breaks();
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    // A knot where the curve itself turns (order 2, a polyline): the next span leaves along its
    // own tangent, a corner as programmed.
    const Vec3 t = unit_tangent(curve, b[i]);
    if (i > 0 && dot(t, fitter.tin_) < std::cos(1e-6)) fitter.tin_ = t;
    fitter.piece(b[i], b[i + 1], 0);
  }
  return out;
}

}  // namespace cncore::interp
