#include "runtime/line_motion.hpp"

#include <algorithm>
#include <cmath>

namespace cncore::runtime {

void LineMotion::start(const MachineConfig& machine, const AxisVec& from, const AxisVec& to,
                       double feed_mm_min) {
  from_ = from;
  target_ = to;
  double len2 = 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) len2 += (to[i] - from[i]) * (to[i] - from[i]);
  length_mm_ = std::sqrt(len2);
  s_mm_ = 0;
  v_mm_s_ = 0;
  period_s_ = machine.period_s;
  active_ = length_mm_ > 1e-9;
  if (!active_) return;
  vmax_mm_s_ = std::min(feed_mm_min, machine.max_feed_mm_min) / 60.0;
  accel_mm_s2_ = machine.max_accel_mm_s2;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    unit_[i] = (to[i] - from[i]) / length_mm_;
    const double share = std::abs(unit_[i]);
    const AxisConfig& a = machine.axes[i];
    if (share < 1e-12 || !a.enabled) continue;
    if (a.max_speed_mm_min > 0) vmax_mm_s_ = std::min(vmax_mm_s_, a.max_speed_mm_min / 60 / share);
    if (a.max_accel_mm_s2 > 0) accel_mm_s2_ = std::min(accel_mm_s2_, a.max_accel_mm_s2 / share);
  }
}

namespace {

// Distance covered, in whole cycles, by moving at v this cycle and braking by a·τ every cycle
// after: D(v) = τ·(v + (v − aτ) + (v − 2aτ) + … ), the terms while positive. With n = ⌊v/(aτ)⌋,
// D(v) = τ·((n + 1)·v − aτ·n(n + 1)/2). brake_speed() is its inverse: the highest speed from which
// `rem` is exactly enough. Following it, every cycle's speed drops by exactly a·τ
// (D(v) − v·τ = D(v − aτ)), and the move ends at rest on the target.
double brake_distance(double v, double a, double tau) {
  if (v <= 0) return 0;
  const double n = std::floor(v / (a * tau));
  return tau * ((n + 1) * v - a * tau * n * (n + 1) / 2);
}

double brake_speed(double rem, double a, double tau) {
  if (rem <= 0) return 0;
  const double unit = a * tau * tau;  // D(n·aτ) = unit·n(n + 1)/2
  double n = std::floor((-1 + std::sqrt(1 + 8 * rem / unit)) / 2);
  while (n > 0 && unit * n * (n + 1) / 2 > rem) n -= 1;  // rounding
  while (unit * (n + 1) * (n + 2) / 2 <= rem) n += 1;
  return (rem / tau + a * tau * n * (n + 1) / 2) / (n + 1);
}

}  // namespace

void LineMotion::stop() {
  if (!active_) return;
  // Brake from the next cycle on: what is left is D(v − aτ).
  const double v_next = std::max(v_mm_s_ - accel_mm_s2_ * period_s_, 0.0);
  length_mm_ = std::min(length_mm_, s_mm_ + brake_distance(v_next, accel_mm_s2_, period_s_));
  for (std::size_t i = 0; i < kMaxAxes; ++i) target_[i] = from_[i] + unit_[i] * length_mm_;
  if (length_mm_ - s_mm_ <= 1e-12) {
    active_ = false;
    v_mm_s_ = 0;
  }
}

bool LineMotion::step(AxisVec& position, double& speed_mm_s) {
  if (!active_) return false;
  const double rem = length_mm_ - s_mm_;
  const double v = std::min(
      {v_mm_s_ + accel_mm_s2_ * period_s_, vmax_mm_s_, brake_speed(rem, accel_mm_s2_, period_s_)});
  double ds = v * period_s_;
  if (ds >= rem - 1e-12) {  // the last step lands on the target
    ds = rem;
    active_ = false;
  }
  s_mm_ += ds;
  v_mm_s_ = active_ ? v : 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) position[i] = from_[i] + unit_[i] * s_mm_;
  if (!active_) position = target_;
  speed_mm_s = ds / period_s_;
  return true;
}

}  // namespace cncore::runtime
