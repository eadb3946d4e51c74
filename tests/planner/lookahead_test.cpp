// The look-ahead structure against a plain reference walk, and the passing-speed formulas of
// spec 01 checked against values worked out by hand.
#include "planner/lookahead.hpp"

#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "planner/min_tree.hpp"
#include "planner/segment.hpp"

namespace cncore::planner {
namespace {

TEST(MinTree, MinAndArgminFollowUpdates) {
  MinTree t(5);
  EXPECT_EQ(t.min(), MinTree::kEmpty);
  t.set(3, 2.0);
  t.set(1, 5.0);
  EXPECT_EQ(t.min(), 2.0);
  EXPECT_EQ(t.argmin(), 3u);
  t.set(3, MinTree::kEmpty);
  EXPECT_EQ(t.min(), 5.0);
  EXPECT_EQ(t.argmin(), 1u);
  t.set(4, -1.0);
  EXPECT_EQ(t.argmin(), 4u);
}

// The 8-ary layout against a plain array: min, argmin (the lowest index on ties), min_range over
// every range, for sizes around the group and level boundaries; and the node-major rows.
TEST(MinTree, MatchesAPlainArrayAtEverySize) {
  std::mt19937 rng(7);
  for (std::size_t n : {1u, 2u, 7u, 8u, 9u, 63u, 64u, 65u, 513u, 1000u}) {
    MinTree t(n);
    MinTreeRows rows(n, 3);
    std::vector<double> v(n, MinTree::kEmpty);
    std::uniform_int_distribution<std::size_t> pick(0, n - 1);
    std::uniform_int_distribution<int> val(0, 20);  // small values: many ties
    for (int step = 0; step < 400; ++step) {
      const std::size_t i = pick(rng);
      v[i] = val(rng) == 0 ? MinTree::kEmpty : val(rng);
      t.set(i, v[i]);
      const double r[3] = {v[i], v[i] + 1, 2 * v[i]};
      rows.set(i, r);
      const auto it = std::min_element(v.begin(), v.end());
      ASSERT_EQ(t.min(), *it) << "n " << n;
      if (*it != MinTree::kEmpty) {
        ASSERT_EQ(t.argmin(), static_cast<std::size_t>(it - v.begin())) << "n " << n;
      }
      ASSERT_EQ(rows.min(0), *it);
      ASSERT_EQ(rows.min(2), 2 * *it);
      ASSERT_EQ(rows.min(1), *it + 1);
    }
    for (std::size_t lo = 0; lo <= n; lo += (n > 70 ? 13 : 1)) {
      for (std::size_t hi = lo; hi <= n; hi += (n > 70 ? 7 : 1)) {
        const double want =
            lo == hi ? MinTree::kEmpty : *std::min_element(v.begin() + lo, v.begin() + hi);
        ASSERT_EQ(t.min_range(lo, hi), want) << "n " << n << " [" << lo << ", " << hi << ")";
      }
    }
    rows.clear(0);
    v[0] = MinTree::kEmpty;
    ASSERT_EQ(rows.min(0), *std::min_element(v.begin(), v.end()));
  }
}

// The group-minima trees against a plain array of leaves: the owner hands over each group's
// minima after a change (as the acceleration type's feed keys do); every tree's minimum is the
// plain minimum of its leaves, for sizes around the group and level boundaries.
TEST(MinTreeGroups, MatchesAPlainArrayAtEverySize) {
  std::mt19937 rng(11);
  for (std::size_t n : {1u, 7u, 8u, 9u, 63u, 64u, 65u, 513u, 4097u}) {
    constexpr std::size_t kWidth = 3;
    MinTreeGroups t(n, kWidth);
    std::vector<double> v(n, MinTree::kEmpty);
    std::uniform_int_distribution<std::size_t> pick(0, n - 1);
    std::uniform_int_distribution<int> val(0, 20);  // small values: many ties
    auto tree_value = [&](std::size_t i, std::size_t j) {
      return v[i] == MinTree::kEmpty ? v[i] : v[i] * static_cast<double>(j + 1) - 3.0 * j;
    };
    for (int step = 0; step < 600; ++step) {
      const std::size_t i = pick(rng);
      v[i] = val(rng) < 3 ? MinTree::kEmpty : val(rng);
      double m[kWidth];
      for (std::size_t j = 0; j < kWidth; ++j) {
        m[j] = MinTree::kEmpty;
        for (std::size_t k = i / 8 * 8; k < std::min(n, i / 8 * 8 + 8); ++k) {
          m[j] = std::min(m[j], tree_value(k, j));
        }
      }
      t.set_group(i / 8, m);
      for (std::size_t j = 0; j < kWidth; ++j) {
        double want = MinTree::kEmpty;
        for (std::size_t k = 0; k < n; ++k) want = std::min(want, tree_value(k, j));
        ASSERT_EQ(t.min(j), want) << "n " << n << " tree " << j;
      }
    }
  }
}

// Randomised: points arrive in path order while the commanded and the (lagging) tool
// positions advance by random steps and the override jumps; every cycle the O(log n)
// structure and the plain walk give the same Ul, bit for bit.
RC_GTEST_PROP(Lookahead, SameLimitAsTheReferenceWalk, ()) {
  const auto seed = *rc::gen::arbitrary<std::uint32_t>();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0, 1);
  const std::size_t slots = 64;
  const double or_max = 2.0;
  Lookahead la(slots, or_max);
  double s_cmd = 0, s_tool = 0, c = 0, orr = 1;
  std::vector<std::size_t> live_order;  // slots in path order
  std::size_t next_slot = 0;
  const int span = 1 + static_cast<int>(u01(rng) * 100);
  for (int cycle = 0; cycle < 3000; ++cycle) {
    // New end points (path order) while there is room.
    while (live_order.size() + 2 < slots && u01(rng) < 0.3) {
      c += u01(rng) < 0.5 ? u01(rng) * 0.05 : u01(rng) * 3;  // tiny and long segments
      const bool feed = u01(rng) < 0.3;
      CapPoint p{c, u01(rng) * 0.2, feed, static_cast<double>(span),
                 c + (u01(rng) < 0.3 ? u01(rng) * 0.5 : 0)};
      const std::size_t slot = next_slot++ % slots;
      la.insert(slot, p, s_cmd);
      live_order.push_back(slot);
    }
    if (u01(rng) < 0.05) orr = u01(rng) * or_max;
    const double ref = la.reference_limit(s_cmd, s_tool, orr);
    const double ul = la.limit(s_cmd, s_tool, orr);
    RC_ASSERT(ul == ref);
    // Advance: commanded by a random step within the limit, tool lags behind.
    const double step = std::max(0.0, std::min(ul, u01(rng) * 0.3));
    s_cmd = std::min(s_cmd + step, c);
    s_tool += (s_cmd - s_tool) * u01(rng) * 0.2;
    // Retire points the tool passed (as the buffer does).
    while (!live_order.empty() && !la.live(live_order.front())) {
      live_order.erase(live_order.begin());
    }
  }
}

// The walk applies every end point's cap: a far point with a very low cap limits even when a
// nearer one is out of range (the seed's flowchart stops at the first point out of range).
TEST(Lookahead, AppliesEveryCapNotJustTheFirstOutOfRange) {
  Lookahead la(8, 1.0);
  const double span = 10;
  la.insert(0, CapPoint{100, 1.0, false, span, 100}, 0);    // r = 90
  la.insert(1, CapPoint{20.5, 0.0, false, span, 20.5}, 0);  // r = 20.5 (a stop-like cap)
  // At s = 19: the nearer point (c = 100) is far out of range; the later one... here the
  // order in the buffer is irrelevant: Ul = min(90 − 19, 20.5 − 19) = 1.5.
  EXPECT_DOUBLE_EQ(la.limit(19, 0, 1), 1.5);
  EXPECT_DOUBLE_EQ(la.reference_limit(19, 0, 1), 1.5);
}

// Range start r = c − V·span and the in-range cap V; release only when the tool passed c.
TEST(Lookahead, CapHoldsUntilTheToolHasPassed) {
  Lookahead la(4, 1.0);
  la.insert(0, CapPoint{50, 0.5, false, 10, 50}, 0);  // r = 45, w = 44.5
  EXPECT_DOUBLE_EQ(la.limit(40, 0, 1), 5.0);          // approaching: r − s
  EXPECT_DOUBLE_EQ(la.limit(44.5, 30, 1), 0.5);       // in range
  EXPECT_DOUBLE_EQ(la.limit(55, 49.9, 1), 0.5);       // commanded past c, tool not: still held
  EXPECT_EQ(la.limit(56, 50, 1), MinTree::kEmpty);    // tool at c: released
  EXPECT_FALSE(la.live(0));
}

// Feed caps: range from the highest override, cap scaled by the current override.
TEST(Lookahead, FeedCapScalesWithOverrideButRangeDoesNot) {
  Lookahead la(4, 2.0);
  la.insert(0, CapPoint{50, 0.1, true, 10, 50}, 0);  // r = 50 − 0.1·2·10 = 48, w = 47.8
  EXPECT_DOUBLE_EQ(la.limit(40, 0, 0.5), 8.0);
  EXPECT_DOUBLE_EQ(la.limit(47.8, 0, 0.5), 0.05);
  EXPECT_DOUBLE_EQ(la.limit(47.9, 0, 1.5), 0.1 * 1.5);
}

// A point that arrives after the commanded position passed its range start gets a lower cap
// (c − s)/span so the argument of lookahead.hpp still holds.
TEST(Lookahead, LateArrivalLowersTheCap) {
  Lookahead la(4, 1.0);
  const double v = la.insert(0, CapPoint{50, 1.0, false, 10, 50}, 45);
  EXPECT_DOUBLE_EQ(v, 0.5);
}

Limits test_limits() {
  MachineConfig m;  // 10 000 mm/min, 2 000 mm/s², 1 ms
  return make_limits(m, false);
}

TEST(Segment, TimeConstantAndCornerSpeedByHand) {
  const Limits l = test_limits();
  // T = ceil(166.67 mm/s / (2000 mm/s² · 1 ms)) = ceil(83.3) = 84.
  EXPECT_EQ(l.t_cycles, 84u);
  Block a;
  a.kind = BlockKind::kLine;
  a.end.set_xyz({10, 0, 0});
  a.feed_mm_min = 10000;
  Block b = a;
  b.start = a.end;
  b.end.set_xyz({10, 10, 0});
  const Segment sa = make_motion_segment(a, l), sb = make_motion_segment(b, l);
  EXPECT_DOUBLE_EQ(sa.length_mm, 10);
  // 90°: V = Amax·τ / (2 sin 45°) = 2 mm/s / 1.41421 = 1.41421 mm/s, far below a third of the
  // feed (166.7 mm/s / 3): crawling through the corner would cost more than a stop, so 0.
  EXPECT_EQ(joint_speed_pc(sa, sb, l), 0.0);
  // 1°: V = 0.002 mm/cycle² / (2 sin 0.5°) = 0.114591 mm/cycle ≥ 0.166667 / 3: passed at V.
  const double a1 = 1.0 * std::numbers::pi / 180;
  Block c = b;
  c.end.set_xyz({10 + 10 * std::cos(a1), 10 * std::sin(a1), 0});
  const Segment sc = make_motion_segment(c, l);
  EXPECT_NEAR(joint_speed_pc(sa, sc, l), 0.002 / (2 * std::sin(a1 / 2)), 1e-12);
}

TEST(Segment, ArcShapeSpeedLengthAndEndPoint) {
  const Limits l = test_limits();
  Block arc;
  arc.kind = BlockKind::kArc;
  arc.start.set_xyz({5, 0, 0});
  arc.end.set_xyz({-5, 0, 2});  // half turn, rise 2
  arc.center = {0, 0, 0};
  arc.feed_mm_min = 10000;
  const Segment s = make_motion_segment(arc, l);
  EXPECT_NEAR(s.length_mm, std::sqrt(std::pow(5 * std::numbers::pi, 2) + 4), 1e-12);
  // Vb = √(R·Amax/(1 + 1/T)) = √(5 · 2000 / (1 + 1/84)) = 99.41 mm/s (the 1/T is kept for the
  // tangential ramp inside the arc, see segment.cpp).
  EXPECT_NEAR(s.vb_pc, 0.1 / std::sqrt(1 + 1.0 / 84), 1e-12);
  const AxisVec mid = s.point_at(s.length_mm / 2);
  EXPECT_NEAR(mid[kX], 0, 1e-12);
  EXPECT_NEAR(mid[kY], 5, 1e-12);
  EXPECT_NEAR(mid[kZ], 1, 1e-12);
  EXPECT_EQ(s.point_at(s.length_mm), arc.end);  // exact end
}

TEST(Segment, FullCircleAndPerAxisSpeedLimit) {
  MachineConfig m;
  m.axes[kY].enabled = true;
  m.axes[kY].max_speed_mm_min = 3000;  // 50 mm/s
  const Limits l = make_limits(m, false);
  Block c;
  c.kind = BlockKind::kArc;
  c.start.set_xyz({10, 0, 0});
  c.end = c.start;
  c.center = {0, 0, 0};
  c.turns = 1;
  c.feed_mm_min = 10000;
  const Segment s = make_motion_segment(c, l);
  EXPECT_NEAR(s.sweep_rad, 4 * std::numbers::pi, 1e-12);  // full circle + one extra turn
  EXPECT_NEAR(s.vb_pc, 0.05, 1e-12);                      // the slowest axis decides: Y at 50 mm/s
  Block line;
  line.kind = BlockKind::kLine;
  line.end.set_xyz({30, 40, 0});  // Y share 0.8: path ≤ 50/0.8 = 62.5 mm/s
  line.feed_mm_min = 10000;
  EXPECT_NEAR(make_motion_segment(line, l).vb_pc, 0.0625, 1e-12);
}

}  // namespace
}  // namespace cncore::planner
