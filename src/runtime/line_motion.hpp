// A straight move of the axes from where they are to a target at a feed, with the speed raised
// and lowered at a constant acceleration: the motion of jogging and homing, which run outside
// the program's planner. Real-time: fixed size, no allocation, O(1) per cycle.
#pragma once

#include "config/machine_config.hpp"
#include "core/geometry.hpp"

namespace cncore::runtime {

class LineMotion {
 public:
  // Speed and acceleration along the line are capped so that no axis exceeds its own limits
  // (the axis whose share of the motion is largest decides).
  void start(const MachineConfig& machine, const AxisVec& from, const AxisVec& to,
             double feed_mm_min);
  // Decelerate to rest as soon as the acceleration allows (jog cancel, a switch reached).
  void stop();
  bool active() const { return active_; }
  // One interpolation period: writes the new position and speed; false (nothing written) once
  // the move has ended at rest.
  bool step(AxisVec& position, double& speed_mm_s);

 private:
  AxisVec from_, unit_, target_;
  double length_mm_ = 0, s_mm_ = 0, v_mm_s_ = 0;
  double vmax_mm_s_ = 0, accel_mm_s2_ = 0, period_s_ = 0.001;
  bool active_ = false;
};

}  // namespace cncore::runtime
