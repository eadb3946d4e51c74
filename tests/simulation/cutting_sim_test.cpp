// The cutting simulation on the simulated machine: programs run through sim::run_program, the
// tool sweeps the stock every interpolation cycle, T / M6 pick tools from the table, MRR and
// spindle load follow; configuration and program errors name the key or line.
#include "simulation/cutting/cutting_sim.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "simulation/run.hpp"

namespace cncore::cut {
namespace {

std::string program_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

// Stock 60 × 60 × 20 with its top at Z 0, centred on X 0 Y 0; tool 1 flat Ø10, tool 2 ball Ø10,
// tool 3 bull nose Ø12 r2; aluminium (kc 700 N/mm²) on a 5.5 kW spindle.
const char* kMachine = R"(
[stock]
min_mm = [-30, -30, -20]
size_mm = [60, 60, 20]
cell_mm = 0.1

[cutting]
material = "aluminium_6061"
spindle_power_kw = 5.5
load_window_s = 0.02

[[tools]]
number = 1
type = "flat"
diameter_mm = 10
flutes = 3

[[tools]]
number = 2
type = "ball"
diameter_mm = 10

[[tools]]
number = 3
type = "bull"
diameter_mm = 12
corner_radius_mm = 2
)";

MachineConfig machine(const std::string& extra = "") {
  return parse_machine_config(std::string(kMachine) + extra, "machine.toml");
}

// Per program line: removed volume and cycles, and the windowed MRR at the line's middle cycle.
struct PerLine : sim::SampleObserver {
  explicit PerLine(CuttingSimulator& s) : sim(&s) {}
  void on_sample(const motion::Sample& s) override {
    Line& l = lines[s.line];
    l.removed_mm3 += sim->last_cycle_removed_mm3();
    l.mrr.push_back(sim->last_mrr_mm3_s());
    l.load.push_back(s.load_pct);
  }
  struct Line {
    double removed_mm3 = 0;
    std::vector<double> mrr, load;
    double mid_mrr() const { return mrr.empty() ? 0 : mrr[mrr.size() / 2]; }
  };
  CuttingSimulator* sim;
  std::map<std::uint32_t, Line> lines;
};

TEST(CuttingSim, SlotThroughTheKernelRemovesWidthTimesDepthTimesLengthAndLoadFollowsKc) {
  const MachineConfig m = machine();
  // Across the whole stock in X at Y 0.03, 2 mm deep, F600 (10 mm/s): the slot's MRR is
  // w·d·v = 10·2·10 = 200 mm³/s → P = kc·MRR = 700·200 mW = 140 W → 2.545 % of 5.5 kW.
  const std::string p = program_file("slot.ngc",
                                     "G21 G90\nT1 M6\nG0 X-40 Y0.03 Z5\nG1 Z-2 F600\n"
                                     "G1 X40\nG0 Z5\nM30\n");
  CuttingSimulator cut(m, p);
  PerLine per(cut);
  CuttingStage stage(cut, {&per});
  sim::run_program(p, m, {}, {&stage});
  // |V − w·d·L| ≤ h·d·L (see the height-map test).
  EXPECT_NEAR(cut.stats().removed_mm3, 10 * 2 * 60, 0.1 * 2 * 60);
  EXPECT_NEAR(per.lines[5].removed_mm3, cut.stats().removed_mm3, 1e-9);
  EXPECT_NEAR(per.lines[5].mid_mrr(), 200, 200 * 0.02);
  const double load = CuttingSimulator::load_from_mrr(200, 700, 5.5);
  EXPECT_NEAR(load, 100 * 140.0 / 5500, 1e-9);
  EXPECT_NEAR(per.lines[5].load[per.lines[5].load.size() / 2], load, load * 0.02);
  EXPECT_NEAR(cut.stats().peak_load_pct, load, load * 0.05);
  EXPECT_NEAR(cut.stats().mean_cutting_load_pct(), load, load * 0.15);
  // No load while the tool moves in the air.
  EXPECT_EQ(per.lines[3].removed_mm3, 0);
}

TEST(CuttingSim, PocketMrrRisesInFullWidthCutsAndFallsInFinishingPasses) {
  const MachineConfig m = machine();
  // A 40 × 40 pocket 2 mm deep with the Ø10 flat end mill at F600 (10 mm/s):
  //   line 5  full-width slot along Y = −15           MRR = 10·2·10 = 200 mm³/s
  //   line 6  step 5 mm (half the width) at Y = −10   MRR =  5·2·10 = 100 mm³/s
  //   line 8  step 5 mm back                          MRR = 100 mm³/s
  //   line 11 finishing pass along the wall, 0.5 mm further out (X 15 → 15.5) from Y −5 to
  //           Y −15, where only the 0.5 mm band X 20 … 20.5 is left: 0.5·2·10 = 10 mm³/s
  const std::string p = program_file("pocket.ngc",
                                     "G21 G90\nT1 M6\nG0 X-15 Y-15 Z5\nG1 Z-2 F600\n"
                                     "G1 X15\n"            // 5: full width
                                     "G1 Y-10\nG1 X-15\n"  // 6, 7: half width
                                     "G1 Y-5\nG1 X15\n"    // 8, 9
                                     "G1 X15.5\n"          // 10: 0.5 mm into the wall
                                     "G1 Y-15\n"           // 11: finishing along the wall
                                     "G0 Z5\nM30\n");
  CuttingSimulator cut(m, p);
  PerLine per(cut);
  CuttingStage stage(cut, {&per});
  sim::run_program(p, m, {}, {&stage});
  const double slot = per.lines[5].mid_mrr(), half = per.lines[7].mid_mrr(),
               half2 = per.lines[9].mid_mrr(), finish = per.lines[11].mid_mrr();
  EXPECT_NEAR(slot, 200, 8);
  EXPECT_NEAR(half, 100, 6);
  EXPECT_NEAR(half2, 100, 6);
  EXPECT_NEAR(finish, 10, 2);
  EXPECT_GT(slot, 1.5 * half);
  EXPECT_GT(half, 5 * finish);
  // Total: the union of the swept areas × depth — the pocket floor 30×10 + slot ends...
  // checked against the map itself: removed = initial − left.
  EXPECT_NEAR(cut.stats().removed_mm3, 60.0 * 60 * 20 - cut.map().volume_mm3(), 1e-3);
}

// How much shallower than programmed a plunge that reverses (G1 Z−d, then G0 Z up) may cut,
// from the machine limits. The moving average stops at the bottom: 0. The acceleration type
// passes the reversal at its corner speed Vg = min(Amax, a_z)·τ²/2 per cycle
// (planner::turn_speed_pc with |S − E| = 2); the one step that crosses the bottom is ≤ Vg, its
// samples lie d1 above the bottom on the way down and d2 on the way up (d1 + d2 ≤ Vg), and the
// simulator sweeps the chord between them, which reaches min(d1, d2) ≤ Vg/2 above the bottom.
// Never deeper than programmed, with either type.
double reversal_shortfall_mm(const MachineConfig& m) {
  double a_mm_s2 = m.max_accel_mm_s2;
  if (m.axes[kZ].enabled && m.axes[kZ].max_accel_mm_s2 > 0) {
    a_mm_s2 = std::min(a_mm_s2, m.axes[kZ].max_accel_mm_s2);
  }
  return a_mm_s2 * m.period_s * m.period_s / 4;
}

TEST(CuttingSim, ToolChangeSelectsTheShapeFromTheTable) {
  const MachineConfig m = machine();
  // T1 (flat Ø10) plunges 2 mm at X −15, then T2 (ball Ø10) plunges 2 mm at X 15.
  const std::string p = program_file("tools.ngc",
                                     "G21 G90\nT1 M6\nG0 X-15 Y0 Z5\nG1 Z-2 F300\nG0 Z5\n"
                                     "T2 M6\nG0 X15 Y0 Z5\nG1 Z-2 F300\nG0 Z5\nM30\n");
  // Heights are floats: one ulp for 2 ≤ |z| < 4 is 2.4e-7 mm (rounding: half of it).
  const double ulp = 2 * static_cast<double>(std::numeric_limits<float>::epsilon());
  const double shortfall = reversal_shortfall_mm(m);  // 0.5 µm on this machine
  for (const motion::AccDecType accdec :
       {motion::AccDecType::kMovingAverage, motion::AccDecType::kAcceleration}) {
    SCOPED_TRACE(accdec == motion::AccDecType::kAcceleration ? "acceleration" : "moving_average");
    CuttingSimulator cut(m, p);
    sim::RunOptions o;
    o.kernel.accdec = accdec;
    sim::run_program(p, m, o, {&cut});
    const HeightMap& h = cut.map();
    const auto z = [&](double x, double y) {
      return static_cast<double>(
          h.at(static_cast<std::size_t>((x + 30) / 0.1), static_cast<std::size_t>((y + 30) / 0.1)));
    };
    // Each plunge reaches −2: at most `shortfall` above it, never below.
    const double flat_bottom = z(-15, 0), ball_bottom = z(15, 0);
    EXPECT_GE(flat_bottom, -2 - ulp);
    EXPECT_LE(flat_bottom, -2 + shortfall + ulp);
    // Flat: the same height everywhere within R (cell centre 4.05 mm away is still inside).
    EXPECT_NEAR(z(-15 + 4.0, 0.0), flat_bottom, ulp);
    // Ball: R − √(R² − r²) above the tip at a cell centre r from the axis. The shape is exact
    // whatever depth the plunge reached (every cell's lowest point is on the same chord).
    const auto sag = [](double r) { return 5 - std::sqrt(25 - r * r); };
    const double r = std::hypot(18.05 - 15, 0.05), r0 = std::hypot(0.05, 0.05);
    EXPECT_NEAR(z(18.0, 0.0) - ball_bottom, sag(r) - sag(r0), 2 * ulp);
    EXPECT_GE(ball_bottom, -2 + sag(r0) - ulp);
    EXPECT_LE(ball_bottom, -2 + sag(r0) + shortfall + ulp);
    EXPECT_EQ(cut.tool().number, 2u);
    EXPECT_EQ(cut.stats().tool_changes, 1u);  // T1 was already in the spindle
  }
}

TEST(CuttingSim, ALoadSourceForAdaptiveFeed) {
  const MachineConfig m = machine();
  const std::string p = program_file("ls.ngc", "G21 G90\nG0 X-40 Y0 Z-2\nG1 X0 F600\nM30\n");
  CuttingSimulator cut(m, p);
  feed::LoadSource& source = cut;
  bool saw_load = false;
  struct Check : sim::SampleObserver {
    Check(CuttingSimulator& c, feed::LoadSource& s, bool& f) : cut(&c), src(&s), flag(&f) {}
    void on_sample(const motion::Sample& s) override {
      EXPECT_EQ(src->load_pct(s.t_s, 0, s.feed_mm_min), s.load_pct);
      *flag = *flag || s.load_pct > 1;
    }
    CuttingSimulator* cut;
    feed::LoadSource* src;
    bool* flag;
  } check(cut, source, saw_load);
  CuttingStage stage(cut, {&check});
  sim::run_program(p, m, {}, {&stage});
  EXPECT_TRUE(saw_load);
}

// ---- bad input -------------------------------------------------------------------------------

void expect_config_error(const std::string& toml, const std::string& key, std::uint32_t line) {
  try {
    parse_machine_config(toml, "m.toml");
    ADD_FAILURE() << "accepted:\n" << toml;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.formatted();
    EXPECT_EQ(e.line(), line) << e.formatted();
  }
}

const char* kTool = "[[tools]]\nnumber = 1\ndiameter_mm = 6\n";

TEST(CuttingSimErrors, StockBoxWithZeroOrNegativeSize) {
  expect_config_error(std::string("[stock]\nmin_mm = [0, 0, 0]\nsize_mm = [10, 0, 5]\n") + kTool,
                      "stock.size_mm", 3);
  expect_config_error(std::string("[stock]\nsize_mm = [-10, 10, 5]\n") + kTool, "stock.size_mm", 2);
  expect_config_error(std::string("[stock]\ncell_mm = 0.1\n") + kTool, "stock.size_mm", 1);
  expect_config_error(std::string("[stock]\nsize_mm = [10, 10, 5]\ncell_mm = -0.1\n") + kTool,
                      "stock.cell_mm", 3);
}

TEST(CuttingSimErrors, HeightMapOverTheMemoryCap) {
  // 1000 × 1000 mm at 0.1 mm = 10⁸ cells = 381 MB > 100 MB.
  expect_config_error(
      std::string("[stock]\nsize_mm = [1000, 1000, 5]\nmax_memory_mb = 100\n") + kTool,
      "stock.max_memory_mb", 3);
  // Default cap 1024 MB: 4000 × 4000 mm at 0.1 mm = 6104 MB.
  expect_config_error(std::string("[stock]\nsize_mm = [4000, 4000, 5]\n") + kTool,
                      "stock.max_memory_mb", 1);
  // Just under the cap is fine: 2000 × 2000 cells × 4 B = 15.3 MB ≤ 16.
  EXPECT_NO_THROW(parse_machine_config(
      std::string("[stock]\nsize_mm = [200, 200, 5]\nmax_memory_mb = 16\n") + kTool, "m.toml"));
}

TEST(CuttingSimErrors, ToolTableProblems) {
  expect_config_error("[stock]\nsize_mm = [10, 10, 5]\n", "[[tools]]", 1);
  expect_config_error("[[tools]]\nnumber = 1\n", "tools[0].diameter_mm", 1);
  expect_config_error("[[tools]]\nnumber = 1\ndiameter_mm = 6\ntype = \"drill\"\n", "tools[0].type",
                      4);
  expect_config_error("[[tools]]\nnumber = 1\ndiameter_mm = 6\ntype = \"bull\"\n",
                      "corner_radius_mm", 1);
  expect_config_error(
      "[[tools]]\nnumber = 1\ndiameter_mm = 6\ntype = \"bull\"\ncorner_radius_mm = 4\n",
      "corner_radius_mm", 5);
  expect_config_error(std::string(kTool) + kTool, "listed twice", 4);
  expect_config_error(std::string(kTool) + "[cutting]\ndefault_tool = 9\n", "cutting.default_tool",
                      5);
  expect_config_error(std::string(kTool) + "[cutting]\nmaterial = \"unobtainium\"\n",
                      "cutting.material", 5);
  expect_config_error(std::string(kTool) + "[cutting]\nspindle_power_kw = 0\n",
                      "cutting.spindle_power_kw", 5);
  expect_config_error(std::string(kTool) + "[cutting]\nspeed = 1\n", "cutting.speed", 5);
}

TEST(CuttingSimErrors, ToolNumberNotInTheTableNamesTheLine) {
  const MachineConfig m = machine();
  const std::string p =
      program_file("badtool.ngc", "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F300\nT7 M6\nM30\n");
  CuttingSimulator cut(m, p);
  try {
    sim::run_program(p, m, {}, {&cut});
    ADD_FAILURE() << "T7 accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), p);
    EXPECT_EQ(e.line(), 5u) << e.formatted();
    EXPECT_NE(std::string(e.what()).find("tool 7"), std::string::npos) << e.formatted();
  }
}

TEST(CuttingConfig, RoundTripsThroughToml) {
  const MachineConfig m = machine();
  const MachineConfig back = parse_machine_config(machine_config_to_toml(m), "back.toml");
  EXPECT_EQ(back.cutting, m.cutting);
  EXPECT_EQ(
      parse_machine_config(machine_config_to_toml(default_machine_config()), "d.toml").cutting,
      default_machine_config().cutting);
}

}  // namespace
}  // namespace cncore::cut
