// Machine configuration: built-in values (spec 05), TOML round trip, and every bad key reported
// with the key's name and its FILE:LINE:COL.
#include "config/machine_config.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <fstream>
#include <string>

#include "core/error.hpp"

namespace cncore {
namespace {

TEST(MachineConfig, BuiltInIsTheSpecMill) {
  const MachineConfig c = default_machine_config();
  EXPECT_DOUBLE_EQ(c.period_s, 0.001);
  EXPECT_DOUBLE_EQ(c.max_feed_mm_min, 10000);
  EXPECT_DOUBLE_EQ(c.rapid_mm_min, 15000);
  EXPECT_DOUBLE_EQ(c.max_accel_mm_s2, 2000);
  EXPECT_DOUBLE_EQ(c.contour_tolerance_mm, 0.01);
  ASSERT_EQ(c.axis_count(), 3u);
  EXPECT_TRUE(c.axes[kX].enabled && c.axes[kY].enabled && c.axes[kZ].enabled);
  EXPECT_FALSE(c.axes[kA].enabled || c.axes[kB].enabled || c.axes[kC].enabled);
  EXPECT_DOUBLE_EQ(c.axes[kX].min_mm, -300);
  EXPECT_DOUBLE_EQ(c.axes[kX].max_mm, 300);
  EXPECT_DOUBLE_EQ(c.axes[kY].min_mm, -200);
  EXPECT_DOUBLE_EQ(c.axes[kY].max_mm, 200);
  EXPECT_DOUBLE_EQ(c.axes[kZ].min_mm, -200);
  EXPECT_DOUBLE_EQ(c.axes[kZ].max_mm, 100);
  for (std::size_t i : {kX, kY, kZ}) {
    EXPECT_DOUBLE_EQ(c.axes[i].max_speed_mm_min, 15000);
    EXPECT_DOUBLE_EQ(c.axes[i].max_accel_mm_s2, 2000);
    EXPECT_FALSE(c.axes[i].rotary);
  }
}

TEST(MachineConfig, EmptyFileIsTheBuiltIn) {
  EXPECT_EQ(parse_machine_config("", "empty.toml"), default_machine_config());
}

TEST(MachineConfig, PrintedBuiltInParsesBackEqual) {
  const MachineConfig c = default_machine_config();
  const std::string text = machine_config_to_toml(c);
  EXPECT_EQ(parse_machine_config(text, "printed.toml"), c);
}

TEST(MachineConfig, PrintedCustomParsesBackEqual) {
  MachineConfig c = default_machine_config();
  c.name = "5-axis \"test\" \\ machine";
  c.period_s = 0.0005;
  c.max_feed_mm_min = 0.1 + 0.2;  // not exactly representable in short decimal
  c.rapid_mm_min = 24000;
  c.max_accel_mm_s2 = 1234.5678901234567;
  c.max_jerk_mm_s3 = 1e-5;
  c.contour_tolerance_mm = 0.003;
  c.post_filter_s = 0.008;
  c.lookahead_blocks = 77;
  c.max_override_pct = 150;
  c.bound_resultant_accel = true;
  c.max_loop_iterations = 123456789012;
  c.max_call_depth = 9;
  c.parameters_inch = true;
  c.max_total_iterations = 98765;
  c.table_cancel_mode = TableCancelMode::kRebase;
  c.table_slow_to_fit = true;
  c.axes[kZ].enabled = false;
  c.axes[kZ] = AxisConfig{};  // a disabled axis keeps no values
  c.axes[kA] = AxisConfig{true, true, -120, 30, 3600, 720};
  c.axes[kC] = AxisConfig{true, true, -1e5, 1e5, 36000, 7200};
  c.start_position[kX] = 12.5;
  c.start_position[kA] = -90;
  const std::string text = machine_config_to_toml(c);
  const MachineConfig back = parse_machine_config(text, "printed.toml");
  EXPECT_EQ(back, c) << text;
}

TEST(MachineConfig, EveryPrintedKeyHasAComment) {
  const std::string text = machine_config_to_toml(default_machine_config());
  std::size_t pos = 0;
  int keys = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(pos, end - pos);
    if (line.find(" = ") != std::string::npos && line[0] != '#') {
      ++keys;
      EXPECT_NE(line.find(" # "), std::string::npos) << line;
    }
    pos = end + 1;
  }
  EXPECT_GE(keys, 30);  // name + 10 motion + 2 interpreter + 2 tables + 3 axes × 5
  EXPECT_NE(text.find("T = Vmax / Amax"), std::string::npos);
}

TEST(MachineConfig, ValuesAreRead) {
  const MachineConfig c = parse_machine_config(R"(
name = "small router"
[motion]
period_s = 0.002
max_feed_mm_min = 6000
max_accel_mm_s2 = 500.5
lookahead_blocks = 64
[axes.x]
min_mm = 0
max_mm = 1200
[axes.y]
max_speed_mm_min = 9000
[axes.b]
max_accel_deg_s2 = 100
start_deg = 45
[interpreter]
max_loop_iterations = 5000
[tables]
cancel_mode = "rebase"
slow_to_fit = true
)",
                                               "router.toml");
  EXPECT_EQ(c.name, "small router");
  EXPECT_DOUBLE_EQ(c.period_s, 0.002);
  EXPECT_DOUBLE_EQ(c.max_feed_mm_min, 6000);
  EXPECT_DOUBLE_EQ(c.max_accel_mm_s2, 500.5);
  EXPECT_EQ(c.lookahead_blocks, 64u);
  EXPECT_EQ(c.max_loop_iterations, 5000u);
  EXPECT_DOUBLE_EQ(c.rapid_mm_min, 15000);  // left out: default
  EXPECT_EQ(c.axis_count(), 3u);            // x, y, b: z is not listed, so disabled
  EXPECT_FALSE(c.axes[kZ].enabled);
  EXPECT_DOUBLE_EQ(c.axes[kX].min_mm, 0);
  EXPECT_DOUBLE_EQ(c.axes[kX].max_mm, 1200);
  EXPECT_DOUBLE_EQ(c.axes[kY].min_mm, -200);  // default of the built-in Y
  EXPECT_DOUBLE_EQ(c.axes[kY].max_speed_mm_min, 9000);
  EXPECT_TRUE(c.axes[kB].enabled);
  EXPECT_TRUE(c.axes[kB].rotary);
  EXPECT_DOUBLE_EQ(c.axes[kB].max_accel_mm_s2, 100);
  EXPECT_DOUBLE_EQ(c.start_position[kB], 45);
  EXPECT_EQ(c.table_cancel_mode, TableCancelMode::kRebase);
  EXPECT_TRUE(c.table_slow_to_fit);
}

TEST(MachineConfig, TablesDefaultsAreClearAndRefuse) {
  const MachineConfig c = parse_machine_config("[tables]\n", "t.toml");
  EXPECT_EQ(c.table_cancel_mode, TableCancelMode::kClear);
  EXPECT_FALSE(c.table_slow_to_fit);
  const std::string text = machine_config_to_toml(c);
  EXPECT_NE(text.find("cancel_mode = \"clear\""), std::string::npos) << text;
  EXPECT_NE(text.find("slow_to_fit = false"), std::string::npos) << text;
}

struct BadCase {
  const char* text;
  std::uint32_t line, col;
  const char* fragment;  // must appear in the message (names the key)
};

class BadConfig : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadConfig, NamesTheKeyAtItsPosition) {
  const BadCase& c = GetParam();
  try {
    parse_machine_config(c.text, "m.toml");
    FAIL() << "accepted: " << c.text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "m.toml");
    EXPECT_EQ(e.line(), c.line) << e.formatted();
    EXPECT_EQ(e.col(), c.col) << e.formatted();
    EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.formatted();
    EXPECT_EQ(e.formatted().rfind("m.toml:" + std::to_string(c.line) + ":", 0), 0u);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Keys, BadConfig,
    ::testing::Values(
        BadCase{"[motion]\nperiod_s = 0.001\n  feed = 3\n", 3, 3, "motion.feed"},
        BadCase{"colour = 1\n", 1, 1, "colour"},
        BadCase{"[motion]\nmax_accel_mm_s2 = 0\n", 2, 1, "motion.max_accel_mm_s2"},
        BadCase{"[motion]\nmax_accel_mm_s2 = -5.0\n", 2, 1, "motion.max_accel_mm_s2"},
        BadCase{"[motion]\nperiod_s = 0\n", 2, 1, "motion.period_s"},
        BadCase{"[motion]\nperiod_s = -0.001\n", 2, 1, "motion.period_s"},
        BadCase{"[motion]\nperiod_s = 0.5\n", 2, 1, "motion.period_s"},
        BadCase{"[motion]\ncontour_tolerance_mm = 0\n", 2, 1, "motion.contour_tolerance_mm"},
        BadCase{"[motion]\nlookahead_blocks = 0\n", 2, 1, "motion.lookahead_blocks"},
        BadCase{"[motion]\nlookahead_blocks = 4000000000\n", 2, 1, "motion.lookahead_blocks"},
        BadCase{"[motion]\nlookahead_blocks = 10.5\n", 2, 1, "motion.lookahead_blocks"},
        BadCase{"[motion]\nmax_feed_mm_min = \"fast\"\n", 2, 1, "motion.max_feed_mm_min"},
        BadCase{"[motion]\nmax_feed_mm_min = nan\n", 2, 1, "motion.max_feed_mm_min"},
        BadCase{"[motion]\nmax_jerk_mm_s3 = -1\n", 2, 1, "motion.max_jerk_mm_s3"},
        BadCase{"[motion]\nmax_override_pct = 50\n", 2, 1, "motion.max_override_pct"},
        BadCase{"[motion]\nbound_resultant_accel = 1\n", 2, 1, "motion.bound_resultant_accel"},
        BadCase{"[axes.x]\nmin_mm = 10\nmax_mm = 10\n", 3, 1, "axes.x.min_mm"},
        BadCase{"[axes.y]\nmin_mm = 250\n", 2, 1, "axes.y.min_mm"},
        BadCase{"[axes.z]\nstart_mm = 150\n", 2, 1, "axes.z.start_mm"},
        BadCase{"[axes.x]\nmax_accel_mm_s2 = 0\n", 2, 1, "axes.x.max_accel_mm_s2"},
        BadCase{"[axes.a]\nmin_mm = 0\n", 2, 1, "axes.a.min_mm"},
        BadCase{"[axes.w]\nmin_mm = 0\n", 1, 7, "axes.w"},
        BadCase{"[interpreter]\nmax_loop_iterations = 0\n", 2, 1,
                "interpreter.max_loop_iterations"},
        BadCase{"[interpreter]\nmax_call_depth = -3\n", 2, 1, "interpreter.max_call_depth"},
        BadCase{"[interpreter]\nparameter_units = \"furlong\"\n", 2, 1,
                "interpreter.parameter_units"},
        BadCase{"[tables]\ncancel_mode = \"keep\"\n", 2, 1, "tables.cancel_mode"},
        BadCase{"[tables]\ncancel_mode = 1\n", 2, 1, "tables.cancel_mode"},
        BadCase{"[tables]\nslow_to_fit = \"yes\"\n", 2, 1, "tables.slow_to_fit"},
        BadCase{"[tables]\nrepeat = 2\n", 2, 1, "tables.repeat"},
        BadCase{"tables = 3\n", 1, 1, "tables must be a table"},
        BadCase{"motion = 3\n", 1, 1, "motion must be a table"},
        BadCase{"[axes]\n", 1, 2, "at least one axis"},
        BadCase{"[axes.x]\nmin_mm = 0\n[axes.x.foo]\n", 3, 9, "axes.x.foo"},
        BadCase{"name = 3\n", 1, 1, "name"},
        // The cutting and adaptive sections read through the same TomlReader.
        BadCase{"[stock]\nsize_mm = [1, 2, 3]\ncolour = 1\n", 3, 1, "(keys here: min_mm,"},
        BadCase{"[stock]\nsize_mm = [1, 2]\n", 2, 1, "stock.size_mm must be an array of 3"},
        BadCase{"[[tools]]\nnumber = -1\n", 2, 1, "between 0 and 1000000000"},
        BadCase{"[cutting]\nspindle_power_kw = 0\n", 2, 1, "must be > 0 kW"},
        BadCase{"[adaptive.plant]\nseed = 1.5\n", 2, 1, "adaptive.plant.seed must be an integer"},
        BadCase{"[adaptive.plant]\nbase_pct = inf\n", 2, 1, "must be a finite number"},
        // TOML syntax errors: position of the error, message says so.
        BadCase{"[motion]\nperiod_s = = 1\n", 2, 12, "TOML syntax"},
        BadCase{"[motion\n", 1, 8, "TOML syntax"}),
    [](const ::testing::TestParamInfo<BadCase>& case_info) {
      std::string name = std::to_string(case_info.index) + "_";
      for (const char ch : std::string(case_info.param.fragment)) {
        name += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
      }
      return name;
    });

TEST(MachineConfig, MissingFileIsAnInputError) {
  try {
    load_machine_config("/nonexistent/dir/m.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/dir/m.toml");
    EXPECT_EQ(e.line(), 0u);
  }
}

TEST(MachineConfig, LoadsAFile) {
  const std::string path = std::string(CNCORE_TEST_TMP_DIR) + "/load_test.toml";
  {
    std::ofstream f(path);
    f << "[motion]\nrapid_mm_min = 20000\n";
  }
  EXPECT_DOUBLE_EQ(load_machine_config(path).rapid_mm_min, 20000);
  {
    std::ofstream f(path);
    f << "[motion]\n\nrapid_mm_min = -1\n";
  }
  try {
    load_machine_config(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.formatted().rfind(path + ":3:1: error: motion.rapid_mm_min", 0), 0u)
        << e.formatted();
  }
}

}  // namespace
}  // namespace cncore
