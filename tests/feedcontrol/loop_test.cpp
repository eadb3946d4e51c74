// The per-cycle driver: kernel samples in, override out; no heap allocation per cycle.
#include <gtest/gtest.h>

#include <cstdlib>

#include "alloc_counter.hpp"
#include "core/error.hpp"
#include "feedcontrol/adaptive_loop.hpp"

using namespace cncore::feed;

namespace {

AdaptiveSettings settings() {
  AdaptiveSettings s;
  s.enabled = true;
  s.control_cycles = 4;
  return s;
}

}  // namespace

TEST(Loop, OnSampleMeasuresAlongThePathAndFillsTheLoadColumns) {
  // Load 0 % at 0 mm rising to 100 % at 100 mm.
  auto rec = RecordedLoad::parse("s_mm,load_pct\n0,0\n100,100\n", "load.csv");
  AdaptiveFeedLoop loop(settings(), 0.001, 200, rec);
  cncore::motion::Sample s;
  for (int n = 0; n <= 30; ++n) {
    s.t_s = n * 0.001;
    s.path_position[0] = 3.0 * n;  // 3 mm per cycle along X, then 4 mm along Y: 5 mm
    s.path_position[1] = 4.0 * n;
    loop.on_sample(s, 100);
  }
  EXPECT_NEAR(loop.path_s_mm(), 150, 1e-9);
  EXPECT_DOUBLE_EQ(s.load_pct, 100);  // held after the last row
  EXPECT_DOUBLE_EQ(s.load_target_pct, settings().target_load_pct);
}

TEST(Loop, DisabledPassesTheOperatorOverride) {
  auto rec = RecordedLoad::parse("t_s,load_pct\n0,90\n", "load.csv");
  AdaptiveSettings s = settings();
  s.enabled = false;
  AdaptiveFeedLoop loop(s, 0.001, 200, rec);
  EXPECT_DOUBLE_EQ(loop.cycle(0, 0, 100, 70), 70);
  EXPECT_DOUBLE_EQ(loop.last_load_pct(), 90);  // still measured for the trajectory
  loop.set_enabled(true);
  // Load 90 > target 60: the controller lowers the feed.
  EXPECT_LT(loop.cycle(0.001, 0, 100, 70), 70);
  loop.set_enabled(false);
  EXPECT_DOUBLE_EQ(loop.cycle(0.002, 0, 100, 70), 70);
}

TEST(Loop, ControlEveryNCyclesButIdlePassThroughAtOnce) {
  // 5 % (below lm) for 10 ms, then 90 %.
  auto rec = RecordedLoad::parse("t_s,load_pct\n0,5\n0.0099,5\n0.0100,90\n", "load.csv");
  AdaptiveFeedLoop loop(settings(), 0.001, 200, rec);   // control every 4 cycles
  EXPECT_DOUBLE_EQ(loop.cycle(0.000, 0, 0, 100), 100);  // control cycle: idle
  EXPECT_DOUBLE_EQ(loop.cycle(0.001, 0, 0, 70), 70);    // operator turns the knob: at once
  EXPECT_DOUBLE_EQ(loop.cycle(0.002, 0, 0, 70), 70);
  EXPECT_DOUBLE_EQ(loop.cycle(0.003, 0, 0, 70), 70);
  EXPECT_DOUBLE_EQ(loop.cycle(0.004, 0, 0, 70), 70);             // control cycle, still idle
  for (int n = 5; n < 12; ++n) loop.cycle(n * 0.001, 0, 0, 70);  // 90 % measured from n = 10
  // Control cycles at n = 8 (idle) and n = 12: the first active one.
  const double first = loop.cycle(0.012, 0, 0, 70);
  // e = −30, Δt = 4 ms: o = Kp·e + Ki·e·Δt + c = −30 − 0.6 + 100 = 69.4, times the operator's
  // 70 % (spec 04: the two combine).
  EXPECT_NEAR(first, 69.4 * 0.70, 1e-9);
  // The controller's output is held until its next cycle; the operator's knob acts at once.
  EXPECT_NEAR(loop.cycle(0.013, 0, 0, 70), first, 1e-12);
  EXPECT_NEAR(loop.cycle(0.014, 0, 0, 50), 69.4 * 0.50, 1e-9);
  EXPECT_NEAR(loop.cycle(0.015, 0, 0, 50), 69.4 * 0.50, 1e-9);
  // Next control cycle: I = 2·(−30·0.004) → o = −30 − 1.2 + 100 = 68.8; the controller's own
  // factor does not depend on the operator's override.
  EXPECT_NEAR(loop.cycle(0.016, 0, 0, 50), 68.8 * 0.50, 1e-9);
}

TEST(Loop, CombinedOverrideStaysWithinTheMachinesMaximum) {
  // A light cut (20 % < target 60 %) drives the controller up to its upper limit; with the
  // operator at 150 % the product is capped at the machine's 200 %.
  auto rec = RecordedLoad::parse("t_s,load_pct\n0,20\n", "load.csv");
  AdaptiveFeedLoop loop(settings(), 0.001, 200, rec);
  double out = 0;
  for (int n = 0; n < 4000; ++n) out = loop.cycle(n * 0.001, 0, 0, 150);
  EXPECT_GT(loop.controller().state().output_pct, 200.0 / 1.5);
  EXPECT_DOUBLE_EQ(out, 200);
  EXPECT_NEAR(loop.cycle(4.0, 0, 0, 50), loop.controller().state().output_pct * 0.5, 1e-9);
}

TEST(Loop, InvalidSettingsAreRejectedAtConstruction) {
  auto rec = RecordedLoad::parse("t_s,load_pct\n0,90\n", "load.csv");
  AdaptiveSettings s = settings();
  s.upper_pct = 300;  // above the machine's 200 %
  EXPECT_THROW(AdaptiveFeedLoop(s, 0.001, 200, rec), cncore::InputError);
}

TEST(Loop, NoHeapAllocationPerCycle) {
  auto rec = RecordedLoad::parse("t_s,load_pct\n0,5\n1,80\n2,20\n3,90\n", "load.csv");
  PlantSettings ps;
  ps.depth.s_mm = {0, 50, 50, 100};
  ps.depth.depth_mm = {0.5, 0.5, 2, 2};
  PlantLoad plant(ps);
  for (AntiWindup p : {AntiWindup::kNone, AntiWindup::kClamp, AntiWindup::kBackCalculation}) {
    AdaptiveSettings s = settings();
    s.antiwindup = p;
    AdaptiveFeedLoop from_file(s, 0.001, 200, rec);
    AdaptiveFeedLoop from_plant(s, 0.001, 200, plant);
    cncore::motion::Sample sample;
    const long before = cncore::testing::allocations();
    double ovr = 100;
    for (int n = 0; n < 4000; ++n) {
      sample.t_s = n * 0.001;
      sample.path_position[0] = n * 0.025;
      sample.feed_mm_min = 15 * ovr;
      ovr = from_file.on_sample(sample, 100);
      ovr = from_plant.cycle(sample.t_s, n * 0.025, 15 * ovr, 100);
    }
    EXPECT_EQ(cncore::testing::allocations() - before, 0);
  }
}
