// RapidCheck generators for motion property tests: random chained Block sequences (lines of every
// length down to far below one cycle's travel, arcs in G17/G18/G19 both ways, full circles,
// helices with extra turns, rapids, exact stops, dwells) inside the built-in machine's travel, and
// random feed-override steps. Link target cncore_test_support_rc.
#pragma once

#include <rapidcheck.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <ostream>
#include <utility>
#include <vector>

#include "core/block.hpp"

namespace cncore {
// How RapidCheck prints a Block in a counterexample (found by argument-dependent lookup).
inline void showValue(const Block& b, std::ostream& os) {
  static constexpr const char* kKinds[] = {"G0", "G1", "arc", "dwell", "aux"};
  const auto old_precision = os.precision(17);
  os << "{line " << b.line << " " << kKinds[static_cast<int>(b.kind)] << " start (" << b.start[kX]
     << ", " << b.start[kY] << ", " << b.start[kZ] << ") end (" << b.end[kX] << ", " << b.end[kY]
     << ", " << b.end[kZ] << ") F" << b.feed_mm_min;
  if (b.kind == BlockKind::kArc)
    os << " centre (" << b.center.x << ", " << b.center.y << ", " << b.center.z << ") normal ("
       << b.normal.x << ", " << b.normal.y << ", " << b.normal.z << ") turns " << b.turns;
  if (b.kind == BlockKind::kDwell) os << " dwell " << b.dwell_s;
  if (b.path_mode == PathMode::kExactStop) os << " exact-stop";
  os << "}";
  os.precision(old_precision);
}
}  // namespace cncore

namespace cncore::testing::gen {

struct BlockGenOptions {
  std::size_t min_blocks = 1;
  std::size_t max_blocks = 25;
  double min_len_mm = 0.001;  // lines: log-uniform between min and max
  double max_len_mm = 50;
  double min_radius_mm = 0.1;  // arcs: log-uniform
  double max_radius_mm = 100;
  double min_feed_mm_min = 60;
  double max_feed_mm_min = 15000;  // above the machine's 10 000: the limit must clip it
  bool arcs = true;
  bool helices = true;
  bool rapids = true;
  bool stops = true;  // exact stops and dwells
  // Travel box the whole path stays inside (the built-in machine's).
  Vec3 travel_min{-300, -200, -200};
  Vec3 travel_max{300, 200, 100};
  AxisVec start{};  // machine position at program start
};

namespace detail {

inline bool inside(const Vec3& p, const BlockGenOptions& o, double margin = 0) {
  return p.x >= o.travel_min.x + margin && p.x <= o.travel_max.x - margin &&
         p.y >= o.travel_min.y + margin && p.y <= o.travel_max.y - margin &&
         p.z >= o.travel_min.z + margin && p.z <= o.travel_max.z - margin;
}

inline double log_uniform(double lo, double hi, int k, int steps = 1000) {
  return lo * std::pow(hi / lo, static_cast<double>(k) / steps);
}

// Normal of the plane (G17 Z, G18 Y, G19 X) with the sign of the direction (G3 +, G2 −).
inline Vec3 plane_normal(int plane, bool ccw) {
  const double s = ccw ? 1.0 : -1.0;
  if (plane == 17) return {0, 0, s};
  if (plane == 18) return {0, s, 0};
  return {s, 0, 0};
}

// A unit vector in the plane perpendicular to the axis-aligned normal n at angle a.
inline Vec3 in_plane(const Vec3& n, double a) {
  if (std::abs(n.z) > 0.5) return {std::cos(a), std::sin(a), 0};
  if (std::abs(n.y) > 0.5) return {std::sin(a), 0, std::cos(a)};
  return {0, std::cos(a), std::sin(a)};
}

}  // namespace detail

// A chained sequence: block[i].start == block[i−1].end for motion blocks, lines numbered 1…n.
inline rc::Gen<std::vector<Block>> blocks(BlockGenOptions o = {}) {
  return rc::gen::exec([o]() {
    using namespace detail;
    const auto n = *rc::gen::inRange<std::size_t>(o.min_blocks, o.max_blocks + 1);
    std::vector<Block> out;
    AxisVec pos = o.start;
    std::uint32_t line = 1;
    const double feed_choice[] = {o.min_feed_mm_min, 600, 3000, 6000, 10000, o.max_feed_mm_min};
    for (std::size_t i = 0; i < n; ++i) {
      Block b;
      b.line = line++;
      b.start = pos;
      const int kind = *rc::gen::inRange(0, 100);
      if (o.stops && kind < 4) {
        b.kind = BlockKind::kDwell;
        b.dwell_s = *rc::gen::element(0.0, 0.001, 0.05);
        out.push_back(b);
        continue;
      }
      const double feed =
          *rc::gen::elementOf(std::vector<double>(std::begin(feed_choice), std::end(feed_choice)));
      b.feed_mm_min = feed;
      if (o.stops && *rc::gen::inRange(0, 10) == 0) b.path_mode = PathMode::kExactStop;
      bool made = false;
      if (o.arcs && kind >= 60) {
        const int plane = *rc::gen::element(17, 18, 19);
        const bool ccw = *rc::gen::arbitrary<bool>();
        const Vec3 nrm = plane_normal(plane, ccw);
        const double r = log_uniform(o.min_radius_mm, o.max_radius_mm, *rc::gen::inRange(0, 1001));
        const double a0 = *rc::gen::inRange(0, 360) * std::numbers::pi / 180;
        const bool full = *rc::gen::inRange(0, 8) == 0;
        const double sweep =
            full ? 2 * std::numbers::pi : *rc::gen::inRange(1, 360) * std::numbers::pi / 180;
        const std::uint32_t turns =
            o.helices && *rc::gen::inRange(0, 6) == 0 ? *rc::gen::inRange<std::uint32_t>(1, 3) : 0;
        const double rise = o.helices && *rc::gen::inRange(0, 3) == 0
                                ? *rc::gen::inRange(-200, 201) / 100.0 * (1 + turns)
                                : 0.0;
        const Vec3 e1 = in_plane(nrm, a0);  // from the centre to the start
        const Vec3 e2 = cross(nrm, e1);
        const Vec3 c = pos.xyz() - r * e1;
        // Conservative travel check: the whole circle and the rise inside the box.
        const Vec3 ext{std::abs(nrm.x) > 0.5 ? 0 : r, std::abs(nrm.y) > 0.5 ? 0 : r,
                       std::abs(nrm.z) > 0.5 ? 0 : r};
        const Vec3 top = pos.xyz() + rise * nrm;
        if (inside(c + ext, o, 1) && inside(c - ext, o, 1) && inside(top, o, 1)) {
          b.kind = BlockKind::kArc;
          b.center = c;
          b.normal = nrm;
          b.turns = turns;
          Vec3 end = full ? pos.xyz() : c + (r * std::cos(sweep)) * e1 + (r * std::sin(sweep)) * e2;
          end = end + rise * nrm;
          b.end = pos;
          b.end.set_xyz(end);
          made = true;
        }
      }
      if (!made) {
        b.kind = (o.rapids && kind < 10) ? BlockKind::kRapid : BlockKind::kLine;
        if (b.kind == BlockKind::kRapid) b.feed_mm_min = 0;
        const double len = log_uniform(o.min_len_mm, o.max_len_mm, *rc::gen::inRange(0, 1001));
        Vec3 d;
        if (*rc::gen::inRange(0, 3) == 0) {
          // Axis-aligned moves make exact 90° and 180° corners.
          const int ax = *rc::gen::inRange(0, 3);
          const double s = *rc::gen::arbitrary<bool>() ? 1.0 : -1.0;
          d = {ax == 0 ? s : 0, ax == 1 ? s : 0, ax == 2 ? s : 0};
        } else {
          const double az = *rc::gen::inRange(0, 3600) * std::numbers::pi / 1800;
          const double el = *rc::gen::inRange(-900, 901) * std::numbers::pi / 1800 / 3;
          d = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
        }
        Vec3 end = pos.xyz() + len * d;
        if (!inside(end, o, 1)) end = pos.xyz() - len * d;  // the other way is inside
        if (!inside(end, o, 1)) end = 0.5 * pos.xyz();      // towards the middle
        b.end = pos;
        b.end.set_xyz(end);
      }
      pos = b.end;
      out.push_back(b);
    }
    return out;
  });
}

// Feed-override steps (time s, override %) at increasing times in [0, max_time_s], values in
// [min_pct, max_pct] (keep min_pct > 0 so that the program ends).
inline rc::Gen<std::vector<std::pair<double, double>>> override_steps(double max_time_s,
                                                                      double min_pct = 10,
                                                                      double max_pct = 200,
                                                                      std::size_t max_steps = 6) {
  return rc::gen::exec([=]() {
    const auto n = *rc::gen::inRange<std::size_t>(0, max_steps + 1);
    std::vector<std::pair<double, double>> steps;
    for (std::size_t i = 0; i < n; ++i) {
      const double t = *rc::gen::inRange(0, 10001) / 10000.0 * max_time_s;
      const double pct = min_pct + (max_pct - min_pct) * *rc::gen::inRange(0, 1001) / 1000.0;
      steps.emplace_back(t, pct);
    }
    std::sort(steps.begin(), steps.end());
    return steps;
  });
}

}  // namespace cncore::testing::gen
