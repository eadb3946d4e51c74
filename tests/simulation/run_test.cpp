// The driver: every sample reaches every observer in order, blocks are announced before they
// move, override steps act at the first cycle with t >= T, and an error in the program stops
// the machine at the end of the last good block before the error is rethrown.
#include "simulation/run.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"

namespace cncore::sim {
namespace {

struct Recorder : SampleObserver {
  std::vector<motion::Sample> samples;
  std::vector<Block> blocks;
  std::vector<std::size_t> samples_at_block;  // samples seen when each block was announced
  bool finished = false;
  void on_block(const Block& b) override {
    blocks.push_back(b);
    samples_at_block.push_back(samples.size());
  }
  void on_sample(const motion::Sample& s) override { samples.push_back(s); }
  void on_finish() override { finished = true; }
};

std::string program_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

TEST(RunProgram, DeliversEverySampleToEveryObserver) {
  const std::string p =
      program_file("square.ngc", "G21 G90\nG1 X10 F3000\nG1 Y10\nG1 X0\nG1 Y0\nM30\n");
  Recorder a, b;
  const RunCounts n = run_program(p, default_machine_config(), {}, {&a, &b});
  EXPECT_TRUE(a.finished && b.finished);
  EXPECT_EQ(n.blocks, 4u);
  EXPECT_EQ(n.cycles, a.samples.size());
  ASSERT_EQ(a.samples.size(), b.samples.size());
  ASSERT_GT(a.samples.size(), 10u);
  EXPECT_EQ(a.samples.front().t_s, 0.0);
  for (std::size_t i = 1; i < a.samples.size(); ++i) {
    ASSERT_NEAR(a.samples[i].t_s - a.samples[i - 1].t_s, 0.001, 1e-9);
    ASSERT_EQ(a.samples[i].position, b.samples[i].position);
  }
  // Every motion block is announced before any sample executes its line.
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const std::uint32_t line = a.blocks[k].line;
    for (std::size_t i = 0; i < a.samples_at_block[k]; ++i) {
      ASSERT_NE(a.samples[i].line, line) << "block of line " << line << " announced late";
    }
  }
  EXPECT_NEAR(a.samples.back().position[kX], 0, 1e-9);
  EXPECT_NEAR(a.samples.back().position[kY], 0, 1e-9);
}

TEST(RunProgram, OverrideStepsActAtTheFirstCycleAtOrAfterTheirTime) {
  const std::string p = program_file("long.ngc", "G21 G90\nG1 X200 F6000\nM30\n");
  RunOptions o;
  o.override_steps = {{0.5, 40}, {0.25, 150}};  // unsorted on purpose
  Recorder r;
  run_program(p, default_machine_config(), o, {&r});
  ASSERT_GT(r.samples.size(), 600u);
  for (const auto& s : r.samples) {
    const double expected = s.t_s < 0.25 - 1e-9 ? 100 : (s.t_s < 0.5 - 1e-9 ? 150 : 40);
    ASSERT_NEAR(s.override_pct, expected, 1e-9) << "t = " << s.t_s;
  }
}

TEST(RunProgram, AnErrorStopsAtTheEndOfTheLastGoodBlockThenThrows) {
  const std::string p =
      program_file("error.ngc", "G21 G90\nG1 X10 F3000\nG1 X10 Y10\nG2 X20 Y20\nG1 X0\nM30\n");
  Recorder r;
  try {
    run_program(p, default_machine_config(), {}, {&r});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 4u) << e.formatted();
  }
  EXPECT_FALSE(r.finished);
  ASSERT_FALSE(r.samples.empty());
  // The machine came to rest at X10 Y10, the end of line 3.
  const auto& last = r.samples.back();
  EXPECT_NEAR(last.position[kX], 10, 1e-9);
  EXPECT_NEAR(last.position[kY], 10, 1e-9);
  if (r.samples.size() >= 2) {
    const auto& before = r.samples[r.samples.size() - 2];
    // Arriving at rest: the last cycle moves less than Amax·τ² = 2000·1e-6 = 0.002 mm.
    EXPECT_LT(std::hypot(last.position[kX] - before.position[kX],
                         last.position[kY] - before.position[kY]),
              0.002 + 1e-9);
  }
}

TEST(RunProgram, MissingFileIsAnInputError) {
  Recorder r;
  EXPECT_THROW(run_program("/nonexistent/p.ngc", default_machine_config(), {}, {&r}), InputError);
  EXPECT_TRUE(r.samples.empty());
}

}  // namespace
}  // namespace cncore::sim
