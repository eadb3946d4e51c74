#include "bound.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cncore::bound {

using testing::PathSegment;

double segment_time_s(double length, double v0, double v1, double vc, double a) {
  if (length <= 0) return 0;
  vc = std::max(vc, std::max(v0, v1));
  // Peak of the triangle: v_p² − v0² + v_p² − v1² = 2·a·L.
  const double vp = std::min(vc, std::sqrt((2 * a * length + v0 * v0 + v1 * v1) / 2));
  const double d_acc = (vp * vp - v0 * v0) / (2 * a);
  const double d_dec = (vp * vp - v1 * v1) / (2 * a);
  const double cruise = std::max(0.0, length - d_acc - d_dec);
  double t = (vp - v0) / a + (vp - v1) / a;
  if (cruise > 0 && vp > 0) t += cruise / vp;
  return t;
}

void BoundBuilder::add(const Block& b) {
  const std::size_t bi = block_index_++;
  auto stop_here = [&] {
    if (!segs_.empty()) segs_.back().join = 0;
  };
  if (b.kind == BlockKind::kDwell) {
    dwell_s_ += b.dwell_s;
    stop_here();
    return;
  }
  if (b.kind == BlockKind::kAux) {
    if (b.aux_waits) stop_here();
    return;
  }
  PathSegment sg;
  if (!testing::make_segment(b, bi, sg)) {
    if (b.path_mode == PathMode::kExactStop) stop_here();
    return;
  }
  const double amax = lim_.max_accel_mm_s2;
  const double vkind = sg.rapid ? lim_.rapid_mm_s() : lim_.feed_mm_s();
  double cap = vkind;
  if (!sg.rapid && sg.feed_mm_min > 0) cap = std::min(cap, sg.feed_mm_min / 60.0);
  Seg s{sg.length_mm, cap, amax, std::numeric_limits<double>::infinity()};
  const bool rotary_only = sg.length_mm <= 1e-12;
  if (rotary_only) {
    // A move of rotary axes only: its own length (degrees) and the slowest moving axis.
    s.length = 0;
    double cap_t = std::numeric_limits<double>::infinity();
    for (std::size_t i = kA; i < kMaxAxes; ++i) {
      const double d = std::abs(sg.end[i] - sg.start[i]);
      if (d <= 0) continue;
      // Time-optimal for the axis that needs longest; approximate with the largest move.
      if (d > s.length) {
        s.length = d;
        const double va = lim_.axis_speed_mm_min[i] > 0 ? lim_.axis_speed_mm_min[i] / 60 : cap;
        cap_t = std::min(cap, va);
        s.accel = lim_.axis_accel_mm_s2[i] > 0 ? lim_.axis_accel_mm_s2[i] : amax;
      }
    }
    s.cap = cap_t;
  } else if (sg.arc) {
    s.cap = std::min(s.cap, std::sqrt(sg.radius_mm() * amax));
  } else {
    // Per-axis speed by direction: axis i moves at v·|Δ_i|/L.
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      const double d = std::abs(sg.end[i] - sg.start[i]);
      if (d <= 0 || lim_.axis_speed_mm_min[i] <= 0) continue;
      s.cap = std::min(s.cap, lim_.axis_speed_mm_min[i] / 60 * sg.length_mm / d);
    }
  }
  // Joint with the previous segment.
  if (!segs_.empty()) {
    auto& pj = segs_.back().join;
    if (rotary_only || prev_rotary_only_) {
      pj = 0;
    } else if (have_prev_) {
      pj = std::min({pj, segs_.back().cap, s.cap});
      const double theta = testing::corner_angle_rad(prev_, sg);
      const double tau = lim_.period_s;
      if (theta > 1e-12) pj = std::min(pj, amax * tau / (2 * std::sin(theta / 2)));
      const Vec3 e = prev_.tangent_at(1.0), st = sg.tangent_at(0.0);
      const double dt[3] = {st.x - e.x, st.y - e.y, st.z - e.z};
      for (std::size_t i = 0; i < 3; ++i) {
        if (lim_.axis_accel_mm_s2[i] > 0 && std::abs(dt[i]) > 1e-12)
          pj = std::min(pj, lim_.axis_accel_mm_s2[i] * tau / std::abs(dt[i]));
      }
    }
  }
  length_mm_ += sg.length_mm;
  segs_.push_back(s);
  if (b.path_mode == PathMode::kExactStop) segs_.back().join = 0;
  prev_ = sg;
  have_prev_ = true;
  prev_rotary_only_ = rotary_only;
}

BoundResult BoundBuilder::finish() {
  BoundResult r;
  r.dwell_s = dwell_s_;
  r.length_mm = length_mm_;
  r.segments = segs_.size();
  const std::size_t n = segs_.size();
  if (n == 0) {
    r.time_s = dwell_s_;
    return r;
  }
  segs_.back().join = 0;
  // Node speeds: u[0] = 0 (start), u[k+1] = joint at the end of segment k.
  std::vector<double> u(n + 1);
  u[0] = 0;
  for (std::size_t k = 0; k < n; ++k) u[k + 1] = segs_[k].join;
  // Forward pass: reachable from the previous node by accelerating along segment k.
  for (std::size_t k = 0; k < n; ++k) {
    const Seg& s = segs_[k];
    u[k + 1] = std::min({u[k + 1], s.cap, std::sqrt(u[k] * u[k] + 2 * s.accel * s.length)});
    if (k + 1 < n) u[k + 1] = std::min(u[k + 1], segs_[k + 1].cap);
  }
  // Backward pass: able to brake to the next node.
  for (std::size_t k = n; k-- > 0;) {
    const Seg& s = segs_[k];
    u[k] = std::min(u[k], std::sqrt(u[k + 1] * u[k + 1] + 2 * s.accel * s.length));
  }
  for (std::size_t k = 0; k < n; ++k) {
    const Seg& s = segs_[k];
    r.motion_time_s += segment_time_s(s.length, u[k], u[k + 1], s.cap, s.accel);
    if (u[k + 1] == 0) ++r.stops;
  }
  r.time_s = r.motion_time_s + r.dwell_s;
  return r;
}

BoundResult optimal_profile(const std::vector<Block>& blocks, const testing::Limits& limits) {
  BoundBuilder b(limits);
  for (const auto& bl : blocks) b.add(bl);
  return b.finish();
}

double optimal_time_s(const std::vector<Block>& blocks, const testing::Limits& limits) {
  return optimal_profile(blocks, limits).time_s;
}

}  // namespace cncore::bound
