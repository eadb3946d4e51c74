// The adaptive loop driving the real motion kernel (the way `cncore run` will wire it): one
// straight G1 through the scenario's depth profile. The kernel's speed and acceleration limits
// hold whatever the controller asks, and back-calculation still beats clamp after the jump.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "alloc_counter.hpp"
#include "feedcontrol/adaptive_loop.hpp"
#include "feedcontrol/adaptive_run.hpp"
#include "motion/kernel.hpp"
#include "scenario.hpp"

using namespace cncore;
using namespace cncore::feed;
namespace sc = cncore::feed::scenario;

namespace {

MachineConfig machine() {
  MachineConfig m;  // built-in limits: 10 000 mm/min, 2000 mm/s², 1 ms, max override 200 %
  for (std::size_t i = 0; i < 3; ++i) {
    m.axes[i].enabled = true;
    m.axes[i].min_mm = -1e6;
    m.axes[i].max_mm = 1e6;
    m.axes[i].max_speed_mm_min = 20000;
    m.axes[i].max_accel_mm_s2 = 10000;
  }
  return m;
}

struct Row {
  double t_s, s_mm, feed_mm_min, override_pct, load_pct, target_pct;
};

std::vector<Row> run_kernel(AntiWindup policy) {
  const MachineConfig m = machine();
  motion::Kernel kernel(m, motion::KernelOptions{});
  Block b;
  b.kind = BlockKind::kLine;
  b.line = 1;
  b.col = 1;
  b.end[0] = 240;
  b.feed_mm_min = 1000;
  b.path_mode = PathMode::kExactStop;
  kernel.push(b);
  kernel.end_of_program();
  PlantLoad plant(sc::plant());
  AdaptiveFeedLoop loop(sc::settings(policy), m.period_s, m.max_override_pct, plant);
  std::vector<Row> rows;
  motion::Sample s;
  while (kernel.step(s) && s.t_s < 60) {
    kernel.set_override(loop.on_sample(s, 100));
    rows.push_back({s.t_s, loop.path_s_mm(), s.feed_mm_min, loop.override_pct(), s.load_pct,
                    s.load_target_pct});
  }
  return rows;
}

double time_above_after_jump(const std::vector<Row>& rows, double period_s) {
  double t = 0;
  for (const Row& r : rows) {
    if (r.s_mm >= sc::kJumpUpMm && r.s_mm < sc::kJumpDownMm &&
        r.load_pct > r.target_pct + sc::kOverloadBandPct) {
      t += period_s;
    }
  }
  return t;
}

}  // namespace

TEST(KernelLoop, LimitsHoldAndBackCalculationBeatsClamp) {
  const MachineConfig m = machine();
  double above[3] = {};
  int i = 0;
  for (AntiWindup p : {AntiWindup::kNone, AntiWindup::kClamp, AntiWindup::kBackCalculation}) {
    const auto rows = run_kernel(p);
    ASSERT_GT(rows.size(), 1000u);
    EXPECT_NEAR(rows.back().s_mm, 240, 0.01) << antiwindup_name(p);
    double max_accel = 0;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      // Never faster than F × the highest override the controller may give.
      const double ceiling = p == AntiWindup::kNone ? m.max_override_pct : 150.0;
      EXPECT_LE(rows[k].feed_mm_min, 1000 * ceiling / 100 + 1e-6) << "t = " << rows[k].t_s;
      if (k > 0) {
        max_accel = std::max(max_accel, std::fabs(rows[k].feed_mm_min - rows[k - 1].feed_mm_min) /
                                            60.0 / m.period_s);
      }
    }
    EXPECT_LE(max_accel, m.max_accel_mm_s2 * (1 + 1e-6)) << antiwindup_name(p);
    above[i++] = time_above_after_jump(rows, m.period_s);
  }
  std::printf(
      "through the kernel, time above target+5 after the jump: none %.3f s, clamp %.3f s, "
      "back_calculation %.3f s, ratio %.3f\n",
      above[0], above[1], above[2], above[2] / above[1]);
  EXPECT_LE(above[2], 0.5 * above[1]);
}

// The motion cycle as `cncore run` drives it: Kernel::step, then the run's cycle controller
// (M52 handling + loop), then set_override. No heap allocation in any cycle; the M52 events
// reach the controller through the kernel's samples (P0 off: the operator's override).
TEST(KernelLoop, RunCycleControllerAllocatesNothingAndFollowsM52) {
  const MachineConfig m = machine();
  motion::Kernel kernel(m, motion::KernelOptions{});
  auto line = [](double x, std::uint32_t n) {
    Block b;
    b.kind = BlockKind::kLine;
    b.line = n;
    b.col = 1;
    b.end[0] = x;
    b.feed_mm_min = 1000;
    return b;
  };
  auto m52 = [](double p, std::uint32_t n) {
    Block b;
    b.kind = BlockKind::kAux;
    b.line = n;
    b.col = 1;
    b.aux_letter = 'M';
    b.aux_value = 52;
    b.aux_p = p;
    return b;
  };
  Block first = line(110, 1);
  kernel.push(first);
  Block off = m52(0, 2);
  off.start = off.end = first.end;
  kernel.push(off);
  Block second = line(175, 3);
  second.start = first.end;
  kernel.push(second);
  Block on = m52(1, 4);
  on.start = on.end = second.end;
  kernel.push(on);
  Block third = line(240, 5);
  third.start = second.end;
  kernel.push(third);
  kernel.end_of_program();
  PlantLoad plant(sc::plant());
  feed::AdaptiveCycleController ctrl(m, sc::settings(AntiWindup::kBackCalculation), plant, "test");
  motion::Sample s;
  const long before = cncore::testing::allocations();
  std::uint64_t cycles = 0, off_cycles = 0, adapted_on_heavy_cut = 0;
  double x_off = -1, x_on = -1;
  while (kernel.step(s) && s.t_s < 60) {
    const double o = ctrl.on_cycle(s, 95);
    kernel.set_override(o);
    ++cycles;
    if (s.aux_letter == 'M' && s.aux_p == 0) x_off = s.position[0];
    if (s.aux_letter == 'M' && s.aux_p == 1) x_on = s.position[0];
    if (x_off >= 0 && x_on < 0) {
      EXPECT_EQ(o, 95) << "t = " << s.t_s;
      ++off_cycles;
    }
    if (x_on >= 0 && s.position[0] < 220 && o != 95) ++adapted_on_heavy_cut;
  }
  const long allocations = cncore::testing::allocations() - before;
  EXPECT_GT(before, 0);  // the counter does count (the set-up above allocated)
  EXPECT_EQ(allocations, 0) << "over " << cycles << " cycles";
  EXPECT_NEAR(x_off, 110, 0.05);
  EXPECT_NEAR(x_on, 175, 0.05);
  EXPECT_GT(off_cycles, 3000u);
  EXPECT_GT(adapted_on_heavy_cut, 1000u);
  EXPECT_EQ(ctrl.switch_count(), 2u);
}
