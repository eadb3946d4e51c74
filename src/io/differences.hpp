// Velocities and accelerations of the servo set-points by finite differences: the one definition
// the summary, the run report and the table report share, so that their figures agree.
//   v_k = (p_k − p_{k−1}) / dt_k          per enabled axis, per s (at the middle of the interval)
//   a_k = (v_k − v_{k−1}) / h_k,  h_k = (dt_k + dt_{k−1}) / 2   (distance between the midpoints)
//   path: length |Δp| and speed |Δp| / dt over the enabled linear axes; tangential acceleration
//   (speed_k − speed_{k−1}) / h_k; resultant |v_k − v_{k−1}| / h_k (normal part included).
// A cycle with dt ≤ 0 changes nothing.
#pragma once

#include <cmath>
#include <cstddef>

#include "config/machine_config.hpp"
#include "core/geometry.hpp"

namespace cncore::io {

struct CycleDifferences {
  bool moved = false;  // dt > 0 this cycle: dt, vel, length and speed are valid
  bool accel = false;  // moved and a previous velocity: h, acc and the accelerations are valid
  double dt_s = 0, h_s = 0;
  AxisVec vel;  // per s (mm/s or deg/s); 0 for disabled axes
  AxisVec acc;  // per s² (signed)
  double length_mm = 0, speed_mm_s = 0;
  double tangential_accel_mm_s2 = 0;  // signed
  double path_accel_mm_s2 = 0;        // resultant, ≥ 0
  // update_deltas() only (update() leaves them alone): the numerators of the accelerations,
  // acc = dv / h_s, tangential = dspeed / h_s, path = √dv2 / h_s.
  AxisVec dv;         // v_k − v_{k−1} per axis (per s)
  double dspeed = 0;  // speed_k − speed_{k−1} (mm/s)
  double dv2 = 0;     // |v_k − v_{k−1}|² over the linear axes
};

class FiniteDifferences {
 public:
  explicit FiniteDifferences(const MachineConfig& machine) {
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      enabled_[i] = machine.axes[i].enabled;
      linear_[i] = machine.axes[i].enabled && !machine.axes[i].rotary;
      enabled_mask_[i] = enabled_[i] ? 1.0 : 0.0;
      linear_mask_[i] = linear_[i] ? 1.0 : 0.0;
      if (enabled_[i]) used_axes_ = i + 1;
    }
  }

  // 1 + the last enabled axis: every axis from here on is disabled.
  std::size_t used_axes() const { return used_axes_; }

  // The next set-point; the result stays valid until the next call.
  const CycleDifferences& update(double t_s, const AxisVec& position) {
    return advance<true, kMaxAxes>(t_s, position);
  }
  // The same without the accelerations' divisions and square root: acc, tangential and path
  // acceleration are left unset, their numerators dv, dspeed, dv2 are set instead (for a caller
  // that keeps only maxima and can skip most divisions: summary.cpp). Velocities, length and
  // speed as update(); both may be mixed (the state carried between calls is the same).
  // Over the first N axes only (N >= used_axes()): the same doubles (the axes left out are
  // disabled: v = 0, and the squared sums gain only trailing +0 terms), with loops of a fixed
  // length and no work for the axes that cannot move.
  template <std::size_t N = kMaxAxes>
  const CycleDifferences& update_deltas(double t_s, const AxisVec& position) {
    return advance<false, N>(t_s, position);
  }

  const CycleDifferences& last() const { return d_; }

 private:
  template <bool kAccel, std::size_t N>
  const CycleDifferences& advance(double t_s, const AxisVec& position) {
    d_.moved = d_.accel = false;
    if (have_prev_) {
      const double dt = t_s - prev_t_;
      if (dt > 0) {
        // Without a branch per axis (fewer branches for the predictor next to the acceleration
        // type's cycle): masks of 1 and 0 (×1 exact; a disabled axis gets d = 0, so v = 0; a
        // non-linear one adds +0 to the squared length: the same doubles as skipping them). In
        // plain loops GCC divides two axes per instruction (3 divpd, not 6 divsd).
        AxisVec d, vel;
        for (std::size_t i = 0; i < N; ++i) {
          d[i] = (position[i] - prev_pos_[i]) * enabled_mask_[i];
        }
        for (std::size_t i = 0; i < N; ++i) vel[i] = d[i] / dt;
        double len2 = 0;
        for (std::size_t i = 0; i < N; ++i) len2 += d[i] * d[i] * linear_mask_[i];
        d_.moved = true;
        d_.dt_s = dt;
        d_.length_mm = std::sqrt(len2);
        d_.speed_mm_s = d_.length_mm / dt;
        if (have_vel_) {
          const double h = 0.5 * (dt + prev_dt_);
          double dv2 = 0;
          for (std::size_t i = 0; i < N; ++i) {
            const double dv = vel[i] - d_.vel[i];  // 0 − 0 for a disabled axis
            if constexpr (kAccel) {
              d_.acc[i] = dv / h;
            } else {
              d_.dv[i] = dv;
            }
            dv2 += dv * dv * linear_mask_[i];
          }
          d_.accel = true;
          d_.h_s = h;
          if constexpr (kAccel) {
            d_.path_accel_mm_s2 = std::sqrt(dv2) / h;
            d_.tangential_accel_mm_s2 = (d_.speed_mm_s - prev_speed_) / h;
          } else {
            d_.dv2 = dv2;
            d_.dspeed = d_.speed_mm_s - prev_speed_;
          }
        }
        d_.vel = vel;
        prev_speed_ = d_.speed_mm_s;
        prev_dt_ = dt;
        have_vel_ = true;
      }
    }
    prev_t_ = t_s;
    prev_pos_ = position;
    have_prev_ = true;
    return d_;
  }

  bool enabled_[kMaxAxes] = {};
  bool linear_[kMaxAxes] = {};
  double enabled_mask_[kMaxAxes] = {}, linear_mask_[kMaxAxes] = {};  // 1.0 / 0.0
  std::size_t used_axes_ = 0;
  bool have_prev_ = false, have_vel_ = false;
  double prev_t_ = 0, prev_dt_ = 0, prev_speed_ = 0;
  AxisVec prev_pos_;
  CycleDifferences d_;
};

}  // namespace cncore::io
