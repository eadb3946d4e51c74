// Trajectory CSV: columns by name (spec 05), one row per sample, optional columns only when
// active, numbers with 1e-6 mm resolution.
#include "io/trajectory_csv.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "test_dir.hpp"

namespace cncore::io {
namespace {

using test::fresh_dir;
using test::list_dir;
using test::slurp;

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (const char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

// Rows as maps column name → cell text.
std::vector<std::map<std::string, std::string>> read_csv(const std::string& text,
                                                         std::vector<std::string>* header_out) {
  std::vector<std::string> lines = split(text, '\n');
  EXPECT_TRUE(!lines.empty() && lines.back().empty()) << "file must end with a newline";
  lines.pop_back();
  const std::vector<std::string> header = split(lines.at(0), ',');
  if (header_out) *header_out = header;
  std::vector<std::map<std::string, std::string>> rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto cells = split(lines[i], ',');
    EXPECT_EQ(cells.size(), header.size()) << lines[i];
    std::map<std::string, std::string> row;
    for (std::size_t k = 0; k < header.size() && k < cells.size(); ++k) row[header[k]] = cells[k];
    rows.push_back(row);
  }
  return rows;
}

motion::Sample sample(double t, std::uint32_t line, double x, double y, double z, double feed) {
  motion::Sample s;
  s.t_s = t;
  s.line = line;
  s.position[kX] = x;
  s.position[kY] = y;
  s.position[kZ] = z;
  s.path_position = s.position;
  s.feed_mm_min = feed;
  return s;
}

TEST(TrajectoryCsv, RequiredColumnsByNameOneRowPerSample) {
  const auto dir = fresh_dir();
  const auto path = dir / "traj.csv";
  const MachineConfig m = default_machine_config();
  TrajectoryCsvWriter w(path.string(), m, {});
  w.on_sample(sample(0, 0, 0, 0, 0, 0));
  w.on_sample(sample(0.001, 7, 123.4567891, -0.5, -1e-9, 6000.04));
  w.on_sample(sample(0.002, 12, -299.9999994, 199.25, 100, 0));
  w.on_finish();
  EXPECT_FALSE(std::filesystem::exists(path)) << "not before commit";
  w.commit();
  std::vector<std::string> header;
  const auto rows = read_csv(slurp(path), &header);
  EXPECT_EQ(header, (std::vector<std::string>{"t", "line", "x", "y", "z", "feed"}));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].at("t"), "0.000000");
  EXPECT_EQ(rows[1].at("t"), "0.001000");
  EXPECT_EQ(rows[1].at("line"), "7");
  EXPECT_EQ(rows[1].at("x"), "123.456789");
  EXPECT_EQ(rows[1].at("y"), "-0.500000");
  EXPECT_EQ(rows[1].at("z"), "0.000000");  // -1e-9 rounds to zero without a minus sign
  EXPECT_DOUBLE_EQ(std::stod(rows[1].at("feed")), 6000.04);
  EXPECT_EQ(rows[2].at("x"), "-299.999999");
  EXPECT_EQ(rows[2].at("line"), "12");
  EXPECT_EQ(list_dir(dir), std::vector<std::string>{"traj.csv"});
}

TEST(TrajectoryCsv, FixedDecimalsRoundToNearest) {
  const auto dir = fresh_dir();
  const auto path = dir / "traj.csv";
  TrajectoryCsvWriter w(path.string(), default_machine_config(), {});
  w.on_sample(sample(1.0000005001, 4294967295u, -0.0000006, 0.0000015, 1e13, -0.0004));
  w.on_sample(sample(2, 1, -12.3456785, 99.9999996, -0.5e-6 + 1e-12, 12.3456));
  w.commit();
  const auto rows = read_csv(slurp(path), nullptr);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("t"), "1.000001");
  EXPECT_EQ(rows[0].at("line"), "4294967295");
  EXPECT_EQ(rows[0].at("x"), "-0.000001");
  EXPECT_EQ(rows[0].at("y"), "0.000002");  // 1.5e-6 is stored a hair above: rounds up
  EXPECT_EQ(rows[0].at("z"), "10000000000000.000000");
  EXPECT_EQ(rows[0].at("feed"), "0.000");  // −0.0004 rounds to 0, without a minus sign
  EXPECT_EQ(rows[1].at("x").substr(0, 9), "-12.34567");
  EXPECT_EQ(rows[1].at("y"), "100.000000");
  EXPECT_EQ(rows[1].at("z"), "0.000000");
  EXPECT_EQ(rows[1].at("feed"), "12.346");
}

TEST(TrajectoryCsv, OptionalColumnsAndConfiguredAxes) {
  const auto dir = fresh_dir();
  const auto path = dir / "traj.csv";
  MachineConfig m = default_machine_config();
  m.axes[kZ].enabled = false;
  m.axes[kA].enabled = true;
  m.axes[kC].enabled = true;
  TrajectoryColumns cols;
  cols.override_pct = true;
  cols.load = true;
  cols.load_target = true;
  TrajectoryCsvWriter w(path.string(), m, cols);
  motion::Sample s = sample(0, 3, 1, 2, 99, 100);
  s.position[kA] = 45.5;
  s.position[kC] = -90;
  s.override_pct = 120;
  s.load_pct = 80.25;  // load_target stays NaN: empty cell
  w.on_sample(s);
  w.commit();
  std::vector<std::string> header;
  const auto rows = read_csv(slurp(path), &header);
  EXPECT_EQ(header, (std::vector<std::string>{"t", "line", "x", "y", "a", "c", "feed", "override",
                                              "load", "load_target"}));
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].at("a"), "45.500000");
  EXPECT_EQ(rows[0].at("c"), "-90.000000");
  EXPECT_DOUBLE_EQ(std::stod(rows[0].at("override")), 120);
  EXPECT_DOUBLE_EQ(std::stod(rows[0].at("load")), 80.25);
  EXPECT_EQ(rows[0].at("load_target"), "");
  EXPECT_EQ(rows[0].count("z"), 0u);
  EXPECT_EQ(rows[0].count("correction"), 0u);
}

TEST(TrajectoryCsv, RefColumnOnlyForTableRuns) {
  const auto dir = fresh_dir();
  const MachineConfig m = default_machine_config();
  TrajectoryColumns cols;
  cols.ref = true;
  {
    TrajectoryCsvWriter w((dir / "table.csv").string(), m, cols);
    motion::Sample s = sample(0.25, 7, 10, 0, 0, 600);
    s.ref = 1800.5;  // ms
    w.on_sample(s);
    w.on_sample(sample(0.5, 7, 20, 0, 0, 600));  // no reference: empty cell
    w.commit();
  }
  std::vector<std::string> header;
  const auto rows = read_csv(slurp(dir / "table.csv"), &header);
  ASSERT_FALSE(header.empty());
  EXPECT_EQ(header.back(), "ref");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("ref"), "1800.500000");
  EXPECT_EQ(rows[1].at("ref"), "");
  // A part-program run (ref off) has no such column even when the sample carries a value.
  {
    TrajectoryCsvWriter w((dir / "program.csv").string(), m, TrajectoryColumns{});
    motion::Sample s = sample(0, 1, 0, 0, 0, 0);
    s.ref = 5;
    w.on_sample(s);
    w.commit();
  }
  const auto prog = read_csv(slurp(dir / "program.csv"), &header);
  ASSERT_EQ(prog.size(), 1u);
  EXPECT_EQ(prog[0].count("ref"), 0u);
}

TEST(TrajectoryCsv, LongRunStreamsAndIsComplete) {
  const auto dir = fresh_dir();
  const auto path = dir / "traj.csv";
  const MachineConfig m = default_machine_config();
  constexpr int kRows = 200000;  // several flushes of the 64 KiB buffer
  {
    TrajectoryCsvWriter w(path.string(), m, {});
    for (int i = 0; i < kRows; ++i) w.on_sample(sample(i * 0.001, 1, i * 1e-3, 0, 0, 60));
    w.commit();
  }
  const auto rows = read_csv(slurp(path), nullptr);
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kRows));
  EXPECT_EQ(rows.back().at("x"), "199.999000");
  EXPECT_EQ(rows.back().at("t"), "199.999000");
}

TEST(TrajectoryCsv, WithoutCommitNothingIsLeft) {
  const auto dir = fresh_dir();
  {
    TrajectoryCsvWriter w((dir / "traj.csv").string(), default_machine_config(), {});
    for (int i = 0; i < 100000; ++i) w.on_sample(sample(i * 0.001, 1, 0, 0, 0, 0));
  }
  EXPECT_TRUE(list_dir(dir).empty());
}

}  // namespace
}  // namespace cncore::io
