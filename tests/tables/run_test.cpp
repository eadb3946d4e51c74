// References (spindle, master axis), cyclic and cubic tables, M codes, multi-axis rows.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "helpers.hpp"

namespace cncore::tables::test {
namespace {

TEST(Reference, SpindleAngleCountsAcrossRevolutions) {
  RunOptions o;
  o.reference = ReferenceSource::spindle(60);  // 360 deg/s
  TableRun r = run_texts({"REF SPINDLE\nAXES X\nL0 X0\nL360 X10\nL720 X10\nL900 X40\n"}, o);
  EXPECT_NEAR(time_reaching(r.samples, kX, 10), 1.0, 0.0005);
  // Second revolution: the angle keeps counting (540 deg at 1.5 s, not 180).
  auto& mid = r.samples[1500];
  EXPECT_NEAR(mid.t_s, 1.5, 1e-12);
  EXPECT_NEAR(mid.ref, 540, 1e-9);
  EXPECT_NEAR(mid.position[kX], 10, 1e-12);
  // 720 → 900 deg is 0.5 s; X = 40 at 2.5 s, the end.
  EXPECT_NEAR(time_reaching(r.samples, kX, 40), 2.5, 0.0005);
  EXPECT_NEAR(r.samples.back().t_s, 2.5, 1e-9);
}

TEST(Reference, SpindleSpeedScalesTheTime) {
  RunOptions o;
  o.reference = ReferenceSource::spindle(120);  // twice as fast: the same table in half the time
  TableRun r = run_texts({"REF SPINDLE\nAXES X\nL0 X0\nL360 X10\nL720 X10\nL900 X40\n"}, o);
  EXPECT_NEAR(r.samples.back().t_s, 1.25, 1e-9);
}

TEST(Reference, MasterAxisAtConstantSpeed) {
  RunOptions o;
  o.reference = ReferenceSource::master_axis(0, 600);  // Y at 600 mm/min = 10 mm/s
  TableRun r = run_texts({"REF AXIS Y\nAXES X\nL0 X0\nL50 X20\n"}, o);
  // X follows Y: X = 0.4 Y, Y = 10 t. The master's position is in the samples.
  for (std::size_t i : {0U, 1234U, 3000U, 5000U}) {
    const auto& s = r.samples[i];
    EXPECT_NEAR(s.position[kY], 10 * s.t_s, 1e-9);
    EXPECT_NEAR(s.position[kX], 0.4 * s.position[kY], 1e-9);
  }
  EXPECT_NEAR(r.samples.back().t_s, 5.0, 1e-9);
}

TEST(Reference, MasterAxisPositionFunctionForwardOnly) {
  // Y goes 0 → 20 (0..2 s), back to 10 (2..4 s), then forward again at 10 mm/s.
  RunOptions o;
  o.reference.position = [](double t) {
    if (t <= 2) return 10 * t;
    if (t <= 4) return 20 - 5 * (t - 2);
    return 10 + 10 * (t - 4);
  };
  o.reference.rate_per_s = 10;  // nominal, for the limit check
  TableRun r = run_texts({"REF AXIS Y\nAXES X\nL0 X0\nL50 X20\n"}, o);
  auto at = [&](double t) { return r.samples[static_cast<std::size_t>(std::lround(t * 1000))]; };
  EXPECT_NEAR(at(1).position[kX], 4, 1e-9);
  // While the master goes back and until it passes 20 again (t = 5 s) X holds at 0.4·20.
  EXPECT_NEAR(at(3).position[kX], 8, 1e-9);
  EXPECT_NEAR(at(3).position[kY], 15, 1e-9);
  EXPECT_NEAR(at(4.9).position[kX], 8, 1e-9);
  EXPECT_NEAR(at(5.5).position[kX], 0.4 * 25, 1e-9);
  EXPECT_NEAR(r.samples.back().t_s, 8.0, 1e-9);  // Y = 50 at t = 8 s
}

TEST(Cyclic, RepeatsTheTable) {
  RunOptions o;
  o.reference = ReferenceSource::spindle(60);
  TableRun r = run_texts({"REF SPINDLE\nAXES X\nCYCLIC 3\nL0 X0\nL180 X10 M20\nL360 X0 M21\n"}, o);
  // Peaks (X = 10) at 0.5, 1.5, 2.5 s; back at 0 at 1, 2, 3 s; ends after three revolutions.
  std::vector<double> peaks, m20, m21;
  for (std::size_t i = 1; i + 1 < r.samples.size(); ++i) {
    const auto& s = r.samples[i];
    if (s.position[kX] >= r.samples[i - 1].position[kX] &&
        s.position[kX] > r.samples[i + 1].position[kX]) {
      peaks.push_back(s.t_s);
    }
  }
  for (const auto& s : r.samples) {
    for (const auto& e : s.m_codes) (e.code == 20 ? m20 : m21).push_back(s.t_s);
  }
  ASSERT_EQ(peaks.size(), 3U);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(peaks[k], 0.5 + static_cast<double>(k), 1e-9);
    EXPECT_NEAR(m20[k], 0.5 + static_cast<double>(k), 1e-9);
  }
  ASSERT_EQ(m21.size(), 3U);
  EXPECT_NEAR(m21[2], 3.0, 1e-9);
  EXPECT_NEAR(r.samples.back().t_s, 3.0, 1e-9);
  EXPECT_NEAR(r.samples.back().position[kX], 0, 1e-12);
  EXPECT_NEAR(r.samples.back().ref, 1080, 1e-9);
}

TEST(Cyclic, RepetitionCountFromOptionsAndShiftsPerRepetition) {
  // The shift is re-applied in every repetition (fresh shift state): each repetition's peak is
  // 100 deg early and a repetition lasts 360 - 0 = 360 deg (the last row is not shifted by
  // SFTCAN in clear mode).
  RunOptions o;
  o.reference = ReferenceSource::spindle(60);
  o.cyclic_repeats = 2;
  TableRun r =
      run_texts({"REF SPINDLE\nAXES X\nCYCLIC\nL0 X0\nL180 X10 SFT-90\nL360 X0 SFTCAN\n"}, o);
  std::vector<double> peaks;
  for (std::size_t i = 1; i + 1 < r.samples.size(); ++i) {
    if (r.samples[i].position[kX] > 10 - 1e-9) peaks.push_back(r.samples[i].t_s);
  }
  ASSERT_EQ(peaks.size(), 2U);
  EXPECT_NEAR(peaks[0], 0.25, 1e-9);
  EXPECT_NEAR(peaks[1], 1.25, 1e-9);
  EXPECT_NEAR(r.samples.back().t_s, 2.0, 1e-9);
}

TEST(Cyclic, LeadInIsNotRepeated) {
  // The machine starts at X = 5; the cycle is the rows L500 … L1500 (period 1000 ms). The
  // lead-in 0 … 500 ms brings X from 5 to 0 once.
  MachineConfig m = stiff_machine();
  m.start_position[kX] = 5;
  TableRun r = run_texts({"REF TIME\nAXES X\nCYCLIC 2\nL500 X0\nL1000 X10\nL1500 X0\n"}, {}, m);
  EXPECT_NEAR(r.samples[250].position[kX], 2.5, 1e-12);
  EXPECT_NEAR(r.samples[500].position[kX], 0, 1e-12);
  EXPECT_NEAR(r.samples[1000].position[kX], 10, 1e-12);
  EXPECT_NEAR(r.samples[1500].position[kX], 0, 1e-12);
  EXPECT_NEAR(r.samples[2000].position[kX], 10, 1e-12);
  EXPECT_NEAR(r.samples.back().t_s, 2.5, 1e-12);
  EXPECT_NEAR(r.samples.back().position[kX], 0, 1e-12);
}

TEST(Cubic, VelocityIsContinuousAtControlPoints) {
  const char* body = "AXES X\nL0 X0\nL1000 X50\nL2000 X150\nL2500 X150\nL3500 X100\nL4000 X100\n";
  TableRun lin = run_texts({std::string("REF TIME\nLINEAR\n") + body});
  TableRun cub = run_texts({std::string("REF TIME\nCUBIC\n") + body});
  auto max_jump = [](const TableRun& r) {
    double m = 0;
    for (std::size_t i = 2; i < r.samples.size(); ++i) {
      m = std::max(m, std::abs(fd_velocity(r.samples, kX, i) - fd_velocity(r.samples, kX, i - 1)));
    }
    return m;
  };
  // Linear: at L1000 the velocity jumps from 50 to 100 mm/s in one cycle.
  EXPECT_NEAR(max_jump(lin), 100.0, 1e-6);  // L2000: 100 → 0 mm/s
  // Cubic: the largest change between two cycles is tiny (acceleration × 1 ms).
  EXPECT_LT(max_jump(cub), 1.0);
  // It still passes through the control points, starts and ends at rest, and does not
  // overshoot the flat parts (monotone cubic).
  for (auto [t, x] : {std::pair{1.0, 50.0}, {2.0, 150.0}, {2.5, 150.0}, {3.5, 100.0}}) {
    EXPECT_NEAR(cub.samples[static_cast<std::size_t>(std::lround(t * 1000))].position[kX], x, 1e-9);
  }
  double xmax = 0, xmin_after = 1e9;
  for (const auto& s : cub.samples) {
    xmax = std::max(xmax, s.position[kX]);
    if (s.t_s >= 2.0 && s.t_s <= 2.5) xmin_after = std::min(xmin_after, s.position[kX]);
  }
  EXPECT_LE(xmax, 150 + 1e-9);
  EXPECT_GE(xmin_after, 150 - 1e-9);
  EXPECT_NEAR(fd_velocity(cub.samples, kX, 1), 0, 0.2);
  EXPECT_NEAR(fd_velocity(cub.samples, kX, cub.samples.size() - 1), 0, 0.2);
}

TEST(Cubic, CyclicCamHasNoVelocityJumpBetweenRevolutions) {
  RunOptions o;
  o.reference = ReferenceSource::spindle(60);
  std::ifstream in(std::string(CNCORE_TABLES_EXAMPLES_DIR) + "/spindle-cam.tbl");
  std::ostringstream ss;
  ss << in.rdbuf();
  TableRun r = run_texts({ss.str()}, o);
  EXPECT_NEAR(r.samples.back().t_s, 3.0, 1e-9);
  // Around the end of the first revolution (t = 1 s) the velocity changes smoothly.
  double jump = 0;
  for (std::size_t i = 900; i < 1100; ++i) {
    jump =
        std::max(jump, std::abs(fd_velocity(r.samples, kX, i + 1) - fd_velocity(r.samples, kX, i)));
  }
  EXPECT_LT(jump, 0.5);
  int m20 = 0;
  for (const auto& s : r.samples) m20 += static_cast<int>(s.m_codes.size());
  EXPECT_EQ(m20, 3);
}

TEST(MultiAxis, RowsDriveSeveralAxesAndMCodesFireAtTheirPoints) {
  TableRun r = run_texts({"REF TIME\nAXES X Z\nL0 X0 Z0\nL500 X10 M8\nL1000 Z-5 M9 M10\n"});
  // Z is modal: unwritten in L500, it stays 0 until then.
  EXPECT_NEAR(r.samples[500].position[kX], 10, 1e-12);
  EXPECT_NEAR(r.samples[500].position[kZ], 0, 1e-12);
  EXPECT_NEAR(r.samples[750].position[kZ], -2.5, 1e-12);
  EXPECT_NEAR(r.samples[750].position[kX], 10, 1e-12);
  std::vector<std::pair<double, int>> fired;
  for (const auto& s : r.samples) {
    for (const auto& e : s.m_codes) fired.push_back({s.t_s, e.code});
  }
  ASSERT_EQ(fired.size(), 3U);
  EXPECT_NEAR(fired[0].first, 0.5, 1e-12);
  EXPECT_EQ(fired[0].second, 8);
  EXPECT_NEAR(fired[1].first, 1.0, 1e-12);
  EXPECT_EQ(fired[1].second, 9);
  EXPECT_EQ(fired[2].second, 10);
  // The active row: line 4 (L500) until 0.5 s, then line 5.
  EXPECT_EQ(r.samples[100].line, 4U);
  EXPECT_EQ(r.samples[700].line, 5U);
  // The motion sample for trajectory writers carries the first M code of the cycle.
  motion::Sample m = to_motion_sample(r.samples[500]);
  EXPECT_EQ(m.aux_letter, 'M');
  EXPECT_EQ(m.aux_value, 8);
  EXPECT_NEAR(m.position[kX], 10, 1e-12);
  // feed: X moves 10 mm in 500 ms = 20 mm/s = 1200 mm/min.
  EXPECT_NEAR(r.samples[200].feed_mm_min, 1200, 1e-6);
}

TEST(MultiAxis, StartPositionOfUnwrittenAxesComesFromTheMachine) {
  MachineConfig m = stiff_machine();
  m.start_position[kX] = 5;
  m.start_position[kY] = 7;
  TableRun r = run_texts({"REF TIME\nAXES X\nL1000 X15\n"}, {}, m);
  EXPECT_NEAR(r.samples[0].position[kX], 5, 1e-12);  // implicit start point
  EXPECT_NEAR(r.samples[500].position[kX], 10, 1e-12);
  EXPECT_NEAR(r.samples[500].position[kY], 7, 1e-12);  // not driven: stays
}

TEST(Run, SeveralTablesEndTogetherAtTheLatestEnd) {
  TableRun r = run_texts({"REF TIME\nAXES X\nL1000 X10\n", "REF TIME\nAXES Z\nL2500 Z-10\n"});
  EXPECT_NEAR(r.samples.back().t_s, 2.5, 1e-12);
  EXPECT_NEAR(r.samples[2000].position[kX], 10, 1e-12);
  EXPECT_EQ(r.samples[2000].lines[1], 3U);
  EXPECT_EQ(r.samples.size(), 2501U);
  EXPECT_EQ(r.summary.cycles, 2501U);
  EXPECT_TRUE(r.summary.finished);
}

TEST(Run, StalledMasterStopsAtMaxTime) {
  RunOptions o;
  o.reference.position = [](double) { return 0.0; };
  o.reference.rate_per_s = 10;
  o.max_time_s = 0.5;
  TableRun r = run_texts({"REF AXIS Y\nAXES X\nL0 X0\nL50 X20\n"}, o);
  EXPECT_FALSE(r.summary.finished);
  EXPECT_EQ(r.summary.warnings.size(), 1U);
  EXPECT_NEAR(r.samples.back().t_s, 0.5, 1e-9);
}

}  // namespace
}  // namespace cncore::tables::test
