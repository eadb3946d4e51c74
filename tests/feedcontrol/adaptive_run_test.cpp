// Adaptive feed control through the real `cncore run` path (spec 04): the machine TOML's
// [adaptive] and [adaptive.plant], the program switch M52, the trajectory columns load,
// load_target and override, the summary's adaptive_feed object, and the errors. Everything is
// measured from the files the binary writes.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "files.hpp"
#include "program_blocks.hpp"
#include "scenario.hpp"
#include "trajectory.hpp"
#include "trajectory_checker.hpp"

namespace fs = std::filesystem;
using namespace cncore;
namespace sc = cncore::feed::scenario;
namespace ct = cncore::testing;

namespace {

struct Result {
  int code = -1;
  std::string out, err;
};

using cncore::testing::slurp;
constexpr auto write = cncore::testing::write_file;

// Columns by name; an empty field is NaN.
struct Csv {
  std::map<std::string, std::size_t> col;
  std::vector<std::vector<double>> rows;
  double at(std::size_t r, const std::string& name) const { return rows[r][col.at(name)]; }
  bool has(const std::string& name) const { return col.count(name) > 0; }
};

Csv read_csv(const fs::path& p) {
  std::ifstream in(p);
  Csv c;
  std::string line;
  std::getline(in, line);
  {
    std::stringstream h(line);
    std::string name;
    std::size_t i = 0;
    while (std::getline(h, name, ',')) c.col[name] = i++;
  }
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::size_t pos = 0;
    while (true) {
      const std::size_t comma = line.find(',', pos);
      const std::string f =
          line.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
      row.push_back(f.empty() ? std::nan("") : std::strtod(f.c_str(), nullptr));
      if (comma == std::string::npos) break;
      pos = comma + 1;
    }
    c.rows.push_back(std::move(row));
  }
  return c;
}

// The scenario of docs/adaptive-feed.md as a machine configuration: the plant with the depth
// jumping 0.5 → 2.0 mm at s = 120 mm (X = 120 on the one straight line).
std::string machine_toml(const std::string& policy, bool enabled = true) {
  const feed::PlantSettings p = sc::plant();
  std::string depth = "[";
  for (std::size_t i = 0; i < p.depth.s_mm.size(); ++i) {
    depth += (i > 0 ? ", [" : "[") + std::to_string(p.depth.s_mm[i]) + ", " +
             std::to_string(p.depth.depth_mm[i]) + "]";
  }
  depth += "]";
  return std::string("[adaptive]\n") + "enabled = " + (enabled ? "true" : "false") +
         "\n"
         "target_load_pct = 60\nkp = 1\nki = 10\nkd = 0\nconstant_pct = 100\n"
         "threshold_pct = 10\nupper_pct = 150\nlower_pct = 10\n"
         "antiwindup = \"" +
         policy +
         "\"\n"
         "control_cycles = 10\n\n"
         "[adaptive.plant]\nbase_pct = 5\nk_pct_per_mm2_min = 0.04\ntime_constant_s = 0.05\n"
         "noise_pct = 0.5\nseed = 7\ndepth = " +
         depth + "\n";
}

constexpr const char* kLine = "G21 G90 G1 X240 F1000\nM2\n";

class AdaptiveRun : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(CNCORE_TEST_TMP_DIR) / "adaptive_run" / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }

  Result run(const std::string& args) const {
    const std::string cmd =
        "cd '" + dir_.string() + "' && '" + CNCORE_BIN + "' " + args + " >.stdout 2>.stderr";
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir_ / ".stdout");
    r.err = slurp(dir_ / ".stderr");
    return r;
  }

  // The spec 01 limits checked on the written trajectory by the independent checker: path
  // speed ≤ F × the override column (with the acc/dec ramp after a decrease), accelerations.
  void expect_limits(const std::string& program, const std::string& csv,
                     const std::string& machine) const {
    const MachineConfig m = load_machine_config((dir_ / machine).string());
    const auto blocks = ct::read_blocks((dir_ / program).string(), m);
    const ct::Trajectory tr = ct::load_trajectory_csv((dir_ / csv).string());
    const ct::CheckReport rep = ct::check_trajectory(tr, blocks, ct::limits_from_config(m));
    for (auto p : {ct::Property::kSpeed, ct::Property::kAxisSpeed, ct::Property::kTangentialAccel,
                   ct::Property::kNormalAccel, ct::Property::kAxisAccel, ct::Property::kEndPoint}) {
      EXPECT_EQ(rep.count(p), 0u) << csv << ": " << ct::property_name(p) << "\n" << rep.summary();
    }
    EXPECT_LE(rep.max_tangential_accel_mm_s2, m.max_accel_mm_s2 * 1.005 + 1e-3) << csv;
    if (std::getenv("ADAPTIVE_DEBUG")) std::printf("%s\n", rep.summary().c_str());
  }

  fs::path dir_;
};

// Seconds with load > load_target + 5 % while X is on the 2 mm cut (120 ≤ X < 170).
double time_above_after_jump_s(const Csv& c) {
  double t = 0;
  for (std::size_t r = 1; r < c.rows.size(); ++r) {
    const double x = c.at(r, "x");
    if (x >= sc::kJumpUpMm && x < sc::kJumpDownMm &&
        c.at(r, "load") > c.at(r, "load_target") + sc::kOverloadBandPct) {
      t += c.at(r, "t") - c.at(r - 1, "t");
    }
  }
  return t;
}

TEST_F(AdaptiveRun, BackCalculationHalvesTheOverloadOfClampAndLimitsHold) {
  write(dir_ / "line.ngc", kLine);
  std::map<std::string, double> above, cycle_s;
  for (const std::string policy : {"none", "clamp", "back_calculation"}) {
    write(dir_ / (policy + ".toml"), machine_toml(policy));
    const Result r = run("run line.ngc --machine " + policy + ".toml --trajectory " + policy +
                         ".csv --summary " + policy + ".json");
    ASSERT_EQ(r.code, 0) << r.err;
    const Csv c = read_csv(dir_ / (policy + ".csv"));
    ASSERT_TRUE(c.has("load") && c.has("load_target") && c.has("override")) << policy;
    ASSERT_GT(c.rows.size(), 5000u);
    above[policy] = time_above_after_jump_s(c);
    double max_override = 0;
    for (std::size_t i = 0; i < c.rows.size(); ++i) {
      ASSERT_EQ(c.at(i, "load_target"), 60) << policy << " row " << i;
      max_override = std::max(max_override, c.at(i, "override"));
    }
    // The controller is really in the loop: it raised the override on the light cut.
    EXPECT_GT(max_override, policy == "none" ? 200 - 1e-9 : 150 - 1e-9) << policy;
    if (policy != "none") {
      EXPECT_LE(max_override, 150 + 1e-9) << policy;
    }
    expect_limits("line.ngc", policy + ".csv", policy + ".toml");

    const auto j = nlohmann::json::parse(slurp(dir_ / (policy + ".json")));
    const auto& a = j.at("adaptive_feed");
    EXPECT_EQ(a.at("adaptive"), true);
    EXPECT_EQ(a.at("antiwindup"), policy);
    cycle_s[policy] = j.at("cycle_time_s");
    // Time saved = the same run with the operator's override alone − this run.
    EXPECT_NEAR(a.at("time_saved_s").get<double>(),
                a.at("time_without_adaptive_s").get<double>() - cycle_s[policy], 1e-9);
    EXPECT_GT(a.at("time_saved_s").get<double>(), 0.5) << policy;
    EXPECT_GT(a.at("peak_load_pct").get<double>(), 60) << policy;
    EXPECT_GE(a.at("time_above_target_s").get<double>(),
              a.at("time_above_target_plus5_s").get<double>());
  }
  std::printf(
      "cncore run, time with load > target + 5 %% after the jump: none %.3f s, clamp %.3f s, "
      "back_calculation %.3f s; ratio back_calculation / clamp = %.3f\n",
      above["none"], above["clamp"], above["back_calculation"],
      above["back_calculation"] / above["clamp"]);
  EXPECT_GT(above["clamp"], 0.5);
  EXPECT_LE(above["back_calculation"], 0.5 * above["clamp"]);

  // The reference time is a real run without the controller: --adaptive off gives it.
  const Result off = run("run line.ngc --machine clamp.toml --adaptive off --summary off.json");
  ASSERT_EQ(off.code, 0) << off.err;
  const auto j_off = nlohmann::json::parse(slurp(dir_ / "off.json"));
  const auto j_clamp = nlohmann::json::parse(slurp(dir_ / "clamp.json"));
  EXPECT_NEAR(j_clamp.at("adaptive_feed").at("time_without_adaptive_s").get<double>(),
              j_off.at("cycle_time_s").get<double>(), 1e-9);
  EXPECT_EQ(j_off.at("adaptive_feed").at("adaptive"), false);
  // 240 mm at F1000 and 100 %: at least 14.4 s.
  EXPECT_GT(j_off.at("cycle_time_s").get<double>(), 14.4);
}

TEST_F(AdaptiveRun, LimitsHoldWhateverTheControllerAsksOnArcsAndCorners) {
  // The pocket example (tangent arcs, plunges, rapids) with a depth that jumps between 0.2 and
  // 2 mm every 15 mm of path and an eager controller without adaptive limits (override swings
  // between 0 and the machine's 200 %), and with back-calculation between 10 and 200 %.
  fs::copy_file(fs::path(CNCORE_SOURCE_DIR) / "examples/pocket-with-arcs.ngc", dir_ / "p.ngc");
  std::string depth = "[";
  for (int k = 0; k < 40; ++k) {
    const double d = k % 2 == 0 ? 0.2 : 2.0;
    depth += (k > 0 ? ", " : "") + std::string("[") + std::to_string(15 * k) + ", " +
             std::to_string(d) + "], [" + std::to_string(15 * (k + 1)) + ", " + std::to_string(d) +
             "]";
  }
  depth += "]";
  for (const std::string policy : {"none", "back_calculation"}) {
    write(dir_ / "m.toml",
          "[adaptive]\nenabled = true\nkp = 2\nki = 20\nkd = 0.02\n"
          "upper_pct = 200\nantiwindup = \"" +
              policy +
              "\"\ncontrol_cycles = 5\n"
              "[adaptive.plant]\nnoise_pct = 2\ntime_constant_s = 0.02\n"
              "depth = " +
              depth + "\n");
    const Result r = run("run p.ngc --machine m.toml --trajectory t.csv");
    ASSERT_EQ(r.code, 0) << r.err;
    const Csv c = read_csv(dir_ / "t.csv");
    double lo = 1e9, hi = 0;
    for (std::size_t i = 0; i < c.rows.size(); ++i) {
      lo = std::min(lo, c.at(i, "override"));
      hi = std::max(hi, c.at(i, "override"));
    }
    EXPECT_LT(lo, 60) << policy;  // the controller really swings the override
    EXPECT_GT(hi, 190) << policy;
    expect_limits("p.ngc", "t.csv", "m.toml");
  }
}

TEST_F(AdaptiveRun, BelowThresholdTheOverrideIsTheOperators) {
  write(dir_ / "line.ngc", kLine);
  write(dir_ / "m.toml", machine_toml("back_calculation"));
  const Result r = run("run line.ngc --machine m.toml --override 80 --trajectory t.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv c = read_csv(dir_ / "t.csv");
  // Rows whose load, and the load of the control period before them, is below lm = 10 %: the
  // controller last decided on a load below lm, so the override must be the operator's 80 %.
  std::size_t checked = 0, below_run = 0;
  std::size_t cutting = 0;
  for (std::size_t i = 0; i < c.rows.size(); ++i) {
    below_run = c.at(i, "load") < 10 ? below_run + 1 : 0;
    if (below_run > 11) {
      ASSERT_EQ(c.at(i, "override"), 80) << "row " << i << " x " << c.at(i, "x");
      ++checked;
    }
    if (c.at(i, "override") != 80) ++cutting;
  }
  EXPECT_GT(checked, 500u);   // air before X10 and after X220
  EXPECT_GT(cutting, 1000u);  // and the controller did act while cutting
}

TEST_F(AdaptiveRun, M52OffSectionRunsAtTheOperatorsOverride) {
  // On from the start (config), off from X100 to X180 (M52 P0), on again (M52 P1, no P = on).
  // The operator turns the override from 90 to 70 % at t = 7 s, inside the off section (which
  // runs from about 4.5 to 9.8 s).
  write(dir_ / "m52.ngc", "G21 G90 G1 X100 F1000\nM52 P0\nX180\nM52\nX240\nM2\n");
  write(dir_ / "m.toml", machine_toml("back_calculation"));
  const Result r =
      run("run m52.ngc --machine m.toml --override 90 --override-at 7:70 --trajectory t.csv "
          "--summary s.json");
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv c = read_csv(dir_ / "t.csv");
  std::size_t off_rows = 0, adapted_before = 0, adapted_after = 0;
  for (std::size_t i = 0; i < c.rows.size(); ++i) {
    const double x = c.at(i, "x"), o = c.at(i, "override"), t = c.at(i, "t");
    // The switch acts from the cycle after the one that passes X100; one cycle moves < 0.05 mm.
    // The step at 7 s is set before the cycle at t = 7 and runs from the next one.
    const double operator_pct = t < 7.0005 ? 90 : 70;
    if (x > 100.1 && x < 179.9) {
      ASSERT_EQ(o, operator_pct) << "row " << i << " x " << x << " t " << t;
      ++off_rows;
    }
    if (x > 20 && x < 99 && o != operator_pct) ++adapted_before;
    if (x > 185 && x < 215 && o != operator_pct) ++adapted_after;
  }
  EXPECT_GT(off_rows, 3000u);
  EXPECT_GT(adapted_before, 1000u);
  EXPECT_GT(adapted_after, 500u);
  const auto j = nlohmann::json::parse(slurp(dir_ / "s.json"));
  EXPECT_EQ(j.at("adaptive_feed").at("m52_switches"), 2);
  expect_limits("m52.ngc", "t.csv", "m.toml");

  // Off in the configuration, on from X60 by the program.
  write(dir_ / "on.ngc", "G21 G90 G1 X60 F1000\nM52 P1\nX240\nM2\n");
  write(dir_ / "off.toml", machine_toml("back_calculation", false));
  const Result r2 = run("run on.ngc --machine off.toml --trajectory t2.csv");
  ASSERT_EQ(r2.code, 0) << r2.err;
  const Csv c2 = read_csv(dir_ / "t2.csv");
  std::size_t adapted = 0;
  for (std::size_t i = 0; i < c2.rows.size(); ++i) {
    if (c2.at(i, "x") < 59.9) {
      ASSERT_EQ(c2.at(i, "override"), 100) << "row " << i;
    }
    if (c2.at(i, "x") > 61 && c2.at(i, "override") != 100) ++adapted;
  }
  EXPECT_GT(adapted, 1000u);

  // check --blocks shows the switch with its P.
  const Result blocks = run("check --blocks m52.ngc");
  ASSERT_EQ(blocks.code, 0) << blocks.err;
  EXPECT_NE(blocks.out.find("N2 AUX M52 P0"), std::string::npos) << blocks.out;
  EXPECT_NE(blocks.out.find("N4 AUX M52 P1"), std::string::npos) << blocks.out;
}

TEST_F(AdaptiveRun, RecordedLoadFileDrivesTheController) {
  // A recorded load against path distance: air, then 90 % (overload) from s = 50 mm.
  write(dir_ / "load.csv", "s_mm,load_pct\n0,0\n50,0\n50,90\n70,90\n");
  write(dir_ / "line.ngc", "G21 G90 G1 X70 F1000\nM2\n");
  write(dir_ / "m.toml", "[adaptive]\nenabled = true\nki = 10\n");
  const Result r = run("run line.ngc --machine m.toml --load load.csv --trajectory t.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const Csv c = read_csv(dir_ / "t.csv");
  double min_override = 1e9;
  for (std::size_t i = 0; i < c.rows.size(); ++i) {
    const double x = c.at(i, "x");
    if (x < 49.9) {
      ASSERT_EQ(c.at(i, "override"), 100) << "row " << i;
    }
    // The recorded load is read at the tool's path distance (interpolated, held after).
    if (x > 50.1) {
      ASSERT_NEAR(c.at(i, "load"), 90, 1e-9) << "row " << i;
      min_override = std::min(min_override, c.at(i, "override"));
    }
  }
  // A load the feed cannot change: the integral drives the override down to the lower limit.
  EXPECT_NEAR(min_override, 10, 1e-9);
  EXPECT_NE(r.out.find("adaptive feed"), std::string::npos) << r.out;
}

TEST_F(AdaptiveRun, BadInputIsRejectedWithItsPlace) {
  write(dir_ / "line.ngc", kLine);
  struct Case {
    std::string toml, where, text;
  };
  const std::vector<Case> cases = {
      {"[adaptive]\nlower_pct = 50\nupper_pct = 40\n", "m.toml:3:1:", "adaptive.upper_pct"},
      {"[adaptive]\ntarget_load_pct = -5\n", "m.toml:2:1:", "adaptive.target_load_pct"},
      {"[adaptive]\nantiwindup = \"back_calculation\"\n  ki = 0\n", "m.toml:3:3:", "adaptive.ki"},
      {"[adaptive]\nantiwindup = \"sometimes\"\n", "m.toml:2:1:", "adaptive.antiwindup"},
      {"[adaptive]\ncontrol_cycles = 0\n", "m.toml:2:1:", "adaptive.control_cycles"},
      {"[adaptive]\nspeed = 1\n", "m.toml:2:1:", "adaptive.speed"},
      {"[motion]\nmax_override_pct = 120\n[adaptive]\nupper_pct = 130\n",
       "m.toml:4:1:", "adaptive.upper_pct"},
      {"[adaptive.plant]\ndepth = [[0, 1], [10, \"deep\"]]\n",
       "m.toml:2:", "adaptive.plant.depth point 2"},
      {"[adaptive.plant]\ndepth = [[0, 1], [-1, 2]]\n", "m.toml:2:1:", "adaptive.plant.depth"},
      {"[adaptive.plant]\nnoise_pct = -1\ndepth = [[0, 1]]\n",
       "m.toml:2:1:", "adaptive.plant.noise_pct"},
  };
  for (const Case& k : cases) {
    write(dir_ / "m.toml", k.toml);
    const Result r = run("run line.ngc --machine m.toml --trajectory t.csv");
    EXPECT_EQ(r.code, 1) << k.toml << r.err;
    EXPECT_EQ(r.err.rfind(k.where, 0), 0u) << k.toml << r.err;
    EXPECT_NE(r.err.find(k.text), std::string::npos) << k.toml << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "t.csv"));
  }

  // Load files: text, an empty field, time going backwards, a bad header.
  write(dir_ / "m.toml", "[adaptive]\nenabled = true\n");
  const std::vector<std::pair<std::string, std::string>> loads = {
      {"t_s,load_pct\n0,10\n1,abc\n", "load.csv:3:3:"},
      {"t_s,load_pct\n0,10\n1,\n", "load.csv:3:3:"},
      {"t_s,load_pct\n0,10\n2,20\n1.5,30\n", "load.csv:4:1:"},
      {"time,load\n0,10\n", "load.csv:1:1:"},
  };
  for (const auto& [text, where] : loads) {
    write(dir_ / "load.csv", text);
    const Result r = run("run line.ngc --machine m.toml --load load.csv --trajectory t.csv");
    EXPECT_EQ(r.code, 1) << text << r.err;
    EXPECT_EQ(r.err.rfind(where, 0), 0u) << text << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "t.csv"));
  }
  EXPECT_EQ(run("run line.ngc --load missing.csv").code, 1);
  // A recorded overload that never ends and no lower limit (none): the feed stops for good.
  // An input error at the program line, not a kernel fault.
  write(dir_ / "hi.csv", "t_s,load_pct\n0,90\n");
  write(dir_ / "none.toml", "[adaptive]\nenabled = true\nantiwindup = \"none\"\n");
  const Result stall = run("run line.ngc --machine none.toml --load hi.csv --trajectory t.csv");
  EXPECT_EQ(stall.code, 1) << stall.err;
  EXPECT_EQ(stall.err.rfind("line.ngc:1:1: error: adaptive feed control has held", 0), 0u)
      << stall.err;
  EXPECT_FALSE(fs::exists(dir_ / "t.csv"));

  // Usage: --adaptive on without a load source; a bad --adaptive value.
  EXPECT_EQ(run("run line.ngc --adaptive on").code, 2);
  EXPECT_EQ(run("run line.ngc --adaptive maybe").code, 2);

  // The program switch: P other than 0/1, P shared with G4.
  write(dir_ / "p2.ngc", "G1 X1 F100\nM52 P2\n");
  const Result p2 = run("check p2.ngc");
  EXPECT_EQ(p2.code, 1);
  EXPECT_EQ(p2.err.rfind("p2.ngc:2:5:", 0), 0u) << p2.err;
  write(dir_ / "g4.ngc", "G4 P1 M52\n");
  const Result g4 = run("check g4.ngc");
  EXPECT_EQ(g4.code, 1);
  EXPECT_NE(g4.err.find("P word"), std::string::npos) << g4.err;
}

TEST_F(AdaptiveRun, BundledExamplesRun) {
  const std::string ex = std::string(CNCORE_SOURCE_DIR) + "/examples/adaptive/";
  const Result r = run("run '" + ex + "m52.ngc' --machine '" + ex + "plant.toml' --summary s.json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "s.json"));
  EXPECT_EQ(j.at("adaptive_feed").at("m52_switches"), 2);
  EXPECT_EQ(j.at("adaptive_feed").at("load_source"), "plant model");
  const Result rec = run("run '" + ex + "line.ngc' --load '" + ex +
                         "load-by-distance.csv' --adaptive on --summary r.json");
  ASSERT_EQ(rec.code, 0) << rec.err;
  const auto jr = nlohmann::json::parse(slurp(dir_ / "r.json"));
  EXPECT_NEAR(jr.at("adaptive_feed").at("peak_load_pct").get<double>(), 85, 1e-9);
}

TEST(AdaptiveConfig, PrintedConfigurationReadsBackEqual) {
  MachineConfig c = default_machine_config();
  c.adaptive.enabled = true;
  c.adaptive.target_load_pct = 72.5;
  c.adaptive.kp = 0.3;
  c.adaptive.ki = 12.25;
  c.adaptive.kd = 0.01;
  c.adaptive.constant_pct = 90;
  c.adaptive.threshold_pct = 7;
  c.adaptive.upper_pct = 180;
  c.adaptive.lower_pct = 20;
  c.adaptive.antiwindup = feed::AntiWindup::kClamp;
  c.adaptive.control_cycles = 4;
  c.adaptive_plant = sc::plant();
  c.adaptive_plant.seed = 123456789012345ULL;
  const std::string text = machine_config_to_toml(c);
  const MachineConfig back = parse_machine_config(text, "printed.toml");
  EXPECT_TRUE(back.adaptive == c.adaptive) << text;
  EXPECT_TRUE(back.adaptive_plant == c.adaptive_plant) << text;
  EXPECT_TRUE(back == c);
  // The built-in machine: [adaptive] printed, the plant only as a commented example.
  const MachineConfig d = default_machine_config();
  const std::string dt = machine_config_to_toml(d);
  EXPECT_NE(dt.find("\n[adaptive]\n"), std::string::npos);
  EXPECT_EQ(dt.find("\n[adaptive.plant]"), std::string::npos);
  EXPECT_NE(dt.find("\n# [adaptive.plant]"), std::string::npos);
  EXPECT_TRUE(parse_machine_config(dt, "builtin.toml") == d);
}

}  // namespace
