// End-to-end tests of the built `cncore` binary: exit codes, error format, outputs written only
// on success (no file and no temporary after an error), trajectory from t = 0 to the programmed
// end point.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
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
using cncore::testing::write_file;

// The i-th of a back-and-forth of 10 mm moves along X.
std::string fmt_move(int i) {
  return i % 2 == 0 ? "G1 X10 F1000\n" : "G1 X0 F1000\n";
}

std::vector<std::string> list_dir(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(CNCORE_TEST_TMP_DIR) / "work" / info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }

  // Runs cncore with the arguments (already shell-quoted where needed) in the test directory.
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

  static std::string example(const std::string& name) {
    return quote(std::string(CNCORE_SOURCE_DIR) + "/examples/" + name);
  }

  fs::path dir_;
};

// CSV rows as maps column → value.
std::vector<std::map<std::string, double>> read_csv(const fs::path& p,
                                                    std::vector<std::string>* header = nullptr) {
  std::ifstream in(p);
  std::string line;
  std::vector<std::string> names;
  std::vector<std::map<std::string, double>> rows;
  auto cells = [](const std::string& l) {
    std::vector<std::string> c;
    std::stringstream ss(l);
    std::string cell;
    while (std::getline(ss, cell, ',')) c.push_back(cell);
    return c;
  };
  if (!std::getline(in, line)) return rows;
  names = cells(line);
  if (header) *header = names;
  while (std::getline(in, line)) {
    const auto c = cells(line);
    std::map<std::string, double> row;
    for (std::size_t i = 0; i < c.size() && i < names.size(); ++i) {
      row[names[i]] = c[i].empty() ? std::nan("") : std::stod(c[i]);
    }
    rows.push_back(row);
  }
  return rows;
}

TEST_F(Cli, VersionAndHelpOnEveryCommand) {
  const Result v = run("--version");
  EXPECT_EQ(v.code, 0);
  EXPECT_NE(v.out.find(CNCORE_VERSION), std::string::npos) << v.out;
  for (const char* args : {"--help", "run --help", "check --help", "machine --help"}) {
    const Result h = run(args);
    EXPECT_EQ(h.code, 0) << args;
    EXPECT_NE(h.out.find("Usage"), std::string::npos) << args << "\n" << h.out;
  }
  EXPECT_NE(run("run --help").out.find("--override-at"), std::string::npos);
  EXPECT_NE(run("check --help").out.find("--blocks"), std::string::npos);
}

TEST_F(Cli, UsageErrorsExitTwo) {
  write_file(dir_ / "p.ngc", "G1 X1 F100\nM30\n");
  for (const char* args : {"",
                           "frobnicate",
                           "run",
                           "run p.ngc --no-such-option",
                           "run p.ngc --mode fast",
                           "run p.ngc --override abc",
                           "run p.ngc --override 500",
                           "run p.ngc --override -1",
                           "run p.ngc --override-at abc",
                           "run p.ngc --override-at 1:50,x:20",
                           "run p.ngc --override-at 0.5:900",
                           "run p.ngc --override-at -1:50",
                           "run p.ngc --var depth",
                           "run p.ngc --var depth=deep",
                           "run p.ngc --param x=1",
                           "run p.ngc --param 0=1",
                           "run p.ngc --dry-run 0",
                           "run p.ngc --dry-run fast",
                           "run p.ngc --single-block -1",
                           "check",
                           "machine extra"}) {
    const Result r = run(args);
    EXPECT_EQ(r.code, 2) << "cncore " << args << "\n" << r.err;
    EXPECT_FALSE(r.err.empty()) << args;
  }
  // The message names the option.
  EXPECT_NE(run("run p.ngc --override-at abc").err.find("--override-at"), std::string::npos);
  EXPECT_EQ(list_dir(dir_), std::vector<std::string>{"p.ngc"});
}

TEST_F(Cli, MachinePrintsTheBuiltInAsParsableToml) {
  const Result r = run("machine");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(cncore::parse_machine_config(r.out, "stdout"), cncore::default_machine_config());
  EXPECT_NE(r.out.find("period_s = 0.001"), std::string::npos);
  // An edited copy prints as the effective configuration.
  write_file(dir_ / "m.toml", "[motion]\nmax_feed_mm_min = 5000\n");
  const Result e = run("machine --machine m.toml");
  ASSERT_EQ(e.code, 0) << e.err;
  cncore::MachineConfig expected = cncore::default_machine_config();
  expected.max_feed_mm_min = 5000;
  EXPECT_EQ(cncore::parse_machine_config(e.out, "stdout"), expected);
}

TEST_F(Cli, BadConfigIsExitOneWithFileLineColumnAndKey) {
  write_file(dir_ / "m.toml", "[motion]\nperiod_s = 0.001\nmax_accel_mm_s2 = 0\n");
  write_file(dir_ / "p.ngc", "G1 X1 F100\nM30\n");
  const Result m = run("machine --machine m.toml");
  EXPECT_EQ(m.code, 1);
  EXPECT_EQ(m.err.rfind("m.toml:3:1: error: ", 0), 0u) << m.err;
  EXPECT_NE(m.err.find("motion.max_accel_mm_s2"), std::string::npos) << m.err;
  const Result r = run("run p.ngc --machine m.toml --trajectory t.csv --summary s.json");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err.rfind("m.toml:3:1: error: ", 0), 0u) << r.err;
  write_file(dir_ / "syntax.toml", "[motion]\nperiod_s = = 1\n");
  const Result s = run("machine --machine syntax.toml");
  EXPECT_EQ(s.code, 1);
  EXPECT_EQ(s.err.rfind("syntax.toml:2:12: error: ", 0), 0u) << s.err;
  EXPECT_EQ(list_dir(dir_), (std::vector<std::string>{"m.toml", "p.ngc", "syntax.toml"}));
}

TEST_F(Cli, MissingProgramIsExitOneCannotOpen) {
  const Result r = run("run nofile.ngc --trajectory t.csv --summary s.json");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err, "nofile.ngc:0:0: error: cannot open: No such file or directory\n");
  fs::create_directory(dir_ / "adir");
  const Result d = run("run adir");
  EXPECT_EQ(d.code, 1);
  EXPECT_EQ(d.err.rfind("adir:0:0: error: cannot open", 0), 0u) << d.err;
  write_file(dir_ / "p.ngc", "G1 X1 F100\n");
  const Result m = run("run p.ngc --machine adir");
  EXPECT_EQ(m.code, 1);
  EXPECT_EQ(m.err.rfind("adir:0:0: error: cannot open", 0), 0u) << m.err;
  fs::remove(dir_ / "adir");
  fs::remove(dir_ / "p.ngc");
  const Result c = run("check nofile.ngc");
  EXPECT_EQ(c.code, 1);
  EXPECT_EQ(c.err, "nofile.ngc:0:0: error: cannot open: No such file or directory\n");
  EXPECT_TRUE(list_dir(dir_).empty());
}

TEST_F(Cli, CannotOpenSaysWhy) {
  write_file(dir_ / "p.ngc", "G1 X1 F100\nM30\n");
  write_file(dir_ / "locked.ngc", "G1 X1 F100\nM30\n");
  fs::permissions(dir_ / "locked.ngc", fs::perms::none);
  const bool root_reads_anything = std::ifstream(dir_ / "locked.ngc").good();
  if (!root_reads_anything) {
    const Result l = run("run locked.ngc");
    EXPECT_EQ(l.code, 1);
    EXPECT_EQ(l.err, "locked.ngc:0:0: error: cannot open: Permission denied\n");
  }
  fs::permissions(dir_ / "locked.ngc", fs::perms::owner_all);
  const Result m = run("run p.ngc --machine nope.toml");
  EXPECT_EQ(m.code, 1);
  EXPECT_EQ(m.err,
            "nope.toml:0:0: error: cannot open machine configuration: No such file or directory\n");
  const Result t = run("table nope.tbl");
  EXPECT_EQ(t.code, 1);
  EXPECT_EQ(t.err, "nope.tbl:0:0: error: cannot open table file: No such file or directory\n");
  const Result l = run("run p.ngc --load nope.csv");
  EXPECT_EQ(l.code, 1);
  EXPECT_EQ(l.err, "nope.csv:0:0: error: cannot open load file: No such file or directory\n");
}

// A program of `moves` 10 mm feed moves at F1000: 0.6 s simulated each.
std::string long_program(int moves) {
  std::string p = "G21 G90 G17\n";
  for (int i = 0; i < moves; ++i) p += fmt_move(i);
  return p + "M30\n";
}

TEST_F(Cli, ProgressJsonIsOneObjectPerLineEndingDone) {
  write_file(dir_ / "p.ngc", long_program(200));  // 120 s simulated: many 4096-cycle checks
  const Result r = run("run p.ngc --progress=json");
  ASSERT_EQ(r.code, 0) << r.err;
  std::istringstream lines(r.err);
  std::string line;
  std::vector<nlohmann::json> updates;
  while (std::getline(lines, line)) updates.push_back(nlohmann::json::parse(line));
  ASSERT_GE(updates.size(), 2U) << r.err;
  double last_pct = 0, last_sim = -1;
  for (const auto& u : updates) {
    EXPECT_EQ(u.at("lines").get<int>(), 202) << u;  // the program's lines, M30 included
    EXPECT_GE(u.at("percent").get<double>(), last_pct) << u;
    EXPECT_GT(u.at("simulated_s").get<double>(), last_sim) << u;
    EXPECT_GE(u.at("wall_s").get<double>(), 0) << u;
    last_pct = u.at("percent").get<double>();
    last_sim = u.at("simulated_s").get<double>();
  }
  const auto& done = updates.back();
  EXPECT_TRUE(done.at("done").get<bool>());
  EXPECT_DOUBLE_EQ(done.at("percent").get<double>(), 100.0);
  EXPECT_DOUBLE_EQ(done.at("left_s").get<double>(), 0.0);
  // The simulated time of the last update is the cycle time the summary prints.
  const std::size_t at = r.out.find("cycle time");
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_NEAR(done.at("simulated_s").get<double>(), std::stod(r.out.substr(at + 14)), 0.001);
  for (std::size_t i = 0; i + 1 < updates.size(); ++i) EXPECT_FALSE(updates[i].at("done"));
}

TEST_F(Cli, ProgressIsOffWhenPipedUnlessAskedFor) {
  write_file(dir_ / "p.ngc", long_program(20));
  for (const char* args : {"run p.ngc", "run p.ngc --progress=off", "run p.ngc --progress=auto",
                           "run --progress=off p.ngc"}) {
    const Result r = run(args);
    EXPECT_EQ(r.code, 0) << args << "\n" << r.err;
    EXPECT_EQ(r.err, "") << args;
  }
  // --progress alone is --progress=on and never takes the program's name as its value.
  const Result bare = run("run --progress p.ngc");
  EXPECT_EQ(bare.code, 0) << bare.err;
  EXPECT_NE(bare.out.find("cycle time"), std::string::npos);
  const Result bad = run("run p.ngc --progress=sometimes");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--progress"), std::string::npos) << bad.err;
  // Tables: no program lines, so no percentage; the last update ends the stream.
  write_file(dir_ / "t.tbl", "REF TIME\nAXES X\nCUBIC\nL1000 X10\nL2000 X0\n");
  const Result t = run("table t.tbl --progress=json");
  ASSERT_EQ(t.code, 0) << t.err;
  const auto last = nlohmann::json::parse(t.err.substr(t.err.rfind('{')));
  EXPECT_TRUE(last.at("done").get<bool>());
  EXPECT_FALSE(last.contains("percent")) << last;
  EXPECT_NEAR(last.at("simulated_s").get<double>(), 2.0, 0.002);
}

TEST_F(Cli, MisspelledCommandsAndOptionsGetASuggestion) {
  write_file(dir_ / "p.ngc", "G1 X1 F100\nM30\n");
  const Result c = run("runn p.ngc");
  EXPECT_EQ(c.code, 2);
  EXPECT_EQ(
      c.err.rfind("cncore: error: unknown command 'runn'; did you mean 'run'? (commands: run, "
                  "check, table, machine, ",
                  0),
      0u)
      << c.err;
  EXPECT_NE(run("chekc p.ngc").err.find("did you mean 'check'?"), std::string::npos);
  EXPECT_NE(run("tabel x.tbl").err.find("did you mean 'table'?"), std::string::npos);
  // Nothing close: no guess, the list of commands.
  const Result f = run("frobnicate");
  EXPECT_EQ(f.code, 2);
  EXPECT_EQ(f.err.find("did you mean"), std::string::npos) << f.err;
  EXPECT_NE(f.err.find("unknown command 'frobnicate' (commands: run,"), std::string::npos) << f.err;
  for (const char* args : {"run p.ngc --overide 50", "run --overide=50 p.ngc"}) {
    const Result o = run(args);
    EXPECT_EQ(o.code, 2) << args;
    EXPECT_EQ(
        o.err.rfind("cncore: error: run: unknown option --overide; did you mean --override?", 0),
        0u)
        << o.err;
  }
  EXPECT_NE(run("run p.ngc --trajectroy t.csv").err.find("did you mean --trajectory?"),
            std::string::npos);
  EXPECT_NE(run("check p.ngc --block").err.find("did you mean --blocks?"), std::string::npos);
  EXPECT_NE(run("table x.tbl --spindle-rmp 100").err.find("did you mean --spindle-rpm?"),
            std::string::npos);
  const Result n = run("run p.ngc --no-such-option");
  EXPECT_EQ(n.code, 2);
  EXPECT_NE(n.err.find("unknown option --no-such-option\n"), std::string::npos) << n.err;
  EXPECT_EQ(list_dir(dir_), std::vector<std::string>{"p.ngc"});
}

TEST_F(Cli, BadProgramIsExitOneWithFileLineColumn) {
  // Two words of the motion modal group in one block (line 3).
  write_file(dir_ / "bad.ngc", "G21 G90\nG1 X10 F1000\nG0 G1 X20\nM30\n");
  for (const char* cmd : {"check bad.ngc", "run bad.ngc"}) {
    const Result r = run(cmd);
    EXPECT_EQ(r.code, 1) << cmd << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("bad.ngc:3:", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(": error: "), std::string::npos) << r.err;
  }
}

TEST_F(Cli, CheckReportsATravelErrorOnceWithoutKnockOnErrors) {
  // Line 5 leaves the travel (Y 0 … 200 on the built-in mill); the arcs after it are written
  // from its end point and the program comes back inside on line 8; line 10 is an error of its
  // own (an arc whose end is not on its circle).
  write_file(dir_ / "travel.ngc",
             "G21 G90 G17\nG0 X10 Y10\nF1000\nG1 X20 Y10\nG1 Y320\nG2 X30 Y320 I5 J0\n"
             "G3 X40 Y320 I5 J0\nG1 X50 Y50\nG2 X60 Y50 I5 J0\nG2 X70 Y50 I3 J0\nM2\n");
  const Result r = run("check travel.ngc");
  EXPECT_EQ(r.code, 1) << r.err;
  std::vector<std::string> lines;
  std::istringstream err(r.err);
  for (std::string l; std::getline(err, l);) lines.push_back(l);
  ASSERT_EQ(lines.size(), 3u) << r.err;
  EXPECT_EQ(lines[0].rfind("travel.ngc:5:", 0), 0u) << r.err;
  EXPECT_NE(lines[0].find("error: Y 320.000 is beyond the travel limit 200.000"), std::string::npos)
      << r.err;
  EXPECT_EQ(lines[1].rfind("travel.ngc:5:", 0), 0u) << r.err;
  EXPECT_NE(lines[1].find(": note: "), std::string::npos) << r.err;
  EXPECT_EQ(lines[2].rfind("travel.ngc:10:", 0), 0u) << r.err;
  EXPECT_NE(lines[2].find("radius to the end"), std::string::npos) << r.err;
}

TEST_F(Cli, ToolTableFileGivesTheLengthOffsetAndItsErrorsNameTheTable) {
  write_file(dir_ / "p.ngc", "T2 M6 G43\nG0 Z5\nM30\n");
  write_file(dir_ / "t.tbl", "T1 P1 Z10 ;short\nT2 P2 Z25 D6 ;long\n");
  const Result r = run("check p.ngc --blocks --tool-table t.tbl");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("RAPID from 0.0000 0.0000 0.0000 to 0.0000 0.0000 30.0000"),
            std::string::npos)
      << r.out;
  write_file(dir_ / "bad.tbl", "T1 Z1\nT2 Zx\n");
  const Result b = run("run p.ngc --tool-table bad.tbl --summary s.json");
  EXPECT_EQ(b.code, 1);
  EXPECT_EQ(b.err.rfind("bad.tbl:2:4: error: tool table:", 0), 0u) << b.err;
  EXPECT_FALSE(fs::exists(dir_ / "s.json"));
  const Result k = run("check p.ngc --canon --tool-table t.tbl");
  EXPECT_EQ(k.code, 0) << k.err;
  EXPECT_EQ(k.out, "STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n");
  const Result m = run("check p.ngc --tool-table missing.tbl");
  EXPECT_EQ(m.code, 1);
  EXPECT_EQ(m.err.rfind("missing.tbl:0:0: error: cannot open the tool table", 0), 0u) << m.err;
}

TEST_F(Cli, SubroutinePathFindsTheFileOfACalledSubroutine) {
  fs::create_directories(dir_ / "lib");
  write_file(dir_ / "lib" / "peck.ngc", "o<peck> sub\nG1 Z#1 F300\nG0 Z5\no<peck> endsub\n");
  write_file(dir_ / "p.ngc", "G21 G90 G0 Z5\no<peck> call [-3]\nM30\n");
  const Result missing = run("check p.ngc");
  EXPECT_EQ(missing.code, 1);
  EXPECT_EQ(missing.err.rfind("p.ngc:2:1: error: subroutine o<peck> is not defined", 0), 0u)
      << missing.err;
  const Result r = run("check p.ngc --blocks --subroutine-path lib");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("N2 LINE from 0.0000 0.0000 5.0000 to 0.0000 0.0000 -3.0000"),
            std::string::npos)
      << r.out;
  const Result s = run("run p.ngc --subroutine-path lib --summary s.json");
  EXPECT_EQ(s.code, 0) << s.err;
  EXPECT_TRUE(fs::exists(dir_ / "s.json"));
}

TEST_F(Cli, CheckReportsEveryErrorWithItsLine) {
  // Errors on lines 2 (unknown word), 4 (two motion words) and 6 (division by zero, at the /).
  write_file(dir_ / "many.ngc", "G21 G90 G1 F1000\nX10 E5\nX20\nG0 G1 X30\nX40\nX[1/0]\nM30\n");
  const Result r = run("check many.ngc --blocks");
  EXPECT_EQ(r.code, 1) << r.err;
  std::vector<std::string> lines;
  std::istringstream err(r.err);
  for (std::string l; std::getline(err, l);) lines.push_back(l.substr(0, l.find(": error: ")));
  EXPECT_EQ(lines, (std::vector<std::string>{"many.ngc:2:5", "many.ngc:4:4", "many.ngc:6:4"}))
      << r.err;
  // The good lines are still listed: X20 and X40.
  EXPECT_NE(r.out.find("20.0000"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("40.0000"), std::string::npos) << r.out;
}

TEST_F(Cli, ErrorAtTheLastLineLeavesNoOutputAndNoTemporary) {
  std::string program = "G21 G90 G17\nG1 X10 F3000\n";
  for (int i = 0; i < 200; ++i) program += i % 2 ? "G1 X10\n" : "G1 X20\n";
  program += "G2 X30 Y10\n";  // arc without centre or radius: an error at the last line
  write_file(dir_ / "late.ngc", program);
  const Result r = run("run late.ngc --trajectory t.csv --summary s.json");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("late.ngc:203:", 0), 0u) << r.err;
  EXPECT_EQ(list_dir(dir_), std::vector<std::string>{"late.ngc"});
}

TEST_F(Cli, InterruptedRunLeavesNoTemporary) {
  // A 20 000 s dwell is 20 M cycles of trajectory, seconds of work however fast the run gets; the
  // signal is sent as soon as the trajectory's temporary exists, so the run is always mid-way
  // (a fixed sleep let a fast machine finish first).
  write_file(dir_ / "long.ngc", "G21 G90 G17 F6000\nG1 X1\nG4 P20000\nG1 X0\nM30\n");
  for (const char* sig : {"TERM", "HUP"}) {  // a background job ignores SIGINT
    const std::string cmd = "cd " + quote(dir_.string()) + " && (" + quote(CNCORE_BIN) +
                            " run long.ngc --trajectory t.csv --summary s.json"
                            " >/dev/null 2>&1 & pid=$!; i=0;"
                            " while [ $i -lt 500 ] && ! ls t.csv.tmp-* >/dev/null 2>&1;"
                            " do sleep 0.01; i=$((i+1)); done; kill -" +
                            std::string(sig) + " $pid; wait $pid)";
    const int status = std::system(cmd.c_str());
    // The shell reports death by signal as 128 + signal number.
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    EXPECT_GT(code, 128) << sig;
    EXPECT_EQ(list_dir(dir_), std::vector<std::string>{"long.ngc"}) << sig;
  }
}

TEST_F(Cli, UnwritableOutputIsExitOneAndLeavesNothing) {
  const Result r =
      run("run " + example("seed-line-arc-line.ngc") + " --trajectory no/such/dir/t.csv");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("no/such/dir/t.csv:0:0: error: ", 0), 0u) << r.err;
  EXPECT_TRUE(list_dir(dir_).empty());
}

TEST_F(Cli, CheckListsTheBlocks) {
  const Result r = run("check --blocks " + example("seed-line-arc-line.ngc"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto lines = std::count(r.out.begin(), r.out.end(), '\n');
  EXPECT_GE(lines, 3);  // line, arc, line (+ the M30 event if listed)
  // On an error the blocks before it are still listed.
  write_file(dir_ / "e.ngc", "G1 X1 F100\nG1 X2\nG2 X3\n");
  const Result e = run("check --blocks e.ngc");
  EXPECT_EQ(e.code, 1);
  EXPECT_EQ(std::count(e.out.begin(), e.out.end(), '\n'), 2) << e.out;
  EXPECT_EQ(e.err.rfind("e.ngc:3:", 0), 0u) << e.err;
  const Result plain = run("check " + example("seed-line-arc-line.ngc"));
  EXPECT_EQ(plain.code, 0);
  EXPECT_NE(plain.out.find("ok"), std::string::npos);
}

TEST_F(Cli, RunWritesTrajectoryFromStartToProgrammedEnd) {
  const Result r =
      run("run " + example("seed-line-arc-line.ngc") + " --trajectory t.csv --summary s.json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("cycle time"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("slowest spots"), std::string::npos) << r.out;
  EXPECT_EQ(list_dir(dir_), (std::vector<std::string>{"s.json", "t.csv"}));

  std::vector<std::string> header;
  const auto rows = read_csv(dir_ / "t.csv", &header);
  for (const char* col : {"t", "line", "x", "y", "z", "feed"}) {
    EXPECT_NE(std::find(header.begin(), header.end(), col), header.end()) << col;
  }
  EXPECT_EQ(std::find(header.begin(), header.end(), "override"), header.end());
  ASSERT_GE(rows.size(), 2u);
  EXPECT_EQ(rows.front().at("t"), 0.0);
  EXPECT_EQ(rows.front().at("x"), 0.0);  // the built-in start position
  EXPECT_EQ(rows.front().at("y"), 0.0);
  // The program ends at X55 Y60 (Z untouched): printed with 6 decimals.
  EXPECT_NEAR(rows.back().at("x"), 55.0, 1e-6);
  EXPECT_NEAR(rows.back().at("y"), 60.0, 1e-6);
  EXPECT_NEAR(rows.back().at("z"), 0.0, 1e-6);
  // Uniform time steps of the period.
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_NEAR(rows[i].at("t") - rows[i - 1].at("t"), 0.001, 1e-6) << "row " << i;
  }

  const auto j = nlohmann::json::parse(slurp(dir_ / "s.json"));
  EXPECT_EQ(j.at("cycles").get<std::size_t>(), rows.size());
  EXPECT_NEAR(j.at("cycle_time_s").get<double>(), rows.back().at("t"), 1e-6);
  EXPECT_EQ(j.at("blocks").get<int>(), 3);
  EXPECT_EQ(j.at("mode"), "lookahead");
  // Path length: 50 + quarter circle of R5 + 55 = 112.854 mm.
  EXPECT_NEAR(j.at("path_length_mm").get<double>(), 105 + 2.5 * M_PI, 0.01);
  EXPECT_LE(j.at("max_feed_mm_min").get<double>(), 8000 * 1.001);
  EXPECT_TRUE(j.at("max_axis_accel_mm_s2").contains("x"));
}

TEST_F(Cli, VariablesParametersAndInchesReachTheTrajectory) {
  // X from a named parameter, Y from a numbered one, Z in inches: ends at 12, 7, −25.4·0.5.
  write_file(dir_ / "p.ngc", "G21 G90\nG1 X#<dist> Y#1 F3000\nG20\nG1 Z-0.5 F20\nM30\n");
  const Result r = run("run p.ngc --var dist=12 --param 1=7 --trajectory t.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_csv(dir_ / "t.csv");
  ASSERT_FALSE(rows.empty());
  EXPECT_NEAR(rows.back().at("x"), 12.0, 1e-6);
  EXPECT_NEAR(rows.back().at("y"), 7.0, 1e-6);
  EXPECT_NEAR(rows.back().at("z"), -12.7, 1e-6);
  // Without the variable the program is wrong (undefined parameter) at line 2.
  const Result bad = run("run p.ngc --param 1=7 --trajectory t2.csv");
  EXPECT_EQ(bad.code, 1) << bad.err;
  EXPECT_EQ(bad.err.rfind("p.ngc:2:", 0), 0u) << bad.err;
  EXPECT_FALSE(fs::exists(dir_ / "t2.csv"));
}

TEST_F(Cli, ProbeMoveEndsOnTheConfiguredSurfaceInTheTrajectory) {
  // A plate whose top is at Z −3.5: the executed probe move stops there, and the retract after
  // it reads the trip point from #5063.
  write_file(dir_ / "m.toml", "[probe]\nboxes = [[-50, -50, -20, 50, 50, -3.5]]\n");
  write_file(dir_ / "p.ngc", "G21 G90 G0 Z5\nG38.2 Z-10 F200\nG0 X1 Z[#5063 + 2]\nM30\n");
  const Result r = run("run p.ngc --machine m.toml --trajectory t.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_csv(dir_ / "t.csv");
  double lowest = 1e9;
  for (const auto& row : rows) lowest = std::min(lowest, row.at("z"));
  EXPECT_NEAR(lowest, -3.5, 1e-6);
  EXPECT_NEAR(rows.back().at("z"), -1.5, 1e-6);
  EXPECT_NEAR(rows.back().at("x"), 1, 1e-6);
  // Bad [probe] boxes name the key; a probe that meets nothing is an error at its line.
  write_file(dir_ / "bad.toml", "[probe]\nboxes = [[0, 0, 0, 1, 1]]\n");
  const Result b = run("machine --machine bad.toml");
  EXPECT_EQ(b.code, 1);
  EXPECT_EQ(b.err.rfind("bad.toml:2:1: error: probe.boxes[0] must be an array of 6 numbers", 0), 0u)
      << b.err;
  write_file(dir_ / "miss.ngc", "G21 G90 G0 X100 Z5\nG38.2 Z-10 F200\nM30\n");
  const Result miss = run("run miss.ngc --machine m.toml --trajectory miss.csv");
  EXPECT_EQ(miss.code, 1);
  EXPECT_EQ(miss.err.rfind("miss.ngc:2:1: error: G38.2: the move ended without contact", 0), 0u)
      << miss.err;
  EXPECT_FALSE(fs::exists(dir_ / "miss.csv"));
}

TEST_F(Cli, ALineOfManyBlocksIsMeasuredAgainstEachOfThem) {
  // One G5 line becomes 26 arcs: the contour error is measured against the arc under the tool,
  // not only against the first ones of the line.
  write_file(dir_ / "s.ngc", "G21 G90 G0 X0 Y0\nG5 X60 Y20 I30 J40 P-10 Q-50 F6000\nM2\n");
  const Result r = run("run s.ngc --summary s.json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "s.json"));
  EXPECT_LE(j.at("max_contour_error_mm").get<double>(), 0.01);
  EXPECT_GT(j.at("blocks").get<int>(), 10);
}

TEST_F(Cli, CyclesWhoseMovesRetraceEachOtherAreMeasuredAgainstThem) {
  // A peck drilling cycle, a threading cycle and a lathe roughing cycle: one line each, whose
  // moves run back over each other (and an index wait between the threading passes). The
  // tool stays on the programmed moves of its line.
  for (const char* program :
       {"G17 G21 G90 F300\nG0 X0 Y0 Z5\nG83 X10 Y10 Z-20 R2 Q3\nG80\nG0 Z10\nM2\n",
        "G18 G21 G90 S300 M3\nG0 X12 Z5\nG76 P2 Z-30 I-1 J0.5 K1.2 R1 H1\nM2\n",
        "o10 sub\nG1 X5 Z0\nZ-10\nG2 X8 Z-13 I3 K0\nG1 X10\nZ-25\no10 endsub\n"
        "G18 G21 G90 G8 F200\nG0 X15 Z5\nG71 Q10 X12 Z2 D0.2 I1 R0.5\nM2\n"}) {
    write_file(dir_ / "c.ngc", program);
    const Result r = run("run c.ngc --summary c.json");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(dir_ / "c.json"));
    EXPECT_LE(j.at("max_contour_error_mm").get<double>(), 0.01) << program;
  }
}

TEST_F(Cli, StopModeIsSlowerThanLookahead) {
  const Result a = run("run " + example("seed-line-arc-line.ngc") + " --summary a.json");
  const Result b =
      run("run " + example("seed-line-arc-line.ngc") + " --mode stop --summary b.json");
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  const auto ja = nlohmann::json::parse(slurp(dir_ / "a.json"));
  const auto jb = nlohmann::json::parse(slurp(dir_ / "b.json"));
  EXPECT_EQ(jb.at("mode"), "stop");
  EXPECT_GT(jb.at("cycle_time_s").get<double>(), ja.at("cycle_time_s").get<double>());
}

// Operator modes: a dry run (F ignored) and single-block stops, named in the summary.
TEST_F(Cli, DryRunAndSingleBlockAreInTheSummary) {
  const std::string p = example("seed-line-arc-line.ngc");
  ASSERT_EQ(run("run " + p + " --summary a.json").code, 0);
  const Result d = run("run " + p + " --dry-run 10000 --summary d.json");
  const Result b = run("run " + p + " --single-block 0.5 --summary b.json");
  ASSERT_EQ(d.code, 0) << d.err;
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_NE(d.out.find("dry run at 10000 mm/min"), std::string::npos) << d.out;
  EXPECT_NE(b.out.find("single block (wait 0.5 s)"), std::string::npos) << b.out;
  const auto ja = nlohmann::json::parse(slurp(dir_ / "a.json"));
  const auto jd = nlohmann::json::parse(slurp(dir_ / "d.json"));
  const auto jb = nlohmann::json::parse(slurp(dir_ / "b.json"));
  EXPECT_FALSE(ja.contains("dry_run_feed_mm_min"));
  EXPECT_EQ(jd.at("dry_run_feed_mm_min").get<double>(), 10000);
  EXPECT_EQ(jb.at("single_block_wait_s").get<double>(), 0.5);
  const double t = ja.at("cycle_time_s").get<double>();
  EXPECT_LT(jd.at("cycle_time_s").get<double>(), t);  // its F is below the machine's top feed
  EXPECT_GT(jb.at("cycle_time_s").get<double>(), t + 3 * 0.5);  // three blocks, three waits
}

// The acc/dec type that computed the time is in the summary: the built-in machine's default
// (acceleration), --accdec, and stop mode's moving average; the seed's example is faster with
// the acceleration type (every speed change takes |ΔV|/Amax instead of T = Vmax/Amax).
TEST_F(Cli, SummaryNamesTheAccDecType) {
  const std::string p = example("seed-line-arc-line.ngc");
  ASSERT_EQ(run("run " + p + " --summary d.json").code, 0);
  ASSERT_EQ(run("run " + p + " --accdec moving_average --summary m.json").code, 0);
  ASSERT_EQ(run("run " + p + " --mode stop --summary s.json").code, 0);
  const auto jd = nlohmann::json::parse(slurp(dir_ / "d.json"));
  const auto jm = nlohmann::json::parse(slurp(dir_ / "m.json"));
  EXPECT_EQ(jd.at("accdec"), "acceleration");
  EXPECT_EQ(jm.at("accdec"), "moving_average");
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "s.json")).at("accdec"), "moving_average");
  EXPECT_LT(jd.at("cycle_time_s").get<double>(), jm.at("cycle_time_s").get<double>());
  // The search type: named, from the option and from the machine's key; no slower
  // than the acceleration type on this example; refused with a jerk limit (usage error).
  ASSERT_EQ(run("run " + p + " --accdec search --summary q.json").code, 0);
  const auto jq = nlohmann::json::parse(slurp(dir_ / "q.json"));
  EXPECT_EQ(jq.at("accdec"), "search");
  EXPECT_LE(jq.at("cycle_time_s").get<double>(), jd.at("cycle_time_s").get<double>());
  write_file(dir_ / "search.toml", "[motion]\naccdec = \"search\"\n");
  ASSERT_EQ(run("run " + p + " --machine search.toml --summary k.json").code, 0);
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "k.json")).at("accdec"), "search");
  write_file(dir_ / "jerk.toml", "[motion]\nmax_jerk_mm_s3 = 1000000\n");
  const Result r = run("run " + p + " --accdec search --machine jerk.toml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("without a jerk limit"), std::string::npos) << r.err;
}

TEST_F(Cli, OverrideColumnFollowsTheSteps) {
  const Result r = run("run " + example("seed-line-arc-line.ngc") +
                       " --override-at 0:100,0.2:50 --trajectory t.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_csv(dir_ / "t.csv");
  ASSERT_GT(rows.size(), 300u);
  for (const auto& row : rows) {
    if (row.at("t") < 0.2 - 1e-9) {
      ASSERT_NEAR(row.at("override"), 100, 1e-9) << "t = " << row.at("t");
    } else if (row.at("t") > 0.2 + 1e-9) {
      ASSERT_NEAR(row.at("override"), 50, 1e-9) << "t = " << row.at("t");
    }
  }
}

TEST_F(Cli, BundledExamplesRun) {
  for (const char* name : {"pocket-with-arcs.ngc", "inch-bracket.ngc", "cam-short-segments.ngc"}) {
    const Result r = run("run " + example(name));
    EXPECT_EQ(r.code, 0) << name << "\n" << r.err;
    EXPECT_NE(r.out.find("cycle time"), std::string::npos) << name;
  }
}

// ---------------------------------------------------------------------------------------------
// cncore table (spec 02 through the command line)

// Time (s, from the `t` column) of the first row where `col` reaches `value` within 1e-6 from
// below (or above, when `falling`); NaN when it never does.
double time_reaching(const std::vector<std::map<std::string, double>>& rows, const char* col,
                     double value, bool falling = false) {
  for (const auto& row : rows) {
    const double v = row.at(col);
    if (falling ? v <= value + 1e-6 : v >= value - 1e-6) return row.at("t");
  }
  return std::nan("");
}

std::string tables_example(const std::string& name) {
  return quote(std::string(CNCORE_SOURCE_DIR) + "/examples/tables/" + name);
}

const std::string kLathe = " --machine " + tables_example("lathe.toml");

TEST_F(Cli, TableFig1ShiftKeepsTheGapsWithARefColumn) {
  const Result r = run("table " + tables_example("fig1-shift.tbl") + kLathe +
                       " --trajectory t.csv --summary s.json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(list_dir(dir_), (std::vector<std::string>{"s.json", "t.csv"}));
  std::vector<std::string> header;
  const auto rows = read_csv(dir_ / "t.csv", &header);
  for (const char* col : {"t", "line", "x", "z", "feed", "ref"}) {
    EXPECT_NE(std::find(header.begin(), header.end(), col), header.end()) << col;
  }
  ASSERT_GT(rows.size(), 3000u);
  // Seed Fig. 1B: SFT-200 at the second row: 100, 200, 300, 400 at 1.0, 1.8, 2.8, 3.8 s.
  EXPECT_NEAR(time_reaching(rows, "x", 100), 1.0, 1e-9);
  EXPECT_NEAR(time_reaching(rows, "x", 200), 1.8, 1e-9);
  EXPECT_NEAR(time_reaching(rows, "x", 300), 2.8, 1e-9);
  EXPECT_NEAR(time_reaching(rows, "x", 400), 3.8, 1e-9);
  EXPECT_NEAR(rows.back().at("t"), 3.8, 1e-9);
  // REF TIME: the reference is the clock in ms.
  for (const auto& row : rows) ASSERT_NEAR(row.at("ref"), row.at("t") * 1000, 1e-6);
  // Between 1.0 and 1.8 s X covers 100 mm in 0.8 s: 7500 mm/min (X is the only moving axis).
  const auto j = nlohmann::json::parse(slurp(dir_ / "s.json"));
  EXPECT_NEAR(j.at("cycle_time_s").get<double>(), 3.8, 1e-9);
  EXPECT_NEAR(j.at("max_feed_mm_min").get<double>(), 7500, 1e-3);
  EXPECT_NE(r.out.find("cycle time    3.800 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("reference     time 0 … 3800 ms"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("X 7500.0"), std::string::npos) << r.out;
}

TEST_F(Cli, TablePrintEffectiveShowsTheShiftedReferences) {
  const Result r = run("table " + tables_example("fig1-shift.tbl") + kLathe + " --print-effective");
  ASSERT_EQ(r.code, 0) << r.err;
  // Written L2000 L3000 L4000 become 1800 2800 3800; the first row keeps L1000.
  for (const char* shifted : {"\nL1000 X100 ", "\nL1800 X200 ", "\nL2800 X300 ", "\nL3800 X400 "}) {
    EXPECT_NE(r.out.find(shifted), std::string::npos) << shifted << "\n" << r.out;
  }
  EXPECT_EQ(r.out.find("\nL2000 X200 "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("written L2000, SFT, shift -200"), std::string::npos) << r.out;
}

TEST_F(Cli, TableFig2CancelModeFromTheMachineConfiguration) {
  const Result clear =
      run("table " + tables_example("fig2c-cancel.tbl") + kLathe + " --trajectory clear.csv");
  ASSERT_EQ(clear.code, 0) << clear.err;
  const auto c = read_csv(dir_ / "clear.csv");
  EXPECT_NEAR(time_reaching(c, "x", 200), 1.5, 1e-9);
  EXPECT_NEAR(time_reaching(c, "x", 300), 3.0, 1e-9);
  EXPECT_NEAR(time_reaching(c, "x", 400), 4.0, 1e-9);

  write_file(dir_ / "rebase.toml",
             "[tables]\ncancel_mode = \"rebase\"\n[axes.x]\nmin_mm = -50\nmax_mm = 450\n"
             "max_accel_mm_s2 = 150000\n");
  const Result rebase = run("table " + tables_example("fig2c-cancel.tbl") +
                            " --machine rebase.toml --trajectory rebase.csv --print-effective");
  ASSERT_EQ(rebase.code, 0) << rebase.err;
  EXPECT_NE(rebase.out.find("SFTCAN rebase"), std::string::npos) << rebase.out;
  const auto b = read_csv(dir_ / "rebase.csv");
  EXPECT_NEAR(time_reaching(b, "x", 200), 1.5, 1e-9);
  EXPECT_NEAR(time_reaching(b, "x", 300), 2.5, 1e-9);
  EXPECT_NEAR(time_reaching(b, "x", 400), 3.5, 1e-9);

  write_file(dir_ / "bad.toml", "[tables]\ncancel_mode = \"keep\"\n");
  const Result bad = run("table " + tables_example("fig2c-cancel.tbl") + " --machine bad.toml");
  EXPECT_EQ(bad.code, 1);
  EXPECT_EQ(bad.err.rfind("bad.toml:2:1: error:", 0), 0u) << bad.err;
  EXPECT_NE(bad.err.find("tables.cancel_mode"), std::string::npos) << bad.err;
}

TEST_F(Cli, TableFig6MacroVariablesOverlapTheCornerAndEndEarlier) {
  const std::string both = tables_example("fig6-x.tbl") + " " + tables_example("fig6-z.tbl");
  const Result plain =
      run("table " + both + kLathe + " --var 501=0 --var 502=0 --var 503=0 --trajectory p.csv");
  ASSERT_EQ(plain.code, 0) << plain.err;
  const Result shifted = run("table " + both + kLathe +
                             " --var 501=-200 --var '#502=-400' --var 503=-200 --trajectory s.csv");
  ASSERT_EQ(shifted.code, 0) << shifted.err;
  const auto p = read_csv(dir_ / "p.csv");
  const auto s = read_csv(dir_ / "s.csv");
  ASSERT_FALSE(p.empty());
  ASSERT_FALSE(s.empty());
  // Unshifted (Fig. 5): Z 1.0 … 2.0 s, X 2.0 … 3.0 s, cycle 4.0 s. Shifted: Z 0.8 … 1.8 s,
  // X 1.6 … 2.6 s, cycle 3.6 s: 400 ms earlier.
  EXPECT_NEAR(p.back().at("t"), 4.0, 1e-9);
  EXPECT_NEAR(s.back().at("t"), 3.6, 1e-9);
  EXPECT_NEAR(time_reaching(p, "z", -100, true), 2.0, 1e-9);
  EXPECT_NEAR(time_reaching(s, "z", -100, true), 1.8, 1e-9);
  EXPECT_NEAR(time_reaching(s, "x", 100), 2.6, 1e-9);
  // The corner overlaps: at 1.7 s both axes move (Z = −100·0.9 = −90, X = 100·0.1 = 10).
  bool seen = false;
  for (const auto& row : s) {
    if (std::fabs(row.at("t") - 1.7) > 1e-9) continue;
    seen = true;
    EXPECT_NEAR(row.at("z"), -90, 1e-6);
    EXPECT_NEAR(row.at("x"), 10, 1e-6);
  }
  EXPECT_TRUE(seen);
  // Without the variables the X table is wrong at its SFT=#502 (line 7, column of SFT).
  const Result missing = run("table " + both + kLathe + " --trajectory m.csv");
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("fig6-x.tbl:7:15: error:"), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("#502"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(dir_ / "m.csv"));
}

TEST_F(Cli, TableParameterAndSignalAmounts) {
  write_file(dir_ / "p.tbl", "REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT=P5\nL3000 X300\n");
  const Result p = run("table p.tbl --param 5=-300 --trajectory p.csv" + kLathe);
  ASSERT_EQ(p.code, 0) << p.err;
  const auto pr = read_csv(dir_ / "p.csv");
  EXPECT_NEAR(time_reaching(pr, "x", 200), 1.7, 1e-9);
  EXPECT_NEAR(time_reaching(pr, "x", 300), 2.7, 1e-9);

  write_file(dir_ / "r.tbl", "REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT=R1001\nL3000 X300\n");
  const Result r = run("table r.tbl --signal R1001=-200 --trajectory r.csv" + kLathe);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NEAR(time_reaching(read_csv(dir_ / "r.csv"), "x", 200), 1.8, 1e-9);
  // The signal changes at 0.5 s, before the row is read at 1.0 s: the new value applies.
  const Result at = run(
      "table r.tbl --signal R1001=-200 --signal-at 0.5:R1001=-400 --trajectory at.csv" + kLathe);
  ASSERT_EQ(at.code, 0) << at.err;
  EXPECT_NEAR(time_reaching(read_csv(dir_ / "at.csv"), "x", 200), 1.6, 1e-9);

  const Result undefined = run("table r.tbl --trajectory u.csv");
  EXPECT_EQ(undefined.code, 1);
  EXPECT_EQ(undefined.err.rfind("r.tbl:4:", 0), 0u) << undefined.err;
  EXPECT_FALSE(fs::exists(dir_ / "u.csv"));
  const Result usage = run("table r.tbl --signal R1001=x");
  EXPECT_EQ(usage.code, 2);
  EXPECT_NE(usage.err.find("--signal"), std::string::npos) << usage.err;
}

TEST_F(Cli, BadTableIsExitOneWithFileLineColumnAndNoOutput) {
  // The shift takes the second point back before the first: 2000 − 1500 = 500 < 1000.
  write_file(dir_ / "back.tbl", "REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT-1500\n");
  const Result back = run("table back.tbl --trajectory t.csv --summary s.json");
  EXPECT_EQ(back.code, 1);
  EXPECT_EQ(back.err.rfind("back.tbl:4:1: error:", 0), 0u) << back.err;
  EXPECT_EQ(back.out, "");
  write_file(dir_ / "addr.tbl", "REF TIME\nAXES X\nL1000 X100 Q5\n");
  const Result addr = run("table addr.tbl --trajectory t.csv --summary s.json");
  EXPECT_EQ(addr.code, 1);
  EXPECT_EQ(addr.err.rfind("addr.tbl:3:12: error:", 0), 0u) << addr.err;
  // Nothing written, no temporaries left behind.
  EXPECT_EQ(list_dir(dir_), (std::vector<std::string>{"addr.tbl", "back.tbl"}));
  // An axis the machine does not have (the built-in mill has no B).
  write_file(dir_ / "b.tbl", "REF TIME\nAXES B\nL1000 B10\n");
  const Result axis = run("table b.tbl --trajectory t.csv");
  EXPECT_EQ(axis.code, 1);
  EXPECT_EQ(axis.err.rfind("b.tbl:", 0), 0u) << axis.err;
  EXPECT_FALSE(fs::exists(dir_ / "t.csv"));
}

TEST_F(Cli, TableSpindleReferenceNeedsTheSpeed) {
  const Result missing = run("table " + tables_example("spindle-cam.tbl") + kLathe);
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("spindle-cam.tbl:3:1: error:"), std::string::npos) << missing.err;
  // 60 rpm = 360 deg/s; CYCLIC 3: three revolutions, 3 s, the reference ends at 1080 deg.
  const Result r = run("table " + tables_example("spindle-cam.tbl") + kLathe +
                       " --spindle-rpm 60 --trajectory t.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_csv(dir_ / "t.csv");
  ASSERT_FALSE(rows.empty());
  EXPECT_NEAR(rows.back().at("t"), 3.0, 1e-9);
  EXPECT_NEAR(rows.back().at("ref"), 1080, 1e-6);
  // L180 X10 of each revolution: X = 10 at 0.5, 1.5, 2.5 s.
  for (const double t : {0.5, 1.5, 2.5}) {
    bool seen = false;
    for (const auto& row : rows) {
      if (std::fabs(row.at("t") - t) > 1e-9) continue;
      seen = true;
      EXPECT_NEAR(row.at("x"), 10, 1e-6) << "t = " << t;
      EXPECT_NEAR(row.at("ref"), t * 360, 1e-6);
    }
    EXPECT_TRUE(seen) << t;
  }
}

TEST_F(Cli, TableMasterAxisAndSignalChangeDuringTheRun) {
  // X follows Z: Z moves from its start 0 at 600 mm/min = 10 mm/s, so Z = 50 (X = 10) at 5 s.
  write_file(dir_ / "ax.tbl", "REF AXIS Z\nAXES X\nL50 X10\nL100 X20\n");
  const Result r = run("table ax.tbl" + kLathe + " --master-speed 600 --trajectory ax.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_csv(dir_ / "ax.csv");
  EXPECT_NEAR(time_reaching(rows, "x", 10), 5.0, 1e-9);
  EXPECT_NEAR(time_reaching(rows, "z", 50), 5.0, 1e-9);
  EXPECT_NEAR(rows.back().at("t"), 10.0, 1e-9);
  for (const auto& row : rows) ASSERT_NEAR(row.at("ref"), row.at("z"), 1e-6);
  const Result no_speed = run("table ax.tbl" + kLathe);
  EXPECT_EQ(no_speed.code, 1);
  EXPECT_EQ(no_speed.err.rfind("ax.tbl:1:", 0), 0u) << no_speed.err;

  // R1 changes to −1500 at 0.5 s; the row L2000 SFT=R1 is read later and goes back to 500 ms:
  // the error comes during the run, and still no output is left.
  write_file(dir_ / "late.tbl", "REF TIME\nAXES X\nL1000 X100\nL2000 X200 SFT=R1\nL3000 X300\n");
  const Result late = run(
      "table late.tbl --signal R1=0 --signal-at 0.5:R1=-1500 --trajectory t.csv --summary s.json" +
      kLathe);
  EXPECT_EQ(late.code, 1);
  EXPECT_NE(late.err.find("late.tbl:4:1: error:"), std::string::npos) << late.err;
  EXPECT_EQ(list_dir(dir_), (std::vector<std::string>{"ax.csv", "ax.tbl", "late.tbl"}));
}

TEST_F(Cli, TableOverTheAxisSpeedIsRefusedOrSlowedToFit) {
  // 100 mm in 100 ms = 60 000 mm/min; the built-in X allows 15 000 mm/min (4 times less).
  write_file(dir_ / "fast.tbl", "REF TIME\nAXES X\nL100 X100\n");
  const Result refused = run("table fast.tbl --trajectory t.csv");
  EXPECT_EQ(refused.code, 1);
  EXPECT_NE(refused.err.find("fast.tbl:3:1: error: X speed 60000 mm/min"), std::string::npos)
      << refused.err;
  EXPECT_FALSE(fs::exists(dir_ / "t.csv"));

  // X stiff enough for the step of 1000 mm/s at the start: only the speed is slowed.
  write_file(dir_ / "slow.toml",
             "[tables]\nslow_to_fit = true\n[axes.x]\nmax_accel_mm_s2 = 1000000\n");
  const Result slowed =
      run("table fast.tbl --machine slow.toml --trajectory t.csv --summary s.json");
  ASSERT_EQ(slowed.code, 0) << slowed.err;
  EXPECT_NE(slowed.out.find("slowed        reference runs 4 times slower"), std::string::npos)
      << slowed.out;
  const auto rows = read_csv(dir_ / "t.csv");
  EXPECT_NEAR(time_reaching(rows, "x", 100), 0.4, 1e-9);  // 100 ms of reference × 4
  const auto j = nlohmann::json::parse(slurp(dir_ / "s.json"));
  EXPECT_NEAR(j.at("max_axis_speed_mm_min").at("x").get<double>(), 15000, 1e-3);
}

}  // namespace

TEST_F(Cli, TableMasterAxisMovedByAPartProgramAndMCodesFire) {
  // An electronic cam: Y follows X (Y = X / 5), X is moved by a part program that also lifts Z.
  write_file(dir_ / "cam.tbl", "REF AXIS X\nAXES Y\nL0 Y0\nL50 Y10 M8\nL100 Y20 M9\n");
  write_file(dir_ / "master.ngc", "G21 G90 G1 F3000 Z5\nX100\nM2\n");
  const Result r =
      run("table cam.tbl --master-program master.ngc --trajectory cam.csv --summary cam.json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_csv(dir_ / "cam.csv");
  ASSERT_GT(rows.size(), 100u);
  double max_x_speed_mm_min = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    ASSERT_NEAR(rows[i].at("y"), rows[i].at("x") / 5, 1e-6) << "row " << i;
    ASSERT_NEAR(rows[i].at("ref"), rows[i].at("x"), 1e-9) << "row " << i;
    if (i > 0) {
      const double dt = rows[i].at("t") - rows[i - 1].at("t");
      max_x_speed_mm_min =
          std::max(max_x_speed_mm_min, (rows[i].at("x") - rows[i - 1].at("x")) / dt * 60);
    }
  }
  // The program's own motion: Z goes up first, X runs at its programmed 3000 mm/min.
  EXPECT_NEAR(rows.back().at("z"), 5, 1e-6);
  EXPECT_NEAR(rows.back().at("x"), 100, 1e-6);
  EXPECT_NEAR(max_x_speed_mm_min, 3000, 3000 * 0.005);
  // Z first: no set-point has X off 0 before Z is at 5 (the corner X 0 Z 5 is not cut). The
  // moving average stops there; the acceleration type passes it at its corner speed, so the
  // cycle that crosses it ends with Z at 5 and X already moved — never earlier. (CSV: 1 µm.)
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].at("x") > 0) {
      ASSERT_NEAR(rows[i].at("z"), 5, 1e-6) << "row " << i;
    }
  }
  // M8 fires in the cycle X reaches 50, M9 at the end; both are in the summary.
  std::vector<std::pair<double, double>> m;  // (x, code)
  for (const auto& row : rows) {
    // A trailing empty cell is not in the map (getline drops it).
    const auto it = row.find("m");
    if (it != row.end() && !std::isnan(it->second)) m.emplace_back(row.at("x"), it->second);
  }
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].second, 8);
  EXPECT_GE(m[0].first, 50 - 1e-9);
  EXPECT_LT(m[0].first, 50 + 3000.0 / 60 * 0.001 + 1e-9);  // within one cycle's travel
  EXPECT_EQ(m[1].second, 9);
  const auto json = nlohmann::json::parse(slurp(dir_ / "cam.json"));
  EXPECT_EQ(json.at("aux_event_count"), 2);
  EXPECT_EQ(json.at("aux_events").at(0).at("code"), "M8");
  EXPECT_EQ(json.at("aux_events").at(0).at("line"), 4);
  // Table runs are not judged by path limits (the cam's Y and X together exceed no axis).
  EXPECT_EQ(r.out.find("path speed"), std::string::npos) << r.out;

  // An error in the master program: exit 1 with its FILE:LINE:COL, nothing written.
  write_file(dir_ / "bad.ngc", "G21 G90 G1 F3000\nX40\nG1 X60 Q\n");
  const Result bad = run("table cam.tbl --master-program bad.ngc --trajectory b.csv");
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find("bad.ngc:3:"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir_ / "b.csv"));
  // A master program needs REF AXIS.
  write_file(dir_ / "time.tbl", "REF TIME\nAXES X\nL1000 X10\n");
  EXPECT_EQ(run("table time.tbl --master-program master.ngc").code, 2);
}

TEST_F(Cli, TableAmountsFromTheMachineConfigurationAndTheCommandLineOverridesThem) {
  write_file(dir_ / "m.toml",
             "[tables.parameters]\n5 = -300\n[tables.variables]\n501 = -200\n"
             "[tables.signals]\n1001 = -400\n[axes.x]\nmax_accel_mm_s2 = 150000\n");
  write_file(dir_ / "all.tbl",
             "REF TIME\nAXES X\nL1000 X10\nL2000 X20 SFT=P5\nL3000 X30 SFT=#501\n"
             "L4000 X40 SFT=R1001\nL5000 X50\n");
  // Shifts accumulate: −300 from row 4, −500 from row 5, −900 from row 6.
  const Result r = run("table all.tbl --machine m.toml --trajectory a.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = read_csv(dir_ / "a.csv");
  EXPECT_NEAR(time_reaching(rows, "x", 20), 1.7, 1e-9);
  EXPECT_NEAR(time_reaching(rows, "x", 30), 2.5, 1e-9);
  EXPECT_NEAR(time_reaching(rows, "x", 40), 3.1, 1e-9);
  EXPECT_NEAR(time_reaching(rows, "x", 50), 4.1, 1e-9);
  // The command line overrides one value and keeps the others.
  const Result o = run("table all.tbl --machine m.toml --var 501=0 --trajectory o.csv");
  ASSERT_EQ(o.code, 0) << o.err;
  const auto orows = read_csv(dir_ / "o.csv");
  EXPECT_NEAR(time_reaching(orows, "x", 30), 2.7, 1e-9);
  EXPECT_NEAR(time_reaching(orows, "x", 50), 4.3, 1e-9);
  // The printed configuration reads back with the values.
  const Result printed = run("machine --machine m.toml");
  ASSERT_EQ(printed.code, 0) << printed.err;
  EXPECT_NE(printed.out.find("[tables.variables]\n501 = -200\n"), std::string::npos) << printed.out;
  write_file(dir_ / "again.toml", printed.out);
  const Result again = run("table all.tbl --machine again.toml --trajectory b.csv");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(slurp(dir_ / "b.csv"), slurp(dir_ / "a.csv"));
  // A key that is not a number: FILE:LINE:COL naming it.
  write_file(dir_ / "bad.toml", "[tables.parameters]\nP5 = -300\n");
  const Result bad = run("table all.tbl --machine bad.toml");
  EXPECT_EQ(bad.code, 1);
  EXPECT_EQ(bad.err.rfind("bad.toml:2:1: error: tables.parameters: key 'P5'", 0), 0u) << bad.err;
}
