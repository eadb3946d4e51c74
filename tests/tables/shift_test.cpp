// The seed's figures, measured on the produced per-cycle positions.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "helpers.hpp"

namespace cncore::tables::test {
namespace {

constexpr double kCycle = 0.001;

std::string read_example(const std::string& name) {
  std::ifstream in(std::string(CNCORE_TABLES_EXAMPLES_DIR) + "/" + name);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Times at which X reaches 100, 200, 300, 400.
std::vector<double> times_at_points(const TableRun& r) {
  std::vector<double> t;
  for (double x : {100.0, 200.0, 300.0, 400.0}) t.push_back(time_reaching(r.samples, kX, x));
  return t;
}

void expect_times(const std::vector<double>& got, const std::vector<double>& want_ms) {
  ASSERT_EQ(got.size(), want_ms.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_NEAR(got[i], want_ms[i] / 1000.0, kCycle / 2) << "point " << i;
  }
}

const char* kFig1Plain =
    "REF TIME\nAXES X\nL1000 X100.0\nL2000 X200.0\nL3000 X300.0\nL4000 X400.0\n";

TEST(SeedFigures, Fig1WithoutShiftReachesPointsAtWrittenTimes) {
  TableRun r = run_texts({kFig1Plain});
  expect_times(times_at_points(r), {1000, 2000, 3000, 4000});
  EXPECT_NEAR(r.samples.back().t_s, 4.0, 1e-9);
}

TEST(SeedFigures, Fig1Sft200KeepsTheGaps) {
  TableRun r = run_texts({read_example("fig1-shift.tbl")});
  expect_times(times_at_points(r), {1000, 1800, 2800, 3800});
  // The run ends at the last point, 3800 ms.
  EXPECT_NEAR(r.samples.back().t_s, 3.8, 1e-9);
  EXPECT_DOUBLE_EQ(r.samples.back().position[kX], 400.0);
  // Gaps after the shifted row keep the written 1000 ms: 100 mm per 1000 ms = 100 mm/s; the
  // shifted segment itself is 100 mm in 800 ms = 125 mm/s.
  auto v_at = [&](double t) {
    auto i = static_cast<std::size_t>(std::lround(t / kCycle));
    return fd_velocity(r.samples, kX, i);
  };
  EXPECT_NEAR(v_at(1.4), 125.0, 1e-6);
  EXPECT_NEAR(v_at(2.3), 100.0, 1e-6);
  EXPECT_NEAR(v_at(3.3), 100.0, 1e-6);
}

// Fig. 2C moves 100 mm in 500 ms (12 000 mm/min): more than the test machine's 10 000 mm/min.
MachineConfig fast_machine() {
  MachineConfig m = stiff_machine();
  m.axes[kX].max_speed_mm_min = 15000;
  return m;
}

TEST(SeedFigures, Fig2cExceedsA10000MmMinAxisAtTheShiftedRow) {
  std::vector<Table> t{parse_table(read_example("fig2c-cancel.tbl"), "fig2c-cancel.tbl")};
  TablePlan plan = plan_tables(t, stiff_machine(), {});
  ASSERT_TRUE(plan.has_errors());
  EXPECT_EQ(plan.diagnostics.front().line, 7U);  // L2000 X200.0 SFT-500
}

TEST(SeedFigures, Fig2cClearMode) {
  RunOptions o;
  o.settings.cancel_mode = CancelMode::kClear;
  TableRun r = run_texts({read_example("fig2c-cancel.tbl")}, o, fast_machine());
  expect_times(times_at_points(r), {1000, 1500, 3000, 4000});
}

TEST(SeedFigures, Fig2cRebaseMode) {
  RunOptions o;
  o.settings.cancel_mode = CancelMode::kRebase;
  TableRun r = run_texts({read_example("fig2c-cancel.tbl")}, o, fast_machine());
  expect_times(times_at_points(r), {1000, 1500, 2500, 3500});
  EXPECT_NEAR(r.samples.back().t_s, 3.5, 1e-9);
}

TEST(SeedFigures, TwoShiftsAccumulate) {
  TableRun r = run_texts(
      {"REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT-200\nL3000 X300 SFT-100\nL4000 X400\n"});
  expect_times(times_at_points(r), {1000, 1800, 2700, 3700});
}

TEST(SeedFigures, ShiftAfterCancelStartsFromZeroInClearMode) {
  TableRun r =
      run_texts({"REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT-200\nL3000 X300 SFTCAN\n"
                 "L4000 X400 SFT-100\n"});
  expect_times(times_at_points(r), {1000, 1800, 3000, 3900});
}

const char* kIndirect = "REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT=%s\nL3000 X300\nL4000 X400\n";

std::string indirect(const std::string& addr) {
  std::string s = kIndirect;
  s.replace(s.find("%s"), 2, addr);
  return s;
}

TEST(IndirectAmount, Parameter) {
  RunOptions o;
  o.values.params[12] = -200;
  expect_times(times_at_points(run_texts({indirect("P12")}, o)), {1000, 1800, 2800, 3800});
}

TEST(IndirectAmount, MacroVariable) {
  RunOptions o;
  o.values.macros[501] = -300;
  expect_times(times_at_points(run_texts({indirect("#501")}, o)), {1000, 1700, 2700, 3700});
}

TEST(IndirectAmount, Signal) {
  RunOptions o;
  o.values.signals[1001] = 250;  // a later point: positive shifts delay
  expect_times(times_at_points(run_texts({indirect("R1001")}, o)), {1000, 2250, 3250, 4250});
}

TEST(IndirectAmount, SignalChangedBeforeTheRowIsReadApplies) {
  // The row L2000 is read when the segment ending at it starts (t = 1.0 s); a change at 0.5 s
  // is seen.
  RunOptions o;
  o.values.signals[1001] = 0;
  o.values.signal_changes.push_back({0.5, 1001, -200});
  TableRun r = run_texts({indirect("R1001")}, o);
  expect_times(times_at_points(r), {1000, 1800, 2800, 3800});
  // The plan (values at t = 0) still shows the unshifted table.
  EXPECT_DOUBLE_EQ(r.plan.effective[0][2].ref, 2000);
}

TEST(IndirectAmount, SignalChangedAfterTheRowIsReadDoesNot) {
  RunOptions o;
  o.values.signals[1001] = 0;
  o.values.signal_changes.push_back({1.2, 1001, -200});
  expect_times(times_at_points(run_texts({indirect("R1001")}, o)), {1000, 2000, 3000, 4000});
}

// Fig. 6: X and Z tables of an L-shaped move (Z down, then X across), overlapped by shifts.
struct Fig6 {
  double x_done_s;   // X reaches 100 (end of the L move)
  double end_s;      // last sample (end of the cycle)
  double corner_mm;  // closest approach to the sharp corner (X0, Z-100)
  double z_start_s;  // Z leaves 0
  double x_start_s;  // X leaves 0
  std::vector<MEvent> events;
  std::vector<double> event_t;
};

Fig6 run_fig6(double v501, double v502, double v503) {
  RunOptions o;
  o.values.macros = {{501, v501}, {502, v502}, {503, v503}};
  TableRun r = run_texts({read_example("fig6-z.tbl"), read_example("fig6-x.tbl")}, o);
  Fig6 f{};
  f.x_done_s = time_reaching(r.samples, kX, 100.0);
  f.end_s = r.samples.back().t_s;
  f.corner_mm = 1e9;
  f.z_start_s = NAN;
  f.x_start_s = NAN;
  for (const auto& s : r.samples) {
    f.corner_mm = std::min(f.corner_mm, std::hypot(s.position[kX], s.position[kZ] + 100.0));
    if (std::isnan(f.z_start_s) && s.position[kZ] < -1e-9) f.z_start_s = s.t_s;
    if (std::isnan(f.x_start_s) && s.position[kX] > 1e-9) f.x_start_s = s.t_s;
    for (const auto& e : s.m_codes) {
      f.events.push_back(e);
      f.event_t.push_back(s.t_s);
    }
  }
  return f;
}

TEST(SeedFigures, Fig6OverlapRoundsTheCornerAndEndsEarlier) {
  Fig6 base = run_fig6(0, 0, 0);  // Fig. 5: no overlap
  Fig6 lap = run_fig6(-200, -400, -200);

  // Without shifts: Z moves 1.0..2.0 s, X 2.0..3.0 s, the cycle ends at 4.0 s, and the path
  // goes through the corner.
  EXPECT_NEAR(base.z_start_s, 1.001, 1e-9);
  EXPECT_NEAR(base.x_start_s, 2.001, 1e-9);
  EXPECT_NEAR(base.x_done_s, 3.0, 1e-9);
  EXPECT_NEAR(base.end_s, 4.0, 1e-9);
  EXPECT_LT(base.corner_mm, 1e-9);

  // With #501 = -200, #502 = -400, #503 = -200: Z moves 0.8..1.8 s, X 1.6..2.6 s (they overlap
  // for 200 ms), the move is done 400 ms earlier and so is the cycle (L3600 instead of L4000).
  EXPECT_NEAR(lap.z_start_s, 0.801, 1e-9);
  EXPECT_NEAR(lap.x_start_s, 1.601, 1e-9);
  EXPECT_NEAR(base.x_done_s - lap.x_done_s, 0.400, kCycle / 2);
  EXPECT_NEAR(base.end_s - lap.end_s, 0.400, kCycle / 2);
  EXPECT_NEAR(lap.end_s, 3.6, 1e-9);
  // Corner: in the overlap Z = -100 + 0.1(1800 - t_ms), X = 0.1(t_ms - 1600); the distance to
  // the corner is smallest at 1700 ms: hypot(10, 10) = 14.142 mm.
  EXPECT_NEAR(lap.corner_mm, std::hypot(10.0, 10.0), 1e-6);

  // M11 (Z at the bottom) and M12 (X at the end) fire at their shifted control points.
  ASSERT_EQ(lap.events.size(), 2U);
  EXPECT_EQ(lap.events[0].code, 11);
  EXPECT_NEAR(lap.event_t[0], 1.8, 1e-9);
  EXPECT_EQ(lap.events[1].code, 12);
  EXPECT_NEAR(lap.event_t[1], 2.6, 1e-9);
}

}  // namespace
}  // namespace cncore::tables::test
