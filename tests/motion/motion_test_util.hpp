// Helpers for the motion-kernel tests: a test machine, block builders and a runner that feeds
// the kernel like the simulation driver does and records the trajectory for the checker.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "motion/kernel.hpp"
#include "trajectory.hpp"

namespace cncore::motion::test {

// The built-in machine's motion limits with X Y Z enabled (local: the tests do not depend on
// the config loader). Axis limits are set above the path limits unless a test lowers them.
inline MachineConfig test_machine() {
  MachineConfig m;
  for (std::size_t i = 0; i < 3; ++i) {
    m.axes[i].enabled = true;
    m.axes[i].min_mm = -1e6;
    m.axes[i].max_mm = 1e6;
    m.axes[i].max_speed_mm_min = 20000;
    m.axes[i].max_accel_mm_s2 = 10000;
  }
  return m;
}

struct Prog {
  std::vector<Block> blocks;
  AxisVec pos;
  std::uint32_t line = 1;

  Block base(BlockKind k) {
    Block b;
    b.kind = k;
    b.line = line++;
    b.col = 1;
    b.start = pos;
    b.end = pos;
    return b;
  }
  Prog& line_to(AxisVec to, double feed, PathMode mode = PathMode::kBlend) {
    Block b = base(BlockKind::kLine);
    b.end = to;
    b.feed_mm_min = feed;
    b.path_mode = mode;
    blocks.push_back(b);
    pos = to;
    return *this;
  }
  Prog& line_to(Vec3 to, double feed, PathMode mode = PathMode::kBlend) {
    AxisVec a = pos;
    a.set_xyz(to);
    return line_to(a, feed, mode);
  }
  Prog& rapid_to(Vec3 to) {
    Block b = base(BlockKind::kRapid);
    b.end.set_xyz(to);
    blocks.push_back(b);
    pos = b.end;
    return *this;
  }
  // Arc counter-clockwise about `normal` through centre `c` to `to` (helix if `to` rises).
  Prog& arc_to(Vec3 to, Vec3 c, double feed, Vec3 normal = {0, 0, 1}, std::uint32_t turns = 0) {
    Block b = base(BlockKind::kArc);
    b.end.set_xyz(to);
    b.center = c;
    b.normal = normal;
    b.turns = turns;
    b.feed_mm_min = feed;
    blocks.push_back(b);
    pos = b.end;
    return *this;
  }
  Prog& dwell(double s) {
    Block b = base(BlockKind::kDwell);
    b.dwell_s = s;
    blocks.push_back(b);
    return *this;
  }
  Prog& aux(char letter, double value, bool waits) {
    Block b = base(BlockKind::kAux);
    b.aux_letter = letter;
    b.aux_value = value;
    b.aux_waits = waits;
    blocks.push_back(b);
    return *this;
  }
};

// The seed's example (FIG. 3): a line ending at G[1], an arc ending at G[2] and a line ending
// at G[3]. As in the seed's FIG. 4 the joints are passed without stopping, at the passing speed
// of the arc (R 5 mm: √(R·Amax) = 100 mm/s below the feed 10 000 mm/min = 166.7 mm/s).
inline Prog seed_example(double feed = 10000) {
  Prog p;
  p.line_to(Vec3{50, 0, 0}, feed);
  p.arc_to(Vec3{55, 5, 0}, Vec3{50, 5, 0}, feed);  // quarter turn, tangent at both ends
  p.line_to(Vec3{55, 50, 0}, feed);
  return p;
}

// Line, arc, line with real corners: 45° at both joints (Vg = Amax·τ/(2 sin 22.5°) = 2.6 mm/s).
inline Prog corner_example(double feed = 10000) {
  Prog p;
  p.line_to(Vec3{50, 0, 0}, feed);
  p.arc_to(Vec3{50, 20, 0}, Vec3{40, 10, 0}, feed);  // R = 14.14, enters at 45°, leaves at 135°
  p.line_to(Vec3{0, 20, 0}, feed);
  return p;
}

// Rapids, a spindle start that waits (M3), a dwell, an exact stop and events that do not wait:
// they must happen in the order S12000 M3 M8 M5.
inline Prog events_example() {
  Prog p;
  p.rapid_to(Vec3{100, 50, 10});
  p.aux('S', 12000, false);
  p.aux('M', 3, true);
  p.line_to(Vec3{100, 50, 0}, 2000);
  p.dwell(0.25);
  p.line_to(Vec3{150, 50, 0}, 5000);
  p.aux('M', 8, false);
  p.line_to(Vec3{150, 80, 0}, 5000, PathMode::kExactStop);
  p.line_to(Vec3{120, 80, 0}, 5000);
  p.aux('M', 5, false);
  return p;
}

// P5: override steps (t_s, %) up and down at arbitrary cycles, also mid-corner of
// corner_example(6000), through 0 and 200 %.
inline std::vector<std::pair<double, double>> p5_override_steps() {
  return {{0.05, 200}, {0.31, 37},  {0.313, 150}, {0.5, 0},  {0.7, 120},
          {0.9, 10},   {0.95, 200}, {1.2, 75},    {1.4, 200}};
}

// The seed's example, a zig-zag of 2 mm strokes and a half circle: the post filter's contour
// tolerance tests (corners of every sharpness, arcs).
inline Prog contour_example() {
  Prog p = seed_example();
  for (int i = 0; i < 20; ++i) {
    p.line_to(Vec3{i % 2 == 0 ? 10.0 : 0.0, 20 + 2.0 * (i + 1), 0}, 10000);
  }
  p.arc_to(Vec3{0, 70, 0}, Vec3{0, 65, 0}, 10000, {0, 0, -1});
  return p;
}

struct RunResult {
  std::vector<Sample> samples;
  testing::Trajectory traj;
  std::uint64_t mismatches = 0;
  double time_s() const { return samples.empty() ? 0 : samples.back().t_s; }
};

// The programmed end point: the last motion block's end (`start` when there is none).
inline AxisVec program_end(AxisVec start, const std::vector<Block>& blocks) {
  for (const Block& b : blocks) {
    if (b.kind == BlockKind::kRapid || b.kind == BlockKind::kLine || b.kind == BlockKind::kArc)
      start = b.end;
  }
  return start;
}

struct RunOpts {
  KernelOptions kernel;
  std::vector<std::pair<double, double>> override_steps;  // (t_s, pct)
  std::vector<std::pair<double, bool>> hold_steps;        // (t_s, hold)
  std::size_t feed_every = 0;  // > 0: push at most this many blocks per cycle (late arrivals)
  std::uint64_t max_cycles = 50'000'000;
  bool keep_samples = true;
};

inline RunResult run(const MachineConfig& m, const std::vector<Block>& blocks,
                     const RunOpts& o = {}) {
  RunResult r;
  Kernel k(m, o.kernel);
  std::size_t next = 0, ov = 0, hd = 0;
  Sample s;
  r.traj.period_s = m.period_s;
  for (std::uint64_t c = 0; c < o.max_cycles; ++c) {
    std::size_t pushed = 0;
    while (next < blocks.size() && k.wants_block() &&
           (o.feed_every == 0 || pushed < o.feed_every)) {
      k.push(blocks[next++]);
      ++pushed;
    }
    if (next == blocks.size()) k.end_of_program();
    const double t = static_cast<double>(c) * m.period_s;
    while (ov < o.override_steps.size() && o.override_steps[ov].first <= t + 1e-12) {
      k.set_override(o.override_steps[ov++].second);
    }
    while (hd < o.hold_steps.size() && o.hold_steps[hd].first <= t + 1e-12) {
      k.set_feed_hold(o.hold_steps[hd++].second);
    }
    if (!k.step(s)) break;
    if (o.keep_samples) {
      r.samples.push_back(s);
      r.traj.add_sample(s);
    }
  }
  r.mismatches = k.reference_mismatches();
  return r;
}

}  // namespace cncore::motion::test
