// The seed's three figures as measurements on the closed loop (plant + controller + feed axis),
// computed from the recorded trace: depth profile air | 1.0 | 0.5 | 2.0 (jump up at 120 mm) |
// 0.5 | air, F 1000 mm/min, target 60 %, upper limit 150 %, see scenario.hpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <new>

#include "feedcontrol/adaptive_loop.hpp"
#include "scenario.hpp"

using namespace cncore::feed;
namespace sc = cncore::feed::scenario;

namespace {

const double kPeriod = sc::options().period_s;
auto always = [](const TraceRow&) { return true; };
auto load_of = [](const TraceRow& r) { return r.load_pct; };
auto override_of = [](const TraceRow& r) { return r.override_pct; };
auto iterm_of = [](const TraceRow& r) { return r.integral_term_pct; };
auto is_limited = [](const TraceRow& r) { return r.limited; };

// The light cut before the jump, from 10 mm after its start (the transient of the step down
// from 1.0 mm is over) to the jump.
constexpr double kLightFrom = sc::kLightStartMm + 10;

// Seconds from the jump until the override first drops below `below_pct`.
double time_at_limit_after_jump(const std::vector<TraceRow>& trace, double below_pct) {
  double t0 = -1;
  for (const TraceRow& r : trace) {
    if (r.s_mm < sc::kJumpUpMm) continue;
    if (t0 < 0) t0 = r.t_s;
    if (r.override_pct < below_pct) return r.t_s - t0;
  }
  return INFINITY;
}

}  // namespace

TEST(ClosedLoop, NoLimitFeedPassesTheUpperLimitAndLoadOvershoots) {
  const auto none = sc::run(AntiWindup::kNone);
  const auto back = sc::run(AntiWindup::kBackCalculation);
  const double upper = sc::settings(AntiWindup::kNone).upper_pct;
  // Light cut: the target needs (60 − 5)/(0.04·0.5)/1000 = 275 % override.
  const auto ovr = sc::range_of(none, kLightFrom, sc::kJumpUpMm, override_of, always);
  EXPECT_GT(ovr.max, upper + 75);
  // Entering the 2 mm cut that fast overshoots the target load.
  const double peak_none = sc::range_of(none, sc::kJumpUpMm, sc::kJumpDownMm, load_of, always).max;
  const double peak_back = sc::range_of(back, sc::kJumpUpMm, sc::kJumpDownMm, load_of, always).max;
  EXPECT_GT(peak_none, 2 * sc::settings(AntiWindup::kNone).target_load_pct);
  EXPECT_GT(peak_none, peak_back + 30);
  // And the load does follow the target on the cuts it can reach: last 20 mm of the 2 mm cut.
  const auto settled = sc::range_of(none, sc::kJumpDownMm - 20, sc::kJumpDownMm, load_of, always);
  EXPECT_GT(settled.min, 55);
  EXPECT_LT(settled.max, 65);
}

TEST(ClosedLoop, ClampWindsUpAndTheLoadStaysAboveTarget) {
  const auto clamp = sc::run(AntiWindup::kClamp);
  const double upper = sc::settings(AntiWindup::kClamp).upper_pct;
  // The output is held at the limit on the whole light cut, and the integral keeps growing:
  // e ≈ 60 − (5 + 0.04·1500·0.5) = 25 % for ~2.2 s → Ki·I grows by ~550 %.
  const auto limited_ovr = sc::range_of(clamp, kLightFrom, sc::kJumpUpMm, override_of, always);
  EXPECT_DOUBLE_EQ(limited_ovr.min, upper);
  EXPECT_DOUBLE_EQ(limited_ovr.max, upper);
  const auto iterm = sc::range_of(clamp, kLightFrom, sc::kJumpUpMm, iterm_of, is_limited);
  EXPECT_GT(iterm.span(), 300);
  // Monotonic growth while held (the error stays positive on the light cut).
  double previous = -INFINITY;
  for (const TraceRow& r : clamp) {
    if (r.s_mm < kLightFrom || r.s_mm >= sc::kJumpUpMm) continue;
    EXPECT_GE(r.integral_term_pct, previous) << "s = " << r.s_mm;
    previous = r.integral_term_pct;
  }
  // After the jump the feed sticks at the limit while the load is far above target.
  EXPECT_GT(time_at_limit_after_jump(clamp, upper - 1), 0.5);
  EXPECT_GT(sc::time_above_s(clamp, sc::kJumpUpMm, sc::kJumpDownMm, kPeriod), 1.0);
}

TEST(ClosedLoop, BackCalculationKeepsTheIntegralAndHalvesTheOverload) {
  const auto clamp = sc::run(AntiWindup::kClamp);
  const auto back = sc::run(AntiWindup::kBackCalculation);
  const AdaptiveSettings s = sc::settings(AntiWindup::kBackCalculation);
  // While limited, Ki·I = upper − c − Kp·e (Formula 4): it moves only with the measurement
  // noise, never more than Kp × the spread of the load, and far less than under clamp.
  const auto rows = sc::range_of(back, kLightFrom, sc::kJumpUpMm, iterm_of, is_limited);
  const auto loads = sc::range_of(back, kLightFrom, sc::kJumpUpMm, load_of, always);
  ASSERT_TRUE(std::isfinite(rows.span()));
  EXPECT_LE(rows.span(), s.kp * loads.span() + 1e-9);
  EXPECT_LT(rows.span(), 5);
  // The feed drops right after the jump: within 2 control cycles + the plant's lag.
  EXPECT_LT(time_at_limit_after_jump(back, s.upper_pct - 1),
            2 * s.control_cycles * kPeriod + sc::plant().time_constant_s);
  // Time with the load above target (+5 %) after the jump: at most half of clamp's.
  const double above_clamp = sc::time_above_s(clamp, sc::kJumpUpMm, sc::kJumpDownMm, kPeriod);
  const double above_back = sc::time_above_s(back, sc::kJumpUpMm, sc::kJumpDownMm, kPeriod);
  std::printf(
      "time above target+5 after the jump: clamp %.3f s, back_calculation %.3f s, "
      "ratio %.3f\n",
      above_clamp, above_back, above_back / above_clamp);
  EXPECT_GT(above_back, 0);  // the jump does overload briefly: the measurement is not empty
  EXPECT_LE(above_back, 0.5 * above_clamp);
}

TEST(ClosedLoop, BelowThresholdTheOverrideIsTheOperators) {
  StraightPathOptions o = sc::options();
  o.operator_override_pct = 80;
  for (AntiWindup p : {AntiWindup::kNone, AntiWindup::kClamp, AntiWindup::kBackCalculation}) {
    const auto trace = run_straight_path(sc::settings(p), sc::plant(), o);
    int idle_rows = 0;
    for (const TraceRow& r : trace) {
      if (!r.active) {
        ++idle_rows;
        EXPECT_EQ(r.override_pct, 80) << "t = " << r.t_s;
      }
      // In the air (and the lag decayed) the controller is idle.
      if (r.s_mm < 10 || r.s_mm > 230) {
        EXPECT_FALSE(r.active) << "s = " << r.s_mm;
      }
    }
    EXPECT_GT(idle_rows, 500);
  }
}

TEST(ClosedLoop, OverrideChangesOnlyAtControlCycles) {
  const auto trace = sc::run(AntiWindup::kBackCalculation);
  const std::uint32_t every = sc::settings(AntiWindup::kBackCalculation).control_cycles;
  int changes = 0;
  for (std::size_t i = 1; i < trace.size(); ++i) {
    if (trace[i].override_pct != trace[i - 1].override_pct) {
      ++changes;
      EXPECT_EQ(i % every, 0u) << "cycle " << i;
    }
  }
  EXPECT_GT(changes, 100);
}

TEST(ClosedLoop, FeedRespectsTheBenchAcceleration) {
  const auto trace = sc::run(AntiWindup::kNone);
  const double dv = sc::options().max_accel_mm_s2 * kPeriod * 60;
  for (std::size_t i = 1; i < trace.size(); ++i) {
    EXPECT_LE(std::fabs(trace[i].feed_mm_min - trace[i - 1].feed_mm_min), dv + 1e-9);
  }
}
