// The PID and its three anti-wind-up policies, one control cycle at a time, against values
// worked out by hand from o = Kp·e + Ki·I + Kd·de/dt + c and I += e·Δt.
#include <gtest/gtest.h>
#include <rapidcheck.h>

#include <cmath>
#include <limits>
#include <vector>

#include "feedcontrol/adaptive.hpp"

using namespace cncore::feed;

namespace {

constexpr double kDt = 0.01;

AdaptiveSettings base(AntiWindup policy) {
  AdaptiveSettings s;
  s.target_load_pct = 60;
  s.kp = 1;
  s.ki = 10;
  s.kd = 0;
  s.constant_pct = 100;
  s.threshold_pct = 10;
  s.upper_pct = 150;
  s.lower_pct = 20;
  s.antiwindup = policy;
  return s;
}

}  // namespace

TEST(Controller, ProportionalTermByHand) {
  AdaptiveSettings s = base(AntiWindup::kClamp);
  s.kp = 2;
  s.ki = 0;
  AdaptiveController c(s, kDt, 200);
  EXPECT_DOUBLE_EQ(c.update(50, 100), 120);  // e = 10: 2·10 + 100
  EXPECT_DOUBLE_EQ(c.update(70, 100), 80);   // e = −10
  EXPECT_FALSE(c.state().limited);
}

TEST(Controller, IntegralTermByHand) {
  AdaptiveSettings s = base(AntiWindup::kClamp);
  s.kp = 0;
  s.ki = 1;
  AdaptiveController c(s, kDt, 200);
  // e = 10 each cycle: I = 0.1·n, o = 100 + 0.1·n.
  for (int n = 1; n <= 50; ++n) {
    EXPECT_NEAR(c.update(50, 100), 100 + 0.1 * n, 1e-9) << n;
  }
  EXPECT_NEAR(c.state().integral, 5.0, 1e-9);
}

TEST(Controller, DerivativeTermByHand) {
  AdaptiveSettings s = base(AntiWindup::kClamp);
  s.kp = 0;
  s.ki = 0;
  s.kd = 0.01;
  AdaptiveController c(s, kDt, 200);
  EXPECT_DOUBLE_EQ(c.update(50, 100), 100);  // first cycle: no derivative
  // e 10 → 5: de/dt = −500 /s, Kd·de/dt = −5.
  EXPECT_NEAR(c.update(55, 100), 95, 1e-9);
  EXPECT_NEAR(c.update(55, 100), 100, 1e-9);
}

TEST(Controller, BackCalculationHoldsTheIntegralAndReleasesAtOnce) {
  AdaptiveController c(base(AntiWindup::kBackCalculation), kDt, 200);
  // e = 50: I = 0.5 → o = 50 + 5 + 100 = 155 > 150 → out 150, I = (150 − 50 − 100)/10 = 0.
  for (int n = 0; n < 100; ++n) {
    EXPECT_DOUBLE_EQ(c.update(10, 100), 150);
    EXPECT_TRUE(c.state().limited);
    EXPECT_NEAR(c.state().integral, 0, 1e-12);
    // Formula 4: the unclamped formula gives exactly the limit.
    EXPECT_NEAR(1 * c.state().error_pct + c.state().integral_term_pct + 100, 150, 1e-9);
  }
  // Load jumps to 90 (e = −30): I = −0.3, o = −30 − 3 + 100 = 67 at the very next cycle.
  EXPECT_NEAR(c.update(90, 100), 67, 1e-9);
  EXPECT_FALSE(c.state().limited);
}

TEST(Controller, ClampWindsUpAndSticksAtTheLimit) {
  AdaptiveController c(base(AntiWindup::kClamp), kDt, 200);
  // e = 50 for 100 cycles: I = 50·0.01·100 = 50, the output held at 150.
  for (int n = 0; n < 100; ++n) EXPECT_DOUBLE_EQ(c.update(10, 100), 150);
  EXPECT_NEAR(c.state().integral, 50, 1e-9);
  // Load 90 (e = −30): I = 50 − 0.3·k; o = −30 + 10·I + 100 stays > 150 while I > 8,
  // i.e. 570 − 3k ≥ 150 for k ≤ 140 cycles (1.4 s) before the feed leaves the limit.
  int stuck = 0;
  while (c.update(90, 100) > 149.5 && stuck < 1000) ++stuck;
  EXPECT_EQ(stuck, 140);
}

TEST(Controller, BackCalculationAtTheLowerLimit) {
  AdaptiveController c(base(AntiWindup::kBackCalculation), kDt, 200);
  // Load 160 (e = −100): I = −1 → o = −100 − 10 + 100 = −10 < 20 → out 20,
  // I = (20 + 100 − 100)/10 = 2.
  EXPECT_DOUBLE_EQ(c.update(160, 100), 20);
  EXPECT_NEAR(c.state().integral, 2, 1e-12);
  EXPECT_DOUBLE_EQ(c.update(160, 100), 20);
  EXPECT_NEAR(c.state().integral, 2, 1e-12);
  // Back at target (e = 0): I = 2 → o = 0 + 20 + 100 = 120.
  EXPECT_NEAR(c.update(60, 100), 120, 1e-9);
}

TEST(Controller, NoneIgnoresTheAdaptiveLimitsButNotTheMachine) {
  AdaptiveController c(base(AntiWindup::kNone), kDt, 250);
  EXPECT_DOUBLE_EQ(c.output_max_pct(), 250);
  EXPECT_DOUBLE_EQ(c.output_min_pct(), 0);
  // e = 50: o = 50 + 5 + 100 = 155, above upper_pct = 150 and still passed.
  EXPECT_NEAR(c.update(10, 100), 155, 1e-9);
  EXPECT_FALSE(c.state().limited);
  for (int n = 0; n < 100; ++n) c.update(10, 100);
  EXPECT_DOUBLE_EQ(c.update(10, 100), 250);
  EXPECT_TRUE(c.state().limited);
  // Load far above target: never a negative override.
  for (int n = 0; n < 1000; ++n) EXPECT_GE(c.update(400, 100), 0);
}

TEST(Controller, BelowThresholdPassesTheOperatorOverride) {
  for (AntiWindup p : {AntiWindup::kNone, AntiWindup::kClamp, AntiWindup::kBackCalculation}) {
    AdaptiveController c(base(p), kDt, 200);
    c.update(40, 100);  // cutting: builds some state
    EXPECT_DOUBLE_EQ(c.update(9.99, 73), 73);
    EXPECT_FALSE(c.state().active);
    EXPECT_DOUBLE_EQ(c.update(0, 5), 5);               // below the lower limit too: unchanged
    EXPECT_DOUBLE_EQ(c.update(std::nan(""), 88), 88);  // no reading: not cutting
    EXPECT_TRUE(c.update(10, 100) != 73);              // at lm the controller runs again
    EXPECT_TRUE(c.state().active);
  }
}

TEST(Controller, UpdateIsNoexcept) {
  AdaptiveController c(base(AntiWindup::kBackCalculation), kDt, 200);
  static_assert(noexcept(c.update(1.0, 1.0)));
}

// Whatever the load sequence, an active clamp/back-calculation controller stays within
// [lower, upper], and an idle one returns the operator's override.
TEST(Controller, OutputAlwaysWithinLimits) {
  const bool ok = rc::check([](bool back_calc, double kp, double ki, double kd) {
    AdaptiveSettings s = base(back_calc ? AntiWindup::kBackCalculation : AntiWindup::kClamp);
    s.kp = std::fabs(std::fmod(kp, 10.0));
    s.ki = 0.01 + std::fabs(std::fmod(ki, 50.0));
    s.kd = std::fabs(std::fmod(kd, 0.1));
    RC_PRE(std::isfinite(s.kp) && std::isfinite(s.ki) && std::isfinite(s.kd));
    AdaptiveController c(s, kDt, 200);
    const auto loads = *rc::gen::container<std::vector<int>>(rc::gen::inRange(0, 3000));
    for (int tenth : loads) {
      const double load = tenth / 10.0;
      const double out = c.update(load, 42);
      if (load < s.threshold_pct) {
        RC_ASSERT(out == 42.0);
      } else {
        RC_ASSERT(out >= s.lower_pct);
        RC_ASSERT(out <= s.upper_pct);
      }
    }
  });
  EXPECT_TRUE(ok);
}
