// Time-optimal lower bound for a part program on a machine: the shortest time to run the exact
// programmed path with |tangential acceleration| ≤ Amax, the speed at every point ≤ min(F, Vmax,
// per-axis limits by direction, √(R·Amax) on arcs), every corner passed at ≤ Amax·τ/(2 sin(θ/2))
// (and ≤ A_i·τ/|ΔT_i| per axis), and a stop wherever the program stops (exact stop, dwell —
// whose time is added —, waiting M-codes, the end). No real controller can be faster under
// those limits, so (kernel cycle time) / bound ≥ 1 measures what the acc/dec method wastes.
//
// Computed exactly per segment: with a constant speed cap inside a segment and constant
// acceleration, v² is linear in the path length, so a forward pass (acceleration) and a backward
// pass (braking) over the joint speeds give the optimal joint speeds, and each segment then runs
// accelerate–cruise–decelerate in closed form. Streams: memory is three numbers per segment.
// Optimistic where exactness would cost more (so it stays a lower bound): per-axis speed limits
// on arcs are not applied, and the normal acceleration on arcs is not added to the tangential.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/block.hpp"
#include "limits.hpp"
#include "path_geometry.hpp"

namespace cncore::bound {

struct BoundResult {
  double time_s = 0;  // motion time + dwell time
  double motion_time_s = 0;
  double dwell_s = 0;
  double length_mm = 0;      // XYZ path length
  std::size_t segments = 0;  // moving segments
  std::size_t stops = 0;     // joints where the program stops (incl. the end)
};

// Feed blocks in program order, then finish().
class BoundBuilder {
 public:
  explicit BoundBuilder(const testing::Limits& limits) : lim_(limits) {}
  void add(const Block& block);
  BoundResult finish();

 private:
  struct Seg {
    double length;  // mm (XYZ), or degrees for a rotary-only move
    double cap;     // speed cap inside the segment, mm/s (deg/s)
    double accel;   // acceleration limit along it
    double join;    // speed limit at its END joint (0 = stop)
  };
  testing::Limits lim_;
  std::vector<Seg> segs_;
  testing::PathSegment prev_;
  bool have_prev_ = false;
  bool prev_rotary_only_ = false;
  double dwell_s_ = 0;
  std::size_t block_index_ = 0;
  double length_mm_ = 0;
};

BoundResult optimal_profile(const std::vector<Block>& blocks, const testing::Limits& limits);
double optimal_time_s(const std::vector<Block>& blocks, const testing::Limits& limits);

// Time to run `length` from speed v0 to v1 with cap vc and acceleration a (v0, v1 reachable:
// |v1² − v0²| ≤ 2·a·length): accelerate, cruise at the cap if it is reached, decelerate.
double segment_time_s(double length, double v0, double v1, double vc, double a);

}  // namespace cncore::bound
