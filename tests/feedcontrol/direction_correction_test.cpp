// Feed correction by direction of motion (spec 03), measured on the produced trajectory: path
// speed by finite differences of the written positions, compared with F × C(FI) × override
// computed here by hand from the geometry; the correction-off run against the plain run byte
// for byte; helices; a real surfacing program through the spec 01 checker; bad laws rejected.
#include "feedcontrol/direction_correction.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "io/summary.hpp"
#include "io/trajectory_csv.hpp"
#include "limits.hpp"
#include "simulation/run.hpp"
#include "simulation/stepper.hpp"
#include "trajectory.hpp"
#include "trajectory_checker.hpp"

namespace cncore {
namespace {

namespace fs = std::filesystem;

std::string tmp_path(const std::string& name) {
  return (fs::path(CNCORE_TEST_TMP_DIR) / name).string();
}

std::string program_file(const std::string& name, const std::string& text) {
  const std::string p = tmp_path(name);
  std::ofstream(p) << text;
  return p;
}

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

MachineConfig corrected_machine(const std::string& extra = "") {
  return parse_machine_config("[direction_correction]\nenabled = true\n" + extra, "test.toml");
}

struct BlockRecorder : sim::SampleObserver {
  std::vector<Block> blocks;
  void on_block(const Block& b) override {
    if (!b.piece) blocks.push_back(b);  // the merged line before the pieces is what ran
  }
  void on_sample(const motion::Sample&) override {}
};

// Runs the program and writes the trajectory CSV (correction column when enabled).
std::vector<Block> run_to_csv(const std::string& program, const MachineConfig& m,
                              const std::string& csv, double override_pct = 100,
                              motion::AccDecType accdec = motion::AccDecType::kMovingAverage) {
  sim::RunOptions o;
  o.kernel.override_pct = override_pct;
  o.kernel.accdec = accdec;
  io::TrajectoryColumns cols;
  cols.override_pct = true;
  cols.correction = m.direction_correction.enabled;
  io::TrajectoryCsvWriter writer(csv, m, cols);
  BlockRecorder rec;
  sim::run_program(program, m, o, {&writer, &rec});
  writer.commit();
  return rec.blocks;
}

// Default law (both branches): C = 1 + 0.5·FI.
double default_c(double fi) {
  return 1 + 0.5 * fi;
}

// Mean path speed (mm/min) over the middle 60 % of the samples on `line`, from positions.
struct Measured {
  double speed_mm_min = 0, min_mm_min = 0, max_mm_min = 0, correction = 0;
  std::size_t samples = 0;
};
Measured measure_line(const testing::Trajectory& tr, std::uint32_t line) {
  std::vector<std::size_t> idx;
  for (std::size_t k = 1; k < tr.size(); ++k) {
    if (tr.line[k] == line && tr.line[k - 1] == line) idx.push_back(k);
  }
  Measured m;
  if (idx.size() < 10) return m;
  const std::size_t a = idx.size() / 5, b = idx.size() - idx.size() / 5;
  m.min_mm_min = 1e300;
  double sum = 0;
  for (std::size_t i = a; i < b; ++i) {
    const std::size_t k = idx[i];
    const AxisVec d = tr.pos[k] - tr.pos[k - 1];
    const double v = norm(d.xyz()) / (tr.t_s[k] - tr.t_s[k - 1]) * 60;
    sum += v;
    m.min_mm_min = std::min(m.min_mm_min, v);
    m.max_mm_min = std::max(m.max_mm_min, v);
  }
  m.samples = b - a;
  m.speed_mm_min = sum / static_cast<double>(m.samples);
  m.correction = tr.correction[idx[idx.size() / 2]];
  return m;
}

// Uphill 30°, level, downhill 30° (each 60 mm), separated by exact stops.
const char* kSlopes =
    "G21 G90 G17\n"
    "G0 X0 Y0 Z0\n"
    "G1 G9 X51.961524 Z30 F1000\n"  // line 3: uphill, FI = sin 30° = 0.5
    "G1 G9 X111.961524\n"           // line 4: level, FI = 0
    "G1 G9 X163.923048 Z0\n"        // line 5: downhill, FI = −0.5
    "M30\n";

void expect_slopes(const testing::Trajectory& tr, double factor_up, double factor_level,
                   double factor_down) {
  const struct {
    std::uint32_t line;
    double expected;
    const char* what;
  } cases[] = {{3, 1000 * factor_up, "uphill"},
               {4, 1000 * factor_level, "level"},
               {5, 1000 * factor_down, "downhill"}};
  for (const auto& c : cases) {
    const Measured m = measure_line(tr, c.line);
    ASSERT_GT(m.samples, 500u) << c.what;
    // Every sample of the steady part, not only the mean, within 0.5 %.
    EXPECT_NEAR(m.min_mm_min, c.expected, 0.005 * c.expected) << c.what;
    EXPECT_NEAR(m.max_mm_min, c.expected, 0.005 * c.expected) << c.what;
  }
}

TEST(DirectionCorrection, UphillLevelDownhillSpeedIsFTimesCTimesOverride) {
  const std::string p = program_file("slopes.ngc", kSlopes);
  const MachineConfig m = corrected_machine();
  const std::string csv = tmp_path("slopes_80.csv");
  run_to_csv(p, m, csv, 80);
  const testing::Trajectory tr = testing::load_trajectory_csv(csv);
  // C × Fr: C(0.5) = 1.25, C(0) = 1, C(−0.5) = 0.75, times 0.8.
  expect_slopes(tr, 1.25 * 0.8, 1.0 * 0.8, 0.75 * 0.8);
  EXPECT_NEAR(measure_line(tr, 3).correction, 1.25, 1e-6);
  EXPECT_EQ(measure_line(tr, 4).correction, 1.0);  // level gives exactly C = 1
  EXPECT_NEAR(measure_line(tr, 5).correction, 0.75, 1e-6);
  EXPECT_NEAR(default_c(0.5), 1.25, 1e-12);
}

TEST(DirectionCorrection, ReplaceModeIgnoresTheOverride) {
  const std::string p = program_file("slopes_c.ngc", kSlopes);
  const MachineConfig m = corrected_machine("override_mode = \"replace\"\n");
  const std::string csv = tmp_path("slopes_c.csv");
  const std::vector<Block> blocks = run_to_csv(p, m, csv, 50);
  const testing::Trajectory tr = testing::load_trajectory_csv(csv);
  expect_slopes(tr, 1.25, 1.0, 0.75);  // F × C: the 50 % override does not act
  // Within spec 01 against the blocks as the kernel got them (feed F·C), the switch ignored.
  testing::Trajectory same = tr;
  std::fill(same.override_pct.begin(), same.override_pct.end(), 100.0);
  std::fill(same.correction.begin(), same.correction.end(), 1.0);
  const testing::CheckReport r =
      testing::check_trajectory(same, blocks, testing::limits_from_config(m));
  EXPECT_TRUE(r.ok()) << r.summary();
}

// The acceleration acc/dec type (constant acceleration before interpolation): the correction
// is in the commanded feed, so it holds there too, in both override modes.
TEST(DirectionCorrection, AccelerationLimitedAccDecToo) {
  const std::string p = program_file("slopes_acc.ngc", kSlopes);
  const std::string a = tmp_path("slopes_acc.csv"), b = tmp_path("slopes_acc_c.csv");
  run_to_csv(p, corrected_machine(), a, 80, motion::AccDecType::kAcceleration);
  expect_slopes(testing::load_trajectory_csv(a), 1.25 * 0.8, 1.0 * 0.8, 0.75 * 0.8);
  run_to_csv(p, corrected_machine("override_mode = \"replace\"\n"), b, 50,
             motion::AccDecType::kAcceleration);
  expect_slopes(testing::load_trajectory_csv(b), 1.25, 1.0, 0.75);
}

TEST(DirectionCorrection, UserFormulaWithFeedAndDiameterAndOtherDirection) {
  // Direction −X (given unnormalised): the "uphill" move of line 3 goes +X, so FI = −cos 30°.
  const std::string p = program_file("slopes_u.ngc", kSlopes);
  const MachineConfig m = corrected_machine(
      "direction = [-2, 0, 0]\n"
      "uphill = \"1 + FI * D / 20\"\n"
      "downhill = \"1 + FI * F / 20000\"\n"
      "tool_diameter_mm = 6\n");
  EXPECT_EQ(m.direction_correction.direction, (Vec3{-1, 0, 0}));
  const std::string csv = tmp_path("slopes_u.csv");
  run_to_csv(p, m, csv);
  const testing::Trajectory tr = testing::load_trajectory_csv(csv);
  const double fi3 = -std::cos(std::numbers::pi / 6);  // line 3 and 5 move +X at 30°
  const double c_down = 1 + fi3 * 1000 / 20000.0;      // downhill law, F = 1000
  const double c_level = 1 - 1000 / 20000.0;           // line 4: FI = −1
  expect_slopes(tr, c_down, c_level, c_down);
}

TEST(DirectionCorrection, OffReproducesTheUncorrectedRunByteForByte) {
  const std::string p = program_file(
      "mixed.ngc",
      "G21 G90 G17\nG0 X5 Y5 Z2\nG1 Z-1 F400\nG1 X40 Y10 Z3 F1500\nG2 X60 Y10 Z0 I10 J0\n"
      "G3 X80 Y10 Z5 I10 J0\nG18 G2 X100 Z5 I10 K0\nG17 G1 X0 Y0 Z0\nM30\n");
  const std::string plain = tmp_path("plain.csv"), off = tmp_path("off.csv"),
                    off_cli = tmp_path("off_cli.csv"), on = tmp_path("on.csv");
  run_to_csv(p, default_machine_config(), plain);
  // The section present with enabled = false, and an enabled section switched off.
  run_to_csv(
      p,
      parse_machine_config("[direction_correction]\nenabled = false\nuphill = \"2\"\n", "t.toml"),
      off);
  MachineConfig cli = corrected_machine();
  cli.direction_correction.enabled = false;  // what `cncore run --correction off` does
  run_to_csv(p, cli, off_cli);
  run_to_csv(p, corrected_machine(), on);
  const std::string a = read_all(plain);
  ASSERT_GT(a.size(), 1000u);
  EXPECT_EQ(a, read_all(off));
  EXPECT_EQ(a, read_all(off_cli));
  EXPECT_NE(a, read_all(on));  // and the correction does change this run
}

TEST(DirectionCorrection, ProgramSwitchTurnsItOffAndOnForASection) {
  // M161 before the uphill line, M160 before the downhill one.
  const std::string p =
      program_file("switch.ngc",
                   "G21 G90\nG0 X0 Y0 Z0\nM161\nG1 G9 X51.961524 Z30 F1000\nG1 G9 X111.961524\n"
                   "G1 G9 X163.923048 Z0 M160\nM30\n");
  const std::string csv = tmp_path("switch.csv");
  run_to_csv(p, corrected_machine(), csv);
  const testing::Trajectory tr = testing::load_trajectory_csv(csv);
  const Measured up = measure_line(tr, 4), level = measure_line(tr, 5), down = measure_line(tr, 6);
  EXPECT_NEAR(up.speed_mm_min, 1000, 5);  // off: not corrected
  EXPECT_EQ(up.correction, 1.0);
  EXPECT_NEAR(level.speed_mm_min, 1000, 5);
  EXPECT_NEAR(down.speed_mm_min, 750, 3.75);  // on again from the block with M160
  EXPECT_NEAR(down.correction, 0.75, 1e-6);
  // active_at_start = false: off until M160.
  const std::string csv2 = tmp_path("switch2.csv");
  const std::string p2 = program_file("switch2.ngc",
                                      "G21 G90\nG0 X0 Y0 Z0\nG1 G9 X51.961524 Z30 F1000\nM160\n"
                                      "G1 G9 X103.923048 Z60\nM30\n");
  run_to_csv(p2, corrected_machine("active_at_start = false\n"), csv2);
  const testing::Trajectory tr2 = testing::load_trajectory_csv(csv2);
  EXPECT_NEAR(measure_line(tr2, 3).speed_mm_min, 1000, 5);
  EXPECT_NEAR(measure_line(tr2, 5).speed_mm_min, 1250, 6.25);
}

TEST(DirectionCorrection, RapidsAreNotCorrected) {
  const std::string p = program_file("rapid.ngc", "G21 G90\nG0 X0 Y0 Z0\nG0 G9 X10 Z80\nM30\n");
  const std::string a = tmp_path("rapid_plain.csv"), b = tmp_path("rapid_on.csv");
  run_to_csv(p, default_machine_config(), a);
  run_to_csv(p, corrected_machine(), b);
  const testing::Trajectory ta = testing::load_trajectory_csv(a);
  const testing::Trajectory tb = testing::load_trajectory_csv(b);
  ASSERT_EQ(ta.size(), tb.size());
  for (std::size_t k = 0; k < ta.size(); ++k) ASSERT_EQ(ta.pos[k], tb.pos[k]);
  EXPECT_EQ(tb.correction.back(), 1.0);
}

// Helix about Z (G17): FI = rise / length is constant along it, > 0 climbing, < 0 descending.
TEST(DirectionCorrection, HelixClimbingAndDescending) {
  // Radius 20, one turn each, rise ±30: FI = 30 / √((40π)² + 30²).
  const std::string p = program_file(
      "helix.ngc",
      "G21 G90 G17\nG0 X20 Y0 Z0\nG3 G9 X20 Y0 Z30 I-20 J0 F1200\nG2 G9 X20 Y0 Z0 I-20 J0\nM30\n");
  const std::string csv = tmp_path("helix.csv");
  run_to_csv(p, corrected_machine(), csv);
  const testing::Trajectory tr = testing::load_trajectory_csv(csv);
  const double fi = 30 / std::hypot(40 * std::numbers::pi, 30.0);
  const Measured up = measure_line(tr, 3), down = measure_line(tr, 4);
  EXPECT_NEAR(up.speed_mm_min, 1200 * default_c(fi), 0.005 * 1200 * default_c(fi));
  EXPECT_NEAR(down.speed_mm_min, 1200 * default_c(-fi), 0.005 * 1200 * default_c(-fi));
  EXPECT_NEAR(up.correction, default_c(fi), 1e-6);  // the CSV has 6 decimals
  EXPECT_NEAR(down.correction, default_c(-fi), 1e-6);
}

// An arc in the XZ plane (G18) with direction Z: the tangent climbs on one half and descends on
// the other, so C must change inside the block, following the measured local direction.
TEST(DirectionCorrection, ArcInAVerticalPlaneFollowsTheLocalTangent) {
  // Half circle from (0,0,0) over the top to (40,0,0), centre (20,0,0), then back below (G18 G2
  // turns clockwise seen from +Y: up first). Radius 20: Vb is far above the feed.
  const std::string p =
      program_file("vertical_arc.ngc",
                   "G21 G90 G18\nG0 X0 Y0 Z0\nG2 X40 Z0 I20 K0 F1000\nG2 X0 Z0 I-20 K0\nM30\n");
  const MachineConfig m = corrected_machine();
  const std::string csv = tmp_path("vertical_arc.csv");
  const std::vector<Block> blocks = run_to_csv(p, m, csv);
  // 2 × 180° at 5°: 72 sub-arcs (plus the rapid).
  EXPECT_EQ(blocks.size(), 73u);
  const testing::Trajectory tr = testing::load_trajectory_csv(csv);
  double worst_c = 0, worst_v = 0;
  std::size_t checked = 0, climbing = 0, descending = 0;
  for (std::size_t k = 2; k + 1 < tr.size(); ++k) {
    if (tr.t_s[k] < 0.3 || tr.line[k] == 0) continue;  // away from the start ramp
    const Vec3 d = (tr.pos[k + 1] - tr.pos[k - 1]).xyz();
    if (norm(d) < 1e-6) continue;
    const double fi = d.z / norm(d);  // local direction, measured
    const double c = default_c(fi);
    // The column holds C of the sub-arc (5°): within 0.5·(5°/2 in rad) + the sample's own span.
    worst_c = std::max(worst_c, std::abs(tr.correction[k] - c));
    const double v = norm(d) / (tr.t_s[k + 1] - tr.t_s[k - 1]) * 60;
    // The speed follows F·C with the acc/dec smoothing the 5° steps: compare with the local value.
    if (tr.t_s.back() - tr.t_s[k] > 0.3) worst_v = std::max(worst_v, std::abs(v / (1000 * c) - 1));
    climbing += fi > 0.2 && tr.correction[k] > 1;
    descending += fi < -0.2 && tr.correction[k] < 1;
    ++checked;
  }
  ASSERT_GT(checked, 5000u);
  EXPECT_LT(worst_c, 0.5 * (2.5 * std::numbers::pi / 180) + 0.002);
  // The speed follows F·C through the acc/dec: C changes in steps of up to 0.5·δ (δ = 5° in rad,
  // slope 0.5 of the law), and the filter (T = Vmax/Amax = 83 ms) lags by up to T·v/r rad of
  // turn: |v/(F·C) − 1| ≤ 0.5·(δ + T·v/r) with v ≤ 1250 mm/min, r = 20 mm (≈ 8.7 %).
  const double bound =
      0.5 * (5 * std::numbers::pi / 180 + (10000.0 / 60 / 2000) * (1250.0 / 60) / 20);
  EXPECT_LT(worst_v, bound);
  EXPECT_GT(climbing, 1000u);
  EXPECT_GT(descending, 1000u);
  // And it keeps every limit of spec 01 (corrected feeds as programmed for the checker).
  testing::Trajectory same = tr;
  std::fill(same.correction.begin(), same.correction.end(), 1.0);
  const testing::CheckReport r =
      testing::check_trajectory(same, blocks, testing::limits_from_config(m));
  EXPECT_TRUE(r.ok()) << r.summary();
}

// The pulled stepper (cncore table --master-program) runs the same corrected motion.
TEST(DirectionCorrection, ProgramStepperMatchesRunProgram) {
  const std::string p = program_file(
      "stepper.ngc", "G21 G90 G18\nG0 X0 Y0 Z0\nG2 X40 Z0 I20 K0 F1000\nG1 X60 Z10\nM30\n");
  const MachineConfig m = corrected_machine();
  struct Positions : sim::SampleObserver {
    std::vector<AxisVec> p;
    std::vector<double> c;
    void on_sample(const motion::Sample& s) override {
      p.push_back(s.position);
      c.push_back(s.correction);
    }
  } run;
  const sim::RunCounts counts = sim::run_program(p, m, {}, {&run});
  sim::ProgramStepper stepper(p, m, motion::KernelOptions{});
  motion::Sample s;
  std::size_t k = 0;
  while (stepper.next(s)) {
    ASSERT_LT(k, run.p.size());
    ASSERT_EQ(s.position, run.p[k]) << k;
    if (!std::isnan(run.c[k])) {
      ASSERT_EQ(s.correction, run.c[k]) << k;
    }
    ++k;
  }
  EXPECT_EQ(k, run.p.size());
  EXPECT_EQ(stepper.blocks(), counts.blocks);  // interpreted blocks, not sub-arcs
  EXPECT_EQ(counts.blocks, 2u);                // the G0 to the start position moves nothing
}

TEST(DirectionCorrection, RealSurfacingProgramStaysWithinLimits) {
  const fs::path file = fs::path(CNCORE_SHARED_DIR) / "testdata/gcode/camotics/bear.nc";
  if (!fs::exists(file)) GTEST_SKIP() << "shared corpus not found: " << file;
  const MachineConfig m = corrected_machine();
  const std::string csv = tmp_path("bear.csv");
  const std::vector<Block> blocks = run_to_csv(file.string(), m, csv);
  const testing::Trajectory tr = testing::load_trajectory_csv(csv);
  double cmin = 10, cmax = 0;
  for (double c : tr.correction) {
    cmin = std::min(cmin, c);
    cmax = std::max(cmax, c);
  }
  EXPECT_LT(cmin, 0.9);  // the relief goes down …
  EXPECT_GT(cmax, 1.1);  // … and up
  testing::Trajectory same = tr;
  std::fill(same.correction.begin(), same.correction.end(), 1.0);
  const testing::CheckReport r =
      testing::check_trajectory(same, blocks, testing::limits_from_config(m));
  EXPECT_TRUE(r.ok()) << r.summary();
}

TEST(DirectionCorrection, SummaryReportsTheRangeOfCAndTheTimeAdded) {
  // 60 mm up at 30°, 60 mm level, 60 mm down at F1000 with exact stops: at constant speed the
  // correction changes 3 × 3.6 s into 60/1250 + 60/1000 + 60/750 min = 11.28 s (+0.48 s); the
  // ramps at the stops are the same in both runs up to a cycle or two.
  const std::string p = program_file("slopes_sum.ngc", kSlopes);
  const MachineConfig on = corrected_machine();
  MachineConfig off = on;
  off.direction_correction.enabled = false;
  io::SummaryObserver with(on, "lookahead"), without(off, "lookahead");
  sim::run_program(p, on, {}, {&with});
  sim::run_program(p, off, {}, {&without});
  with.set_time_without_correction_s(without.summary().cycle_time_s);
  const io::Summary& s = with.summary();
  EXPECT_NEAR(s.correction_min, 0.75, 1e-6);
  EXPECT_NEAR(s.correction_max, 1.25, 1e-6);
  EXPECT_NEAR(s.cycle_time_s - s.time_without_correction_s, 0.48, 0.003);
  EXPECT_TRUE(std::isnan(without.summary().correction_min));  // off: no coefficient at all
  const std::string json = io::summary_to_json(s, on);
  EXPECT_NE(json.find("\"direction_correction\""), std::string::npos);
  EXPECT_NE(json.find("\"time_added_s\""), std::string::npos);
  EXPECT_EQ(io::summary_to_json(without.summary(), off).find("direction_correction"),
            std::string::npos);
  EXPECT_NE(io::format_human_summary(s, on, p).find("correction    C 0.750 … 1.250; added 0.48"),
            std::string::npos)
      << io::format_human_summary(s, on, p);
}

#ifdef CNCORE_BIN
// End to end through `cncore run` / `cncore machine`: the option, the column, the summary key and
// the exit code of a bad law.
int run_cli(const std::string& args, const std::string& stderr_file) {
  const std::string cmd = std::string(CNCORE_BIN) + " " + args + " > /dev/null 2> " + stderr_file;
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(DirectionCorrectionCli, OptionColumnSummaryAndErrors) {
  const std::string p = program_file("cli_slopes.ngc", kSlopes);
  const std::string err = tmp_path("cli_err.txt");
  const std::string on_csv = tmp_path("cli_on.csv"), on_json = tmp_path("cli_on.json");
  ASSERT_EQ(
      run_cli("run " + p + " --correction on --trajectory " + on_csv + " --summary " + on_json,
              err),
      0);
  EXPECT_EQ(read_all(on_csv).substr(0, 28), "t,line,x,y,z,feed,correction");
  const std::string json = read_all(on_json);
  EXPECT_NE(json.find("\"direction_correction\""), std::string::npos) << json;
  const std::size_t at = json.find("\"time_added_s\": ");
  ASSERT_NE(at, std::string::npos) << json;
  EXPECT_NEAR(std::strtod(json.c_str() + at + 16, nullptr), 0.48, 0.003) << json;  // by hand
  // --correction off over an enabled machine: the plain run, byte for byte.
  const std::string toml = program_file("cli_dc.toml", "[direction_correction]\nenabled = true\n");
  const std::string plain = tmp_path("cli_plain.csv"), off = tmp_path("cli_off.csv");
  ASSERT_EQ(run_cli("run " + p + " --trajectory " + plain, err), 0);
  ASSERT_EQ(
      run_cli("run " + p + " --machine " + toml + " --correction off --trajectory " + off, err), 0);
  EXPECT_EQ(read_all(plain), read_all(off));
  EXPECT_EQ(run_cli("run " + p + " --correction maybe", err), 2);
  // A bad law: exit 1, FILE:LINE:COL with the FI.
  const std::string bad =
      program_file("cli_bad.toml", "[direction_correction]\ndownhill = \"1 + 2*FI\"\n");
  EXPECT_EQ(run_cli("run " + p + " --machine " + bad, err), 1);
  EXPECT_NE(read_all(err).find(bad + ":2:1: error: direction_correction.downhill: C = -1 at FI = "
                                     "-1"),
            std::string::npos)
      << read_all(err);
  const std::string printed = tmp_path("cli_machine.toml");
  ASSERT_EQ(run_cli("machine --machine " + toml + " > " + printed, err), 0);
}
#endif

// ---- configuration -------------------------------------------------------------------------

std::string config_error(const std::string& text) {
  try {
    parse_machine_config(text, "bad.toml");
  } catch (const InputError& e) {
    return e.formatted();
  }
  return "(accepted)";
}

TEST(DirectionCorrectionConfig, BadFormulasAreRejectedWithTheOffendingFI) {
  // 1 − 2·FI is 0 at FI = 0.5 (the grid has 2000 steps over [0, 1], so 0.5 is on it).
  EXPECT_EQ(config_error("[direction_correction]\nuphill = \"1 - 2*FI\"\n"),
            "bad.toml:2:1: error: direction_correction.uphill: C = 0 at FI = 0.5 (F = 10000 "
            "mm/min, D = 10 mm): the coefficient must be finite and > 0 for every FI in [0, 1]");
  // 1/(FI + 0.5) divides by zero at FI = −0.5 and is negative below it: first bad FI is −1.
  const std::string e = config_error("[direction_correction]\ndownhill = \"1/(FI + 0.5)\"\n");
  EXPECT_NE(e.find("bad.toml:2:1: error: direction_correction.downhill: C = -2 at FI = -1 "),
            std::string::npos)
      << e;
  // sqrt of a negative number: NaN.
  const std::string n = config_error("[direction_correction]\ndownhill = \"sqrt(FI)\"\n");
  EXPECT_NE(n.find("C = NaN at FI = -1"), std::string::npos) << n;
  // Depends on F: bad only at low feeds.
  const std::string f = config_error("[direction_correction]\nuphill = \"1 + FI - 100/F\"\n");
  EXPECT_NE(f.find("at FI = 0 (F = 1 mm/min"), std::string::npos) << f;
  // Syntax error: the column points into the formula.
  const std::string s = config_error("[direction_correction]\nuphill = \"1 + * FI\"\n");
  EXPECT_NE(s.find("bad.toml:2:"), std::string::npos) << s;
  EXPECT_NE(s.find("direction_correction.uphill: formula \"1 + * FI\""), std::string::npos) << s;
  EXPECT_NE(config_error("[direction_correction]\nuphill = \"1 + Q\"\n").find("Q"),
            std::string::npos);
}

TEST(DirectionCorrectionConfig, TablesDirectionAndModes) {
  EXPECT_NE(config_error("[direction_correction]\ndirection = [0, 0, 0]\n").find("zero vector"),
            std::string::npos);
  EXPECT_NE(config_error("[direction_correction]\ndownhill = [[-1, 0.5], [-1, 0.7]]\n")
                .find("must be greater than the previous FI"),
            std::string::npos);
  EXPECT_NE(config_error("[direction_correction]\ndownhill = [[-1, 0], [0, 1]]\n")
                .find("C = 0 at FI = -1"),
            std::string::npos);
  EXPECT_NE(
      config_error("[direction_correction]\noverride_mode = \"C only\"\n").find("\"multiply\""),
      std::string::npos);
  EXPECT_NE(config_error("[direction_correction]\nfoo = 1\n").find("direction_correction.foo"),
            std::string::npos);
  const MachineConfig m = parse_machine_config(
      "[direction_correction]\nenabled = true\ndirection = [0, 3, 4]\n"
      "uphill = [[0, 1], [0.5, 1.2], [1, 1.3]]\ndownhill = [[-1, 0.4], [0, 1]]\n"
      "override_mode = \"replace\"\narc_step_deg = 2\n",
      "t.toml");
  const DirectionCorrectionConfig& d = m.direction_correction;
  EXPECT_TRUE(d.enabled);
  EXPECT_NEAR(d.direction.y, 0.6, 1e-15);
  EXPECT_NEAR(d.direction.z, 0.8, 1e-15);
  EXPECT_EQ(d.override_mode, CorrectionOverrideMode::kReplace);
  // Table: linear between points, flat outside.
  feed::DirectionCorrector corr(m);
  Block b;
  EXPECT_NEAR(corr.coefficient({0, 0.6, 0.8}, 1000, b), 1.3, 1e-12);          // FI = 1
  EXPECT_NEAR(corr.coefficient({0, 0, 1}, 1000, b), 1.2 + 0.1 * 0.6, 1e-12);  // FI = 0.8
  EXPECT_NEAR(corr.coefficient({0, -0.6, -0.8}, 1000, b), 0.4, 1e-12);        // FI = −1
  EXPECT_NEAR(corr.coefficient({1, 0, 0}, 1000, b), 1.0, 1e-12);              // FI = 0
  // Round trip through `cncore machine`'s text.
  EXPECT_EQ(parse_machine_config(machine_config_to_toml(m), "again.toml"), m);
}

TEST(DirectionCorrectionConfig, DefaultIsOffAndPrinted) {
  const MachineConfig d = default_machine_config();
  EXPECT_FALSE(d.direction_correction.enabled);
  const std::string text = machine_config_to_toml(d);
  EXPECT_NE(text.find("[direction_correction]"), std::string::npos);
  EXPECT_NE(text.find("uphill = \"1 + 0.5*FI\""), std::string::npos);
  EXPECT_EQ(parse_machine_config(text, "t.toml"), d);
}

TEST(DirectionCorrection, FormulaThatFailsBetweenGridPointsStopsTheRunAtTheLine) {
  // Infinite at F = 1234.5 exactly (not on the load-time grid of feeds): the run stops at the
  // line of that block with the FI in the message.
  const MachineConfig m = corrected_machine("uphill = \"1 + FI/abs(F - 1234.5)\"\n");
  const std::string p =
      program_file("between.ngc", "G21 G90\nG0 X0 Y0 Z0\nG1 X10 F1000\nG1 X20 Z5 F1234.5\nM30\n");
  try {
    run_to_csv(p, m, tmp_path("between.csv"));
    FAIL() << "accepted";
  } catch (const InputError& e) {
    const std::string s = e.formatted();
    EXPECT_NE(s.find(p + ":4:1: error: direction correction: the uphill law gives C = inf at FI = "
                         "0.447214"),
              std::string::npos)
        << s;
  }
}

}  // namespace
}  // namespace cncore
