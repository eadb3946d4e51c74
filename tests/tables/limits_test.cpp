// Per-axis limits checked before running, with the rows responsible; slow_to_fit.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/error.hpp"
#include "helpers.hpp"

namespace cncore::tables::test {
namespace {

using Sev = Diagnostic::Severity;

std::vector<Diagnostic> of(const TablePlan& p, Sev sev) {
  std::vector<Diagnostic> out;
  for (const auto& d : p.diagnostics) {
    if (d.severity == sev) out.push_back(d);
  }
  return out;
}

// Row 5 (L1500 X200) asks for 100 mm in 500 ms = 12 000 mm/min > 10 000 mm/min.
const char* kTooFast = "REF TIME\nAXES X\nCUBIC\nL0 X0\nL1000 X100\n   L1500 X200\nL3000 X200\n";
const char* kTooFastLinear = "REF TIME\nAXES X\nL1000 X100\n   L1500 X200\nL3000 X200\n";

TEST(Limits, SpeedViolationNamesTheRowAndRefusesTheRun) {
  std::vector<Table> t{parse_table(kTooFastLinear, "fast.tbl")};
  TablePlan plan = plan_tables(t, stiff_machine(), {});  // the speed alone
  auto errors = of(plan, Sev::kError);
  ASSERT_EQ(errors.size(), 1U);
  EXPECT_EQ(errors[0].file, "fast.tbl");
  EXPECT_EQ(errors[0].line, 4U);
  EXPECT_EQ(errors[0].col, 4U);
  EXPECT_NE(errors[0].message.find("X speed 12000 mm/min"), std::string::npos) << errors[0].message;
  EXPECT_NE(errors[0].formatted().find("fast.tbl:4:4: error: "), std::string::npos);
  EXPECT_TRUE(plan.has_errors());
  bool called = false;
  try {
    run_tables(plan, [&](const TableSample&) { called = true; });
    FAIL() << "run_tables accepted a plan with errors";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 4U);
  }
  EXPECT_FALSE(called);
}

TEST(Limits, LinearVelocityStepsAreErrorsAtTheirRowsAndRefuseTheRun) {
  // 100 mm/s appears in one 1 ms cycle at L0 (line 3) and vanishes at L1000 (line 4):
  // 100 000 mm/s² > 2 000 mm/s².
  std::vector<Table> t{parse_table("REF TIME\nAXES X\nL0 X0\nL1000 X100\nL2000 X100\n", "s.tbl")};
  TablePlan plan = plan_tables(t, test_machine(), {});
  EXPECT_TRUE(plan.has_errors());
  auto e = of(plan, Sev::kError);
  ASSERT_EQ(e.size(), 2U);  // the start of the move (line 3) and its end (line 4)
  EXPECT_EQ(e[0].line, 3U);
  EXPECT_EQ(e[1].line, 4U);
  EXPECT_NE(e[0].message.find("100000 mm/s²"), std::string::npos) << e[0].message;
  // What would make it fit: 100 mm/s / 2000 mm/s² = 50 ms of post filter.
  EXPECT_NE(e[0].message.find("post_filter_s >= 0.05 s"), std::string::npos) << e[0].message;
  EXPECT_THROW(run_tables(plan, [](const TableSample&) {}), InputError);
}

TEST(Limits, LinearStepErrorsAreListedForFiveRowsThenCounted) {
  // A zig-zag of 12 rows: every control point steps the velocity.
  std::string text = "REF TIME\nAXES X\n";
  for (int i = 1; i <= 12; ++i) {
    text += "L" + std::to_string(100 * i) + " X" + std::to_string(i % 2) + "\n";
  }
  std::vector<Table> t{parse_table(text, "z.tbl")};
  TablePlan plan = plan_tables(t, test_machine(), {});
  auto e = of(plan, Sev::kError);
  ASSERT_EQ(e.size(), 6U);
  EXPECT_EQ(e[0].line, 3U);
  EXPECT_EQ(e[4].line, 7U);
  EXPECT_EQ(e[5].line, 1U);
  EXPECT_NE(e[5].message.find("at 7 more control points"), std::string::npos) << e[5].message;
}

// Largest finite-difference acceleration of `axis` over the run, units/s².
double measured_accel(const std::vector<TableSample>& s, std::size_t axis, double period_s) {
  double amax = 0;
  for (std::size_t i = 2; i < s.size(); ++i) {
    amax =
        std::max(amax, std::abs(fd_velocity(s, axis, i) - fd_velocity(s, axis, i - 1)) / period_s);
  }
  return amax;
}

TEST(Limits, PostFilterSpreadsLinearStepsWithinTheAxisLimit) {
  // Steps of 100 mm/s: a 50 ms moving average makes them ramps of 2000 mm/s².
  const char* text = "REF TIME\nAXES X\nL0 X0\nL1000 X100\nL2000 X100\n";
  MachineConfig m = test_machine();
  m.post_filter_s = 0.04;  // 2500 mm/s²: still refused, naming the rows
  EXPECT_TRUE(plan_tables({parse_table(text, "s.tbl")}, m, {}).has_errors());
  m.post_filter_s = 0.05;
  TableRun r = run_texts({text}, {}, m);
  EXPECT_FALSE(r.plan.has_errors());
  EXPECT_TRUE(of(r.plan, Sev::kWarning).empty());
  EXPECT_LE(measured_accel(r.samples, kX, m.period_s), 2000 * 1.001);
  EXPECT_GT(measured_accel(r.samples, kX, m.period_s), 2000 * 0.99);  // the ramp is 50 ms, no more
  // The filter settles on the end point: 49 cycles after the table's last control point.
  EXPECT_NEAR(r.samples.back().position[kX], 100.0, 1e-9);
  EXPECT_NEAR(r.samples.back().t_s, 2.049, 1e-9);
  // Half-way through the ramp the axis lags the table by half the window: 25 ms at 100 mm/s.
  EXPECT_NEAR(time_reaching(r.samples, kX, 50.0), 0.5 + 0.0245, 0.0011);
}

TEST(Limits, SlowToFitCoversLinearSteps) {
  // 100 000 mm/s² within one cycle: the reference runs 50 times slower (a scales with 1/k here:
  // the step stays one cycle long).
  RunOptions o;
  o.settings.slow_to_fit = true;
  TableRun r = run_texts({"REF TIME\nAXES X\nL0 X0\nL1000 X100\nL2000 X100\n"}, o, test_machine());
  EXPECT_NEAR(r.plan.slow_factor, 50.0, 1e-6);
  EXPECT_FALSE(r.plan.has_errors());
  EXPECT_LE(measured_accel(r.samples, kX, 0.001), 2000 * 1.001);
  EXPECT_NEAR(r.samples.back().t_s, 2.0 * 50.0, 0.0011);
}

TEST(Limits, CubicAccelerationViolationIsAnError) {
  // 0 → 10 mm in 100 ms, smooth: peak acceleration 6·10/0.1² = 6000 mm/s² (zero end tangents).
  std::vector<Table> t{parse_table("REF TIME\nAXES Z\nCUBIC\nL0 Z0\nL100 Z10\n", "a.tbl")};
  TablePlan plan = plan_tables(t, test_machine(), {});
  auto errors = of(plan, Sev::kError);
  ASSERT_EQ(errors.size(), 1U);
  EXPECT_EQ(errors[0].line, 5U);
  EXPECT_NE(errors[0].message.find("Z acceleration 6000 mm/s²"), std::string::npos)
      << errors[0].message;
}

TEST(Limits, SlowToFitRunsTheReferenceSlowerAndStaysWithinLimits) {
  RunOptions o;
  o.settings.slow_to_fit = true;
  TableRun r = run_texts({kTooFast}, o, test_machine());
  // The cubic segment L1000→L1500 needs the largest factor; after slowing, the measured speed
  // and acceleration stay within the limits.
  EXPECT_GT(r.plan.slow_factor, 1.2);
  EXPECT_FALSE(r.plan.has_errors());
  double vmax = 0, amax = 0;
  for (std::size_t i = 2; i < r.samples.size(); ++i) {
    double v1 = fd_velocity(r.samples, kX, i), v0 = fd_velocity(r.samples, kX, i - 1);
    vmax = std::max(vmax, std::abs(v1));
    amax = std::max(amax, std::abs(v1 - v0) / 0.001);
  }
  EXPECT_LE(vmax * 60, 10000 * 1.001);
  EXPECT_LE(amax, 2000 * 1.01);
  EXPECT_GT(vmax * 60, 10000 * 0.95);  // …and is not slowed more than needed
  // The whole cycle takes slow_factor times as long (3000 ms at full rate).
  EXPECT_NEAR(r.samples.back().t_s, 3.0 * r.plan.slow_factor, 0.0011);
  // The violations stay visible as warnings naming the rows.
  auto w = of(r.plan, Sev::kWarning);
  EXPECT_TRUE(std::any_of(w.begin(), w.end(), [](auto& d) { return d.line == 6; }));
}

TEST(Limits, TravelViolationIsAnErrorEvenWithSlowToFit) {
  RunOptions o;
  o.settings.slow_to_fit = true;
  std::vector<Table> t{parse_table("REF TIME\nAXES X\nL1000 X100\nL5000 X1200\n", "tr.tbl")};
  TablePlan plan = plan_tables(t, test_machine(), o);
  auto errors = of(plan, Sev::kError);
  ASSERT_EQ(errors.size(), 1U);
  EXPECT_EQ(errors[0].line, 4U);
  EXPECT_NE(errors[0].message.find("travel"), std::string::npos);
}

TEST(Limits, MasterAxisTooFast) {
  RunOptions o;
  o.reference = ReferenceSource::master_axis(0, 20000);
  std::vector<Table> t{parse_table("REF AXIS Y\nAXES X\nL0 X0\nL50 X1\n", "m.tbl")};
  TablePlan plan = plan_tables(t, stiff_machine(), o);
  auto errors = of(plan, Sev::kError);
  ASSERT_EQ(errors.size(), 1U);
  EXPECT_EQ(errors[0].line, 1U);
}

TEST(Limits, SignalChangedDuringTheRunIsCheckedWhenTheRowIsRead) {
  // At t = 0 R5 = 0 and the plan is clean; at 0.5 s R5 becomes -600, so the row L2000 read at
  // 1.0 s lands at 1400 ms: 100 mm in 400 ms = 15 000 mm/min > 10 000 mm/min.
  RunOptions o;
  o.values.signals[5] = 0;
  o.values.signal_changes.push_back({0.5, 5, -600});
  TableRun r = run_texts({"REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT=R5\nL3000 X300\n"}, o);
  EXPECT_FALSE(r.plan.has_errors());
  ASSERT_EQ(r.summary.warnings.size(), 1U);
  EXPECT_NE(r.summary.warnings[0].find("t1.tbl:4:1: warning:"), std::string::npos)
      << r.summary.warnings[0];
  EXPECT_NE(r.summary.warnings[0].find("X 15000 mm/min"), std::string::npos)
      << r.summary.warnings[0];
  // And the motion did follow the new value: X = 200 at 1.4 s.
  EXPECT_NEAR(time_reaching(r.samples, kX, 200), 1.4, 0.0005);
}

TEST(Limits, DefaultReferenceFollowsTheTableKind) {
  MachineConfig m = test_machine();
  m.start_position[kY] = 12;
  Table time = parse_table("REF TIME\nAXES X\nL10 X1\n", "a.tbl");
  Table spin = parse_table("REF SPINDLE\nAXES X\nL10 X1\n", "b.tbl");
  Table axis = parse_table("\nREF AXIS Y\nAXES X\nL10 X1\n", "c.tbl");
  EXPECT_DOUBLE_EQ(default_reference(time, m, 0, 0).rate_per_s, 1000);
  EXPECT_DOUBLE_EQ(default_reference(spin, m, 100, 0).rate_per_s, 600);  // 100 rpm = 600 deg/s
  ReferenceSource y = default_reference(axis, m, 0, 1200);
  EXPECT_DOUBLE_EQ(y.start, 12);
  EXPECT_DOUBLE_EQ(y.rate_per_s, 20);
  EXPECT_THROW(default_reference(spin, m, 0, 0), InputError);
  try {
    default_reference(axis, m, 100, 0);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2U);
  }
}

}  // namespace
}  // namespace cncore::tables::test
