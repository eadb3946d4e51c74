// RapidCheck helpers shared by the motion kernel's property tests: random moves, random override
// steps and the log of a failing case.
#pragma once

#include <rapidcheck.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <vector>

#include "motion_test_util.hpp"

namespace cncore::motion::test {

// 1–13 moves from the origin: lines (some exact stops or exact paths), rapids, and arcs or
// helices about a random centre in a principal plane, 1 µm to 30 mm, feeds 500–20 000 mm/min
// (above the machine's too). arcs_only: arcs and helices only.
inline Prog random_moves(bool arcs_only = false) {
  Prog p;
  const int n = *rc::gen::inRange(1, 14);
  for (int i = 0; i < n; ++i) {
    const int kind = *rc::gen::inRange(arcs_only ? 6 : 0, 10);
    const double scale = *rc::gen::element(1e-3, 0.05, 0.5, 5.0, 30.0);
    const double dx = scale * (*rc::gen::inRange(-1000, 1001)) / 1000.0;
    const double dy = scale * (*rc::gen::inRange(-1000, 1001)) / 1000.0;
    const double dz = scale * (*rc::gen::inRange(-300, 301)) / 1000.0;
    const double feed = *rc::gen::element(500.0, 3000.0, 8000.0, 10000.0, 20000.0);
    const Vec3 at = p.pos.xyz();
    const Vec3 to = at + Vec3{dx, dy, dz};
    if (kind < 5) {
      p.line_to(to, feed,
                *rc::gen::element(PathMode::kBlend, PathMode::kBlend, PathMode::kExactStop,
                                  PathMode::kExactPath));
    } else if (kind < 6) {
      p.rapid_to(to);
    } else {
      const Vec3 normal =
          *rc::gen::element(Vec3{0, 0, 1}, Vec3{0, 0, -1}, Vec3{0, 1, 0}, Vec3{-1, 0, 0});
      const double r = std::max(0.05, scale * (0.1 + (*rc::gen::inRange(0, 1000)) / 1000.0));
      // Centre offset perpendicular to the normal.
      const Vec3 off =
          normal.z != 0 ? Vec3{r, 0, 0} : (normal.y != 0 ? Vec3{0, 0, r} : Vec3{0, r, 0});
      const Vec3 centre = at + off;
      const double ang = (*rc::gen::inRange(1, 700)) / 100.0;
      // End point: rotate (at − centre) about the normal by ang, plus a rise along it.
      const Vec3 v = at - centre;
      const Vec3 w = cross(normal, v);
      const double rise = *rc::gen::element(0.0, 0.0, dz);
      const Vec3 end = centre + std::cos(ang) * v + std::sin(ang) * w + rise * normal;
      p.arc_to(end, centre, feed, normal, *rc::gen::element(0u, 0u, 0u, 1u));
    }
  }
  return p;
}

// 0–5 override steps at 0–2 s to 0–200 %, then 100 % at 2.5 s (never stuck at 0).
inline void add_random_override_steps(RunOpts& o) {
  const int steps = *rc::gen::inRange(0, 6);
  for (int i = 0; i < steps; ++i) {
    o.override_steps.emplace_back((*rc::gen::inRange(0, 2000)) / 1000.0,
                                  *rc::gen::element(0.0, 10.0, 50.0, 100.0, 150.0, 200.0));
  }
  std::sort(o.override_steps.begin(), o.override_steps.end());
  if (!o.override_steps.empty()) o.override_steps.emplace_back(2.5, 100.0);
}

// A failing case's blocks and override steps, to rebuild it as a plain test.
inline void log_case(const std::vector<Block>& blocks, const RunOpts& o) {
  for (const Block& b : blocks) {
    RC_LOG() << std::setprecision(17) << "kind " << static_cast<int>(b.kind) << " line " << b.line
             << " (" << b.start[0] << "," << b.start[1] << "," << b.start[2] << ") -> (" << b.end[0]
             << "," << b.end[1] << "," << b.end[2] << ") c (" << b.center.x << "," << b.center.y
             << "," << b.center.z << ") n (" << b.normal.x << "," << b.normal.y << "," << b.normal.z
             << ") turns " << b.turns << " F " << b.feed_mm_min << " mode "
             << static_cast<int>(b.path_mode) << "\n";
  }
  for (const auto& [t, pct] : o.override_steps) RC_LOG() << "override " << t << " " << pct << "\n";
}

}  // namespace cncore::motion::test
