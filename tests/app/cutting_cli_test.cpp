// `cncore run` with the cutting simulation: outputs (PNG, grid, load column, summary
// keys), errors (tool not in the table, stock box, --heightmap without a stock) leave no files,
// and adaptive feed on the simulated cut of a real corpus program reports the time saved.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "files.hpp"

namespace {

namespace fs = std::filesystem;

struct Result {
  int code = -1;
  std::string out, err;
};

using cncore::testing::slurp;
constexpr auto quote = cncore::testing::shell_quote;

const char* kMill = R"([stock]
min_mm = [-30, -30, -20]
size_mm = [60, 60, 20]
cell_mm = 0.1

[cutting]
material = "aluminium_6061"
spindle_power_kw = 5.5

[[tools]]
number = 1
type = "flat"
diameter_mm = 10

[[tools]]
number = 2
type = "ball"
diameter_mm = 6
)";

// Slot across the stock at Y 0, 2 mm deep, F600: MRR 10·2·10 = 200 mm³/s, load
// 700·200/1000 W / 5500 W = 2.545 %; then a ball plunge 1 mm deep with T2.
const char* kProgram =
    "G21 G90\nT1 M6\nG0 X-40 Y0 Z5\nG1 Z-2 F600\nG1 X40\nG0 Z5\n"
    "T2 M6\nG0 X0 Y15 Z5\nG1 Z-1 F300\nG0 Z5\nM30\n";

class CuttingCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(CNCORE_TEST_TMP_DIR) / "cutting" / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    write("mill.toml", kMill);
    write("part.ngc", kProgram);
  }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }
  Result run(const std::string& args) const {
    const std::string cmd = "cd " + quote(dir_.string()) + " && " + quote(CNCORE_BIN) + " " + args +
                            " >" + quote((dir_ / ".stdout").string()) + " 2>" +
                            quote((dir_ / ".stderr").string());
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir_ / ".stdout");
    r.err = slurp(dir_ / ".stderr");
    fs::remove(dir_ / ".stdout");
    fs::remove(dir_ / ".stderr");
    return r;
  }
  std::size_t files() const {
    std::size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir_)) n += e.is_regular_file() ? 1 : 0;
    return n;
  }
  fs::path dir_;
};

TEST_F(CuttingCli, WritesHeightMapGridLoadColumnAndSummary) {
  const Result r =
      run("run part.ngc --machine mill.toml --heightmap top.png --heightmap-grid grid.csv "
          "--heightmap-grid grid.bin --trajectory traj.csv --summary sum.json");
  ASSERT_EQ(r.code, 2) << "--heightmap-grid given twice must be a usage error\n" << r.err;
  const Result ok =
      run("run part.ngc --machine mill.toml --heightmap top.png --heightmap-grid grid.csv "
          "--trajectory traj.csv --summary sum.json");
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(ok.out.find("cutting       removed"), std::string::npos) << ok.out;

  // PNG: signature and the 600 × 600 size in IHDR.
  const std::string png = slurp(dir_ / "top.png");
  ASSERT_GT(png.size(), 33u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const auto be32 = [&](std::size_t at) {
    return (std::uint32_t(std::uint8_t(png[at])) << 24) |
           (std::uint32_t(std::uint8_t(png[at + 1])) << 16) |
           (std::uint32_t(std::uint8_t(png[at + 2])) << 8) |
           std::uint32_t(std::uint8_t(png[at + 3]));
  };
  EXPECT_EQ(be32(16), 600u);
  EXPECT_EQ(be32(20), 600u);

  // Grid: 600 rows of 600 heights; the slot floor at −2 (row of Y 0.05, X 0.05), the ball
  // dimple's centre at −1 (X 0.05, Y 15.05: −1 + 3 − √(9 − 0.005) ≈ −0.99917), top elsewhere.
  // The grid has 4 decimals (±0.5e-4). The slot's plunge turns 90° into the slot, whose floor
  // is exact; the dimple's plunge reverses (G1 Z−1, G0 Z5), and a reversal may leave it
  // shallower by up to a quarter of min(Amax, a_z)·τ² (0.5 µm here): the moving average stops
  // at the bottom, the acceleration type crosses it in one step ≤ its corner speed
  // min(Amax, a_z)·τ²/2 and the cut sweeps the chord of that step, which misses the bottom by
  // at most half of it. Never deeper.
  const cncore::MachineConfig m = cncore::parse_machine_config(kMill, "mill.toml");
  const double a_z_mm_s2 = m.axes[cncore::kZ].max_accel_mm_s2;
  const double a_mm_s2 = a_z_mm_s2 > 0 ? std::min(m.max_accel_mm_s2, a_z_mm_s2) : m.max_accel_mm_s2;
  const double shortfall = a_mm_s2 * m.period_s * m.period_s / 4;
  const double rounding = 0.5e-4 + 1e-12;
  std::ifstream grid(dir_ / "grid.csv");
  std::string line;
  std::vector<std::vector<double>> rows;
  while (std::getline(grid, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<double> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  ASSERT_EQ(rows.size(), 600u);
  ASSERT_EQ(rows[0].size(), 600u);
  EXPECT_NEAR(rows[300][300], -2, 1e-4);
  const double dimple = -1 + 3 - std::sqrt(9 - 0.05 * 0.05 * 2);
  EXPECT_GE(rows[450][300], dimple - rounding);
  EXPECT_LE(rows[450][300], dimple + shortfall + rounding);
  EXPECT_NEAR(rows[599][0], 0, 1e-9);

  // Summary: the cutting object and the load figures.
  const auto j = nlohmann::json::parse(slurp(dir_ / "sum.json"));
  ASSERT_TRUE(j.contains("cutting")) << j.dump(2);
  const auto& c = j["cutting"];
  // The slot: w·d·L = 10·2·60 = 1200 mm³ within h·d·L = 12; the dimple: a cap of R 3, 1 deep:
  // π·1·(9 − 1)/3 = 8.38 mm³.
  EXPECT_NEAR(c["removed_mm3"].get<double>(), 1200 + 8.38, 12 + 0.5);
  const double load = 100 * 700 * 200 / 1000.0 / 5500;
  EXPECT_GT(c["peak_load_pct"].get<double>(), 0.95 * load);
  EXPECT_EQ(c["final_tool"].get<int>(), 2);
  EXPECT_GT(c["mean_load_pct"].get<double>(), 0);
  EXPECT_LT(c["mean_load_pct"].get<double>(), c["mean_cutting_load_pct"].get<double>());

  // Trajectory: a load column, 2.545 % in the middle of the slot (X 0).
  std::ifstream traj(dir_ / "traj.csv");
  std::getline(traj, line);
  std::vector<std::string> names;
  {
    std::stringstream ss(line);
    std::string n;
    while (std::getline(ss, n, ',')) names.push_back(n);
  }
  const auto col = [&](const std::string& n) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
  };
  ASSERT_LT(col("load"), names.size()) << line;
  bool checked = false;
  while (std::getline(traj, line)) {
    std::vector<std::string> v;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) v.push_back(cell);
    if (std::stod(v[col("line")]) == 5 && std::fabs(std::stod(v[col("x")])) < 0.02) {
      EXPECT_NEAR(std::stod(v[col("load")]), load, 0.02 * load) << line;
      checked = true;
    }
  }
  EXPECT_TRUE(checked);
}

TEST_F(CuttingCli, ToolNotInTheTableIsAnErrorAtItsLineAndWritesNothing) {
  write("bad.ngc", "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F300\nT7 M6\nM30\n");
  const std::size_t before = files();
  const Result r = run("run bad.ngc --machine mill.toml --heightmap top.png --summary s.json");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.err.find("bad.ngc:5:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("tool 7"), std::string::npos) << r.err;
  EXPECT_EQ(files(), before);
}

TEST_F(CuttingCli, StockErrorsNameTheKey) {
  write("zero.toml", "[stock]\nsize_mm = [60, 0, 20]\n[[tools]]\nnumber = 1\ndiameter_mm = 6\n");
  Result r = run("run part.ngc --machine zero.toml");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("zero.toml:2:1: error: stock.size_mm"), std::string::npos) << r.err;
  write("big.toml",
        "[stock]\nsize_mm = [600, 600, 20]\ncell_mm = 0.01\nmax_memory_mb = 64\n"
        "[[tools]]\nnumber = 1\ndiameter_mm = 6\n");
  r = run("run part.ngc --machine big.toml");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("big.toml:4:1: error:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("stock.max_memory_mb"), std::string::npos) << r.err;
  // --heightmap without a stock: a usage error.
  r = run("run part.ngc --heightmap top.png");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("[stock]"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "top.png"));
}

TEST_F(CuttingCli, CuttingAloneIgnoresAdaptiveSettingsItDoesNotUse) {
  // The default adaptive.upper_pct (150) exceeds this machine's max_override_pct: only an
  // error when adaptive control is asked for.
  write("m120.toml", std::string(kMill) + "\n[motion]\nmax_override_pct = 120\n");
  const Result r = run("run part.ngc --machine m120.toml");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("cutting       removed"), std::string::npos) << r.out;
  const Result on = run("run part.ngc --machine m120.toml --adaptive on");
  EXPECT_EQ(on.code, 1) << on.out;
  EXPECT_NE(on.err.find("adaptive.upper_pct"), std::string::npos) << on.err;
}

// Adaptive feed on camotics/bear.nc with each acc/dec type (--accdec). The target is 60 %: the
// program's flat passes at the full programmed feed load the spindle to 40–60 % (the acceleration
// type spends 35.3 s of its 37.6 s at F there, the moving average 22.3 of 23.2 s), so a 60 %
// target lets the controller raise the feed on them. At a 40 % target it must lower it there
// instead, and the light cuts lie on the steep relief, where 0.3–0.5 mm segments with corners
// keep the tool below F: the acceleration type already runs them at Amax, so raising the
// override gains nothing (127.5 s at a mean override of 141 % saved 0.07 s) and the run is
// 0.95 s longer; the moving average saves 4.9 s there only because its ramps steepen with the
// override (F·OR·Amax/Vmax: 1190 mm/s² at 100 %, 1770 mm/s² at 150 %, measured).
class CuttingCliAdaptive : public CuttingCli, public ::testing::WithParamInterface<const char*> {};

TEST_P(CuttingCliAdaptive, AdaptiveFeedOnTheSimulatedCutOfARealProgram) {
  // camotics/bear.nc (3D relief raster, F6000) on a stock whose top is 2 mm above the relief's
  // highest point, so the tool cuts all the way; cells of 0.5 mm keep the test short.
  const fs::path bear = fs::path(CNCORE_SHARED_DIR) / "testdata/gcode/camotics/bear.nc";
  if (!fs::exists(bear)) GTEST_SKIP() << bear << " absent (shared corpus)";
  write("bear.toml",
        "[stock]\nmin_mm = [-10, -10, -20]\nsize_mm = [100, 100, 14]\ncell_mm = 0.5\n"
        "[cutting]\nmaterial = \"steel_1045\"\nspindle_power_kw = 3\n"
        "[adaptive]\ntarget_load_pct = 60\n"
        "[[tools]]\nnumber = 1\ntype = \"ball\"\ndiameter_mm = 6\n");
  const std::string accdec = GetParam();
  const std::string common =
      "run " + quote(bear.string()) + " --machine bear.toml --accdec " + accdec;
  const Result off = run(common + " --summary off.json");
  ASSERT_EQ(off.code, 0) << off.err;
  const Result on = run(common + " --adaptive on --summary on.json");
  ASSERT_EQ(on.code, 0) << on.err;
  const auto j_off = nlohmann::json::parse(slurp(dir_ / "off.json"));
  const auto j_on = nlohmann::json::parse(slurp(dir_ / "on.json"));
  const auto& a = j_on["adaptive_feed"];
  std::printf(
      "bear.nc, %s: %.1f s without adaptive feed, %.1f s with it (saved %.1f s); time above "
      "the 60 %% target %.2f s (+5 %%: %.2f s), peak load %.0f %%; without: peak %.0f %%\n",
      accdec.c_str(), a["time_without_adaptive_s"].get<double>(),
      j_on["cycle_time_s"].get<double>(), a["time_saved_s"].get<double>(),
      a["time_above_target_s"].get<double>(), a["time_above_target_plus5_s"].get<double>(),
      j_on["cutting"]["peak_load_pct"].get<double>(),
      j_off["cutting"]["peak_load_pct"].get<double>());
  EXPECT_TRUE(a["adaptive"].get<bool>());
  EXPECT_EQ(a["load_source"].get<std::string>(), "cutting simulation");
  // The run without adaptive control is the plain run (of the same acc/dec type).
  EXPECT_NEAR(a["time_without_adaptive_s"].get<double>(), j_off["cycle_time_s"].get<double>(),
              1e-9);
  EXPECT_GT(a["time_saved_s"].get<double>(), 0);
  // Adaptive control removes the same material (the same path), at a different pace.
  EXPECT_NEAR(j_on["cutting"]["removed_mm3"].get<double>(),
              j_off["cutting"]["removed_mm3"].get<double>(),
              0.01 * j_off["cutting"]["removed_mm3"].get<double>());
}

INSTANTIATE_TEST_SUITE_P(BothAccDecTypes, CuttingCliAdaptive,
                         ::testing::Values("moving_average", "acceleration"),
                         [](const ::testing::TestParamInfo<const char*>& p) {
                           return std::string(p.param);
                         });

}  // namespace
