// `cncore estimate` through the binary: every program's cycle time is the one `cncore run` gives
// for it alone, a broken program is reported with its error while the others are estimated, the
// outputs (CSV, HTML ranking) are complete or absent.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "files.hpp"

namespace {

namespace fs = std::filesystem;
using cncore::testing::shell_quote;
using cncore::testing::slurp;
using cncore::testing::write_file;

struct Result {
  int code = -1;
  std::string out, err;
};

// Splits one CSV record (RFC 4180 quoting, no line breaks inside fields in these tests).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> f(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        f.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        f.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      f.emplace_back();
    } else {
      f.back() += c;
    }
  }
  return f;
}

// CSV rows keyed by program, each as column → text.
std::map<std::string, std::map<std::string, std::string>> read_rows(const fs::path& p) {
  std::istringstream in(slurp(p));
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = csv_fields(line);
  std::map<std::string, std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> f = csv_fields(line);
    EXPECT_EQ(f.size(), header.size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < std::min(f.size(), header.size()); ++i) row[header[i]] = f[i];
    rows[row["program"]] = row;
  }
  return rows;
}

class Estimate : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(CNCORE_TEST_TMP_DIR) / "work" / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }

  Result cncore(const std::string& args) const {
    const std::string cmd = "cd " + shell_quote(dir_.string()) + " && " + shell_quote(CNCORE_BIN) +
                            " " + args + " >.stdout 2>.stderr";
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(dir_ / ".stdout");
    r.err = slurp(dir_ / ".stderr");
    fs::remove(dir_ / ".stdout");
    fs::remove(dir_ / ".stderr");
    return r;
  }

  // Cycle time of `cncore run PROGRAM --summary` alone; nullopt when the run fails.
  std::optional<double> run_alone(const std::string& program) const {
    const Result r = cncore("run " + shell_quote(program) + " --summary alone.json");
    if (r.code != 0) return std::nullopt;
    const auto j = nlohmann::json::parse(slurp(dir_ / "alone.json"));
    fs::remove(dir_ / "alone.json");
    return j.at("cycle_time_s").get<double>();
  }

  // Estimates the programs with -j 2 and checks each row against `cncore run` alone.
  void expect_same_as_run(const std::vector<std::string>& programs) {
    std::string args = "estimate -j 2 --csv batch.csv --report batch.html";
    for (const std::string& p : programs) args += " " + shell_quote(p);
    const Result est = cncore(args);
    const auto rows = read_rows(dir_ / "batch.csv");
    ASSERT_EQ(rows.size(), programs.size()) << est.err;
    bool any_failed = false;
    for (const std::string& p : programs) {
      SCOPED_TRACE(p);
      ASSERT_TRUE(rows.contains(p));
      const auto& row = rows.at(p);
      const std::optional<double> alone = run_alone(p);
      ASSERT_EQ(row.at("status"), alone ? "ok" : "error");
      if (!alone) {
        any_failed = true;
        EXPECT_NE(row.at("error").find(": error: "), std::string::npos) << row.at("error");
        continue;
      }
      // The CSV prints 6 decimals.
      EXPECT_NEAR(std::stod(row.at("cycle_time_s")), *alone, 6e-7);
      EXPECT_GT(std::stod(row.at("path_length_mm")), 0);
    }
    EXPECT_EQ(est.code, any_failed ? 1 : 0) << est.err;
    EXPECT_TRUE(fs::exists(dir_ / "batch.html"));
  }

  fs::path dir_;
};

std::string example(const std::string& name) {
  return std::string(CNCORE_SOURCE_DIR) + "/examples/" + name;
}

TEST_F(Estimate, ExamplesHaveTheCycleTimesOfRunAlone) {
  expect_same_as_run({example("seed-line-arc-line.ngc"), example("pocket-with-arcs.ngc"),
                      example("inch-bracket.ngc"), example("cam-short-segments.ngc")});
}

TEST_F(Estimate, BrokenProgramIsReportedWhileTheOthersSucceed) {
  write_file(dir_ / "broken.ngc", "G21 G90\nG1 X10 F1000\nG1 X20 Q\nM2\n");
  const std::string seed = example("seed-line-arc-line.ngc");
  const std::string pocket = example("pocket-with-arcs.ngc");
  const Result r = cncore("estimate -j 3 " + shell_quote(seed) + " broken.ngc missing.ngc " +
                          shell_quote(pocket) + " --csv out.csv --report out.html");
  EXPECT_EQ(r.code, 1) << r.err;
  const auto rows = read_rows(dir_ / "out.csv");
  ASSERT_EQ(rows.size(), 4U);
  EXPECT_EQ(rows.at(seed).at("status"), "ok");
  EXPECT_EQ(rows.at(pocket).at("status"), "ok");
  EXPECT_EQ(rows.at("broken.ngc").at("status"), "error");
  // The program's own error, at its line and column, as `cncore run` reports it.
  EXPECT_TRUE(rows.at("broken.ngc").at("error").starts_with("broken.ngc:3:"))
      << rows.at("broken.ngc").at("error");
  EXPECT_EQ(rows.at("missing.ngc").at("status"), "error");
  EXPECT_NE(r.err.find("broken.ngc:3:"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("(2 ok, 2 failed)"), std::string::npos) << r.out;

  // The page ranks the programs: the longer one first, the failed ones after them.
  const std::string html = slurp(dir_ / "out.html");
  const double t_seed = std::stod(rows.at(seed).at("cycle_time_s"));
  const double t_pocket = std::stod(rows.at(pocket).at("cycle_time_s"));
  const std::string longer = t_seed > t_pocket ? seed : pocket;
  const std::string shorter = t_seed > t_pocket ? pocket : seed;
  ASSERT_NE(html.find(longer), std::string::npos);
  EXPECT_LT(html.find(longer), html.find(shorter));
  EXPECT_LT(html.find(shorter), html.find("broken.ngc"));
  EXPECT_NE(html.find("missing.ngc"), std::string::npos);
}

TEST_F(Estimate, SlowestLinesAndTimeLostComeFromTheRun) {
  const std::string seed = example("seed-line-arc-line.ngc");
  ASSERT_EQ(cncore("run " + shell_quote(seed) + " --summary s.json").code, 0);
  const auto j = nlohmann::json::parse(slurp(dir_ / "s.json"));
  ASSERT_EQ(cncore("estimate " + shell_quote(seed) + " --csv out.csv").code, 0);
  const auto row = read_rows(dir_ / "out.csv").at(seed);
  double lost_s = 0;
  std::string lines;
  for (const auto& s : j.at("slowest_spots")) {
    lost_s += s.at("lost_s").get<double>();
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s%d:%.3f", lines.empty() ? "" : ";", s.at("line").get<int>(),
                  s.at("lost_s").get<double>());
    lines += buf;
  }
  EXPECT_GT(lost_s, 0);
  // The program's total, of which the slowest lines are a part.
  EXPECT_NEAR(std::stod(row.at("time_lost_s")), j.at("time_lost_s").get<double>(), 1e-6);
  EXPECT_LE(lost_s, j.at("time_lost_s").get<double>() + 1e-9);
  EXPECT_EQ(row.at("slowest_lines"), lines);
  EXPECT_EQ(std::stoull(row.at("blocks")), j.at("blocks").get<std::uint64_t>());
  EXPECT_EQ(std::stoull(row.at("cycles")), j.at("cycles").get<std::uint64_t>());
}

// A zigzag at F20000 on the built-in machine (max feed 10 000 mm/min): its loss by cause names
// the feed limit (exactly the time at 10 000 instead of 20 000 mm/min over the path) and the
// corners, the columns equal the run's summary and add up to the run's total.
TEST_F(Estimate, TimeLostByCauseComesFromTheRun) {
  std::string program = "G21 G90 G17\nG0 X0 Y0 Z0\nG1 F20000\n";
  for (int i = 1; i <= 20; ++i) {
    program += "X" + std::to_string(10 * i) + " Y" + std::to_string(i % 2 == 0 ? 0 : 10) + "\n";
  }
  program += "M2\n";
  write_file(dir_ / "zigzag.ngc", program);
  ASSERT_EQ(cncore("run zigzag.ngc --summary s.json").code, 0);
  const auto j = nlohmann::json::parse(slurp(dir_ / "s.json"));
  const auto& causes = j.at("time_lost_by_cause_s");
  ASSERT_EQ(cncore("estimate zigzag.ngc --csv out.csv").code, 0);
  const auto row = read_rows(dir_ / "out.csv").at("zigzag.ngc");
  double sum_s = 0;
  for (const char* c :
       {"corners", "arcs", "short_segments", "stops", "acceleration", "feed_limit", "override"}) {
    SCOPED_TRACE(c);
    const double s = causes.at(c).get<double>();
    EXPECT_NEAR(std::stod(row.at(std::string("lost_") + c + "_s")), s, 1e-6);
    sum_s += s;
  }
  EXPECT_NEAR(sum_s, causes.at("total").get<double>(), 1e-9);
  const double length_mm = 20 * std::hypot(10.0, 10.0);
  // The executed path rounds the corners within the contour tolerance.
  EXPECT_NEAR(j.at("path_length_mm").get<double>(), length_mm, 0.01);
  EXPECT_NEAR(causes.at("feed_limit").get<double>(),
              length_mm * 60 / 10000 - length_mm * 60 / 20000, 1e-3);
  EXPECT_GT(causes.at("corners").get<double>(), 0.01);
  EXPECT_EQ(causes.at("override").get<double>(), 0);
  // Against F as written: the summary's loss (against F capped by the machine) plus the cap.
  EXPECT_NEAR(causes.at("total").get<double>(),
              j.at("time_lost_s").get<double>() + causes.at("feed_limit").get<double>(), 1e-3);
}

TEST_F(Estimate, AFolderStandsForItsPrograms) {
  fs::create_directories(dir_ / "batch" / "sub");
  fs::copy_file(example("seed-line-arc-line.ngc"), dir_ / "batch" / "a.ngc");
  fs::copy_file(example("pocket-with-arcs.ngc"), dir_ / "batch" / "sub" / "b.nc");
  write_file(dir_ / "batch" / "notes.txt", "not a program\n");
  const Result r = cncore("estimate batch --csv out.csv");
  EXPECT_EQ(r.code, 0) << r.err;
  const auto rows = read_rows(dir_ / "out.csv");
  EXPECT_EQ(rows.size(), 2U);
  EXPECT_TRUE(rows.contains("batch/a.ngc"));
  EXPECT_TRUE(rows.contains("batch/sub/b.nc"));
}

TEST_F(Estimate, BadUsageAndBadOutputsWriteNothing) {
  const std::string seed = shell_quote(example("seed-line-arc-line.ngc"));
  EXPECT_EQ(cncore("estimate " + seed).code, 2);  // --csv is required
  EXPECT_EQ(cncore("estimate " + seed + " -j 0 --csv out.csv").code, 2);
  const Result bad_dir = cncore("estimate " + seed + " --csv no/such/dir/out.csv");
  EXPECT_EQ(bad_dir.code, 1);
  EXPECT_NE(bad_dir.err.find("no/such/dir/out.csv"), std::string::npos) << bad_dir.err;
  write_file(dir_ / "bad.toml", "[motion\n");
  const Result bad_machine = cncore("estimate " + seed + " --machine bad.toml --csv out.csv");
  EXPECT_EQ(bad_machine.code, 1);
  EXPECT_TRUE(bad_machine.err.starts_with("bad.toml:")) << bad_machine.err;
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
}

// A handful of programs of the public corpus, when it is present.
TEST_F(Estimate, CorpusProgramsHaveTheCycleTimesOfRunAlone) {
  const fs::path gcode = fs::path(CNCORE_SHARED_DIR) / "testdata" / "gcode";
  if (!fs::is_directory(gcode)) GTEST_SKIP() << "no shared corpus at " << gcode;
  std::vector<std::string> programs;
  for (const char* name : {"grbl/HelloWorld_cambam.nc", "cncjs/helical-thread-milling.gcode",
                           "linuxcnc-tp/arc_time.ngc", "camotics/heart.ngc",
                           "cncjs/arc-xz-plane.gcode", "camotics/genes-encoder.ngc"}) {
    if (fs::exists(gcode / name)) programs.push_back((gcode / name).string());
  }
  ASSERT_FALSE(programs.empty());
  expect_same_as_run(programs);
}

}  // namespace
