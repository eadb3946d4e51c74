#include "jerk_bound.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>

namespace cncore::bound {
namespace {

// E on one piece, x from its start: rising branch R(x) = √(u0² + 2ax) up to the meeting point
// x_rf (R = F), falling branch F(x) = √(u1² + 2d(L − x)) after it, both cut by the cap.
struct PieceShape {
  double length, cap, u0, u1, a, d, x_rf;
  explicit PieceShape(const EnvelopePiece& p)
      : length(p.length_mm),
        cap(p.cap_mm_s),
        u0(p.u0_mm_s),
        u1(p.u1_mm_s),
        a(p.accel_mm_s2),
        d(p.decel_mm_s2),
        x_rf(std::clamp((u1 * u1 - u0 * u0 + 2 * d * length) / (2 * (a + d)), 0.0, length)) {}
  double rise(double x) const { return std::sqrt(u0 * u0 + 2 * a * std::max(0.0, x)); }
  double fall(double x) const { return std::sqrt(u1 * u1 + 2 * d * std::max(0.0, length - x)); }
  double value(double x) const { return std::min(cap, x <= x_rf ? rise(x) : fall(x)); }
  // The highest value and where it is (the middle of a cruise at the cap).
  std::pair<double, double> peak() const {
    const double top = std::min(cap, rise(x_rf));
    if (top < cap) return {x_rf, top};
    const double x_rc = std::clamp((cap * cap - u0 * u0) / (2 * a), 0.0, length);
    const double x_fc = std::clamp(length - (cap * cap - u1 * u1) / (2 * d), 0.0, length);
    return {(x_rc + std::max(x_rc, x_fc)) / 2, cap};
  }
  // ∫ dx/E over [p, q] ⊂ [0, length]: dx/√(c + 2ax) integrates to (√(c + 2aq) − √(c + 2ap))/a.
  double time(double p, double q) const {
    double t = 0;
    if (p < x_rf) {  // rising part, the cap from x_rc on
      const double e = std::min(q, x_rf);
      const double x_rc = (cap * cap - u0 * u0) / (2 * a);
      const double m = std::clamp(x_rc, p, e);
      if (m > p) t += (rise(m) - rise(p)) / a;
      if (e > m) t += (e - m) / cap;
    }
    if (q > x_rf) {  // falling part, the cap up to x_fc
      const double b = std::max(p, x_rf);
      const double x_fc = length - (cap * cap - u1 * u1) / (2 * d);
      const double m = std::clamp(x_fc, b, q);
      if (m > b) t += (m - b) / cap;
      if (q > m) t += (fall(m) - fall(q)) / d;
    }
    return t;
  }
};

class Envelope {
 public:
  explicit Envelope(const std::vector<EnvelopePiece>& pieces) {
    shapes_.reserve(pieces.size());
    start_.reserve(pieces.size() + 1);
    cum_.reserve(pieces.size() + 1);
    double s = 0, t = 0;
    for (const auto& p : pieces) {
      shapes_.emplace_back(p);
      start_.push_back(s);
      cum_.push_back(t);
      s += p.length_mm;
      t += shapes_.back().time(0, p.length_mm);
    }
    start_.push_back(s);
    cum_.push_back(t);
  }
  std::size_t size() const { return shapes_.size(); }
  const PieceShape& shape(std::size_t k) const { return shapes_[k]; }
  double start(std::size_t k) const { return start_[k]; }
  double length() const { return start_.back(); }
  double value(double s) const {
    const std::size_t k = find(s);
    return shapes_[k].value(s - start_[k]);
  }
  // ∫ds/E from the path's start to s.
  double cum_time(double s) const {
    const std::size_t k = find(s);
    return cum_[k] + shapes_[k].time(0, std::min(s - start_[k], shapes_[k].length));
  }

 private:
  std::size_t find(double s) const {
    const auto it = std::upper_bound(start_.begin(), start_.end() - 1, s);
    return it == start_.begin() ? 0 : static_cast<std::size_t>(it - start_.begin()) - 1;
  }
  std::vector<PieceShape> shapes_;
  std::vector<double> start_, cum_;
};

// The speed bound after the valley: with a(t_j) = α and jerk ≤ J, a(t_j + t) ≤ min(A, α + J·t),
// so v(t_j + t) ≤ E_j + Φ(t) with Φ(t) = ∫₀ᵗ min(A, α + J·u) du (α + J·u reaches A at
// t_A = (A − α)/J), and the distance covered ≤ E_j·t + Ψ(t), Ψ(t) = ∫₀ᵗ Φ.
struct Rise {
  double alpha, a, j;
  double t_sat() const { return (a - alpha) / j; }
  double phi(double t) const {
    const double ts = t_sat();
    if (t <= ts) return alpha * t + j * t * t / 2;
    return alpha * ts + j * ts * ts / 2 + a * (t - ts);
  }
  double psi(double t) const {
    const double ts = t_sat();
    if (t <= ts) return alpha * t * t / 2 + j * t * t * t / 6;
    const double r = t - ts;
    return alpha * ts * ts / 2 + j * ts * ts * ts / 6 + phi(ts) * r + a * r * r / 2;
  }
  // Whether a speed ≤ low at t_j leaves a speed ≥ 0 later: the lowest E_j + Φ is at
  // t = −α/J, E_j − α²/(2J); below 0 no trajectory has this α.
  bool feasible(double low) const { return alpha >= 0 || low - alpha * alpha / (2 * j) >= 0; }
};

// Time steps per side: kFineSteps of A/(8J), then kSteps − kFineSteps growing by kGrowth each
// (about 25·A/J in all): the speed bound lags E by up to A/(2J) until E levels off. (Longer
// steps lose where E_j + Φ crosses E inside a step: min(∫w, h·max E) is above ∫min(w, E).)
constexpr int kFineSteps = 24;
constexpr int kSteps = 40;
constexpr double kGrowth = 1.25;
constexpr int kAlphaCells = 32;  // the acceleration at the valley, [−A, A] in equal cells

struct Window {
  double p0, p1, valley, low;  // ends, valley position and E there
};

class WindowBound {
 public:
  WindowBound(const Envelope& env, double amax, double jerk)
      : env_(env), a_(amax), j_(jerk), h_(amax / jerk / 8) {}

  // Lower bound of the time in window w (≥ ∫_W ds/E).
  double time(const Window& w) const {
    const double t_acc = env_.cum_time(w.p1) - env_.cum_time(w.p0);
    if (w.low <= 0) {
      // At rest at the valley: a = 0 there.
      return std::max(t_acc, side(w, 0, +1) + side(w, 0, -1));
    }
    // The acceleration α at the valley is unknown: for α in [α_k, α_k+1] the time after the
    // valley is at least side(α_k+1) (more acceleration, faster), the time before it at least
    // side(α_k) (backwards in time the acceleration is −α: more α, slower before).
    double best = std::numeric_limits<double>::infinity();
    double before = side(w, -a_, -1);
    for (int k = 0; k < kAlphaCells && best > t_acc; ++k) {
      const double hi = -a_ + 2 * a_ * (k + 1) / kAlphaCells;
      const double after = side(w, hi, +1);
      best = std::min(best, before + after);
      before = side(w, hi, -1);
    }
    return std::max(t_acc, best);
  }

 private:
  // Lower bound of the time from the valley to the window's end in direction dir (+1: to p1,
  // −1: from p0, backwards in time, where the acceleration is −α), with the speed
  // ≤ min(E, E_j + Φ(t)), t the time from the valley. Infinite where no speed ≥ 0 fits.
  double side(const Window& w, double alpha, int dir) const {
    const Rise rise{dir > 0 ? alpha : -alpha, a_, j_};
    if (!rise.feasible(w.low)) return std::numeric_limits<double>::infinity();
    const double end = dir > 0 ? w.p1 : w.p0;
    double dist = dir * (end - w.valley);  // left to cover
    if (dist <= 0) return 0;
    // E rises away from the valley up to the window's end: its maximum over a stretch is at
    // the far end.
    double t = 0, s = w.valley, h = h_;
    for (int n = 0; n < kSteps; ++n) {
      if (n >= kFineSteps) {
        // Past the rise to A: where E_j + Φ has caught up with E, E alone bounds the rest.
        if (t >= rise.t_sat() && w.low + rise.phi(t) >= env_.value(s)) break;
        h *= kGrowth;
      }
      const double t1 = t + h;
      const double dw = w.low * h + rise.psi(t1) - rise.psi(t);  // ∫ (E_j + Φ) over the step
      const double reach = dir > 0 ? std::min(s + dw, end) : std::max(s - dw, end);
      const double emax = env_.value(reach);
      const double step = std::min(dw, h * emax);
      if (step >= dist) {
        const double vmax = std::min(w.low + std::max(rise.phi(t), rise.phi(t1)), emax);
        return t + dist / vmax;
      }
      s += dir * step;
      dist -= step;
      t = t1;
    }
    const double rest =
        dir > 0 ? env_.cum_time(end) - env_.cum_time(s) : env_.cum_time(s) - env_.cum_time(end);
    return t + std::max(0.0, rest);
  }
  const Envelope& env_;
  double a_, j_, h_;
};

// Cut the path at the local maxima of E: breakpoints u0, peak of piece 0, u1, peak of piece 1,
// … with E monotone between neighbours.
std::vector<Window> windows(const Envelope& env) {
  std::vector<Window> out;
  double start = 0, prev_v = 0, prev_s = 0;
  double valley_s = 0, valley_v = 0;
  bool rising = false;
  auto visit = [&](double s, double v) {
    if (!rising && v > prev_v) {
      rising = true;
      valley_s = prev_s;
      valley_v = prev_v;
    } else if (rising && v < prev_v) {
      out.push_back({start, prev_s, valley_s, valley_v});
      start = prev_s;
      rising = false;
    }
    prev_s = s;
    prev_v = v;
  };
  if (env.size() == 0) return out;
  prev_v = env.shape(0).u0;
  for (std::size_t k = 0; k < env.size(); ++k) {
    const PieceShape& p = env.shape(k);
    const auto [x, top] = p.peak();
    visit(env.start(k) + x, top);
    visit(env.start(k) + p.length, p.u1);
  }
  if (!rising) {
    valley_s = prev_s;
    valley_v = prev_v;
  }
  out.push_back({start, env.length(), valley_s, valley_v});
  return out;
}

}  // namespace

std::vector<PeakCap> peak_caps(const std::vector<EnvelopePiece>& pieces, double amax_mm_s2,
                               double jerk_mm_s3) {
  std::vector<PeakCap> caps;
  const Envelope env(pieces);
  if (env.size() == 0 || jerk_mm_s3 <= 0 || amax_mm_s2 <= 0) return caps;
  const std::vector<Window> ws = windows(env);
  const Rise fall{0, amax_mm_s2, jerk_mm_s3};  // Φ0: the speed lost u after a ≥ 0
  const double h = amax_mm_s2 / jerk_mm_s3 / 8;
  // Whether a speed v at the peak p with a ≥ 0 there (dir +1; a ≤ 0 and backwards: −1) keeps
  // v − Φ0(u) ≤ E(x_u) for the points x_u the slowest braking reaches by u, up to the valley.
  // Larger v only moves x_u on, where E is lower, and checks more points: feasibility is
  // monotone in v.
  auto feasible = [&](double p, double valley, double v, int dir) {
    double u = 0, d = 0;
    for (int n = 0; n < 6 * 8; ++n) {
      const double u1 = u + h;
      if (v - fall.phi(u1) < 0) return true;  // no longer sure to move on
      d += v * h - (fall.psi(u1) - fall.psi(u));
      const double x = dir > 0 ? std::min(p + d, valley) : std::max(p - d, valley);
      if (v > env.value(x) + fall.phi(u1)) return false;
      u = u1;
    }
    return true;
  };
  for (std::size_t i = 0; i + 1 < ws.size(); ++i) {
    const double p = ws[i].p1, top = env.value(p);
    double cap = 0;
    for (const int dir : {+1, -1}) {
      const double valley = dir > 0 ? ws[i + 1].valley : ws[i].valley;
      if (feasible(p, valley, top, dir)) {
        cap = top;
        break;
      }
      double lo = 0, hi = top;  // lo feasible, hi not: every v ≥ hi is not
      for (int it = 0; it < 40 && hi - lo > 1e-9 * top; ++it) {
        const double mid = (lo + hi) / 2;
        (feasible(p, valley, mid, dir) ? lo : hi) = mid;
      }
      cap = std::max(cap, hi);
    }
    if (cap < top * (1 - 1e-9)) caps.push_back({p, cap});
  }
  return caps;
}

double envelope_time_s(const std::vector<EnvelopePiece>& pieces) {
  const Envelope env(pieces);
  return env.size() == 0 ? 0.0 : env.cum_time(env.length());
}

double jerk_motion_time_s(const std::vector<EnvelopePiece>& pieces, double amax_mm_s2,
                          double jerk_mm_s3) {
  const Envelope env(pieces);
  if (env.size() == 0) return 0;
  if (jerk_mm_s3 <= 0 || amax_mm_s2 <= 0) return env.cum_time(env.length());
  const WindowBound wb(env, amax_mm_s2, jerk_mm_s3);
  double t = 0;
  for (const Window& w : windows(env)) t += wb.time(w);
  return t;
}

}  // namespace cncore::bound
