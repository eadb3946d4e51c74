// The sample search (motion/sample_search.hpp): its samples go to the independent
// checker (P1–P4 by finite differences), and its cycle count is compared with the acceleration
// type's on the same blocks. Nothing here reads the search's own variables except its counters
// (forced commits, recoveries) to show that a case exercised them.
#include "motion/sample_search.hpp"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "motion_test_util.hpp"
#include "program_gen_rc.hpp"
#include "trajectory_checker.hpp"

namespace cncore::motion::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct SearchRun {
  testing::Trajectory traj;
  SampleSearchStats stats;
  std::string error;         // empty: ran to the end
  long allocations = 0;      // during advance() and pop()
  std::uint64_t cycles = 0;  // samples − 1
};

// Feeds the blocks as they fit (the window streams), searches and pops every committed sample.
SearchRun run_search(const MachineConfig& m, const std::vector<Block>& blocks,
                     const SampleSearchOptions& o = {}) {
  SearchRun r;
  SampleSearch ss(planner::make_limits(m, false), o);
  r.traj.period_s = m.period_s;
  std::size_t next = 0;
  bool ended = false;
  AxisVec p;
  std::uint32_t line = 0;
  double s = 0;
  while (!ss.finished()) {
    while (next < blocks.size() && ss.wants_segment()) {
      if (!ss.push(blocks[next++])) {
        r.error = "block not supported";
        return r;
      }
    }
    if (next == blocks.size() && !ended) {
      ss.end_of_program();
      ended = true;
    }
    long before = cncore::testing::allocations();
    if (ss.at_stop() && ss.ready() == 0) ss.resume();  // released at once
    const bool moved = ss.advance();
    r.allocations += cncore::testing::allocations() - before;
    std::size_t popped = 0;
    for (;;) {
      before = cncore::testing::allocations();
      const bool got = ss.pop(p, line, s);
      r.allocations += cncore::testing::allocations() - before;
      if (!got) break;
      r.traj.add(static_cast<double>(r.traj.size()) * m.period_s, line, p);
      ++popped;
    }
    if (ss.failed()) {
      r.error = "failed";
      break;
    }
    if (!moved && popped == 0 && !ss.finished() && (next == blocks.size() || !ss.wants_segment())) {
      r.error = "stuck";
      break;
    }
  }
  r.stats = ss.stats();
  r.cycles = r.traj.size() > 0 ? r.traj.size() - 1 : 0;
  return r;
}

std::uint64_t kernel_cycles(const MachineConfig& m, const std::vector<Block>& blocks) {
  RunOpts o;
  o.kernel.accdec = AccDecType::kAcceleration;
  o.keep_samples = true;
  const RunResult r = run(m, blocks, o);
  return r.samples.size() - 1;
}

void expect_clean(const MachineConfig& m, const Prog& p, const SearchRun& r,
                  const std::string& what) {
  ASSERT_TRUE(r.error.empty()) << what << ": " << r.error;
  const auto rep = testing::check_trajectory(r.traj, p.blocks, testing::limits_from_config(m));
  EXPECT_TRUE(rep.ok()) << what << ": " << rep.summary();
  ASSERT_FALSE(r.traj.empty());
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(r.traj.pos.back()[i], p.pos[i], 1e-9) << what;
}

MachineConfig machine() {
  MachineConfig m = test_machine();
  for (std::size_t i = 0; i < 3; ++i) m.axes[i].max_accel_mm_s2 = 2000;
  return m;
}

// Part of a circle of radius R in chords of `chord_mm`, coordinates rounded to 4 decimals of an
// inch (2.54 µm) as circle_small_segments is written: a staircase of alternating micro-corners.
Prog rounded_circle(double r_mm, double chord_mm, double sweep_deg, double feed = 10000) {
  auto rnd = [](double v) { return std::round(v / 25.4 * 1e4) / 1e4 * 25.4; };
  Prog p;
  p.line_to(Vec3{0, r_mm, 0}, feed);
  const double sweep = sweep_deg * kPi / 180;
  const int n = static_cast<int>(std::lround(sweep * r_mm / chord_mm));
  for (int k = 1; k <= n; ++k) {
    const double a = sweep * k / n;
    p.line_to(Vec3{rnd(r_mm * std::sin(a)), rnd(r_mm * std::cos(a)), 0}, feed);
  }
  return p;
}

TEST(SampleSearch, SeedExampleKeepsEveryLimitAndEndsAtRest) {
  const MachineConfig m = machine();
  const Prog p = seed_example();
  const SearchRun r = run_search(m, p.blocks);
  expect_clean(m, p, r, "seed example");
  EXPECT_EQ(r.allocations, 0);
  // Measured: 747 cycles against the acceleration type's 753 (the search crosses the tangent
  // joints and lands on the end as late as the rules allow).
  const std::uint64_t k = kernel_cycles(m, p.blocks);
  EXPECT_LE(r.cycles, k) << r.cycles << " cycles, kernel " << k;
}

// A long move runs at its feed: the step that meets the feed exactly is a candidate, and it is
// compared with the cap up to rounding (without either, a circle at F600 ran at 9.49 of 10 mm/s
// from 8 mm on, where s + cap − s first exceeded the cap by an ulp).
TEST(SampleSearch, LongMovesRunAtTheirFeed) {
  const MachineConfig m = machine();
  Prog p;
  p.line_to(Vec3{30, 0, 0}, 600);
  p.arc_to(Vec3{30, 0, 0}, Vec3{0, 0, 0}, 600);  // full circle, R 30
  const SearchRun r = run_search(m, p.blocks);
  expect_clean(m, p, r, "line and circle at F600");
  // Path speed from the samples: the chords over the middle of the line and of the circle.
  const double limit_mm_s = 600.0 / 60.0;
  for (const std::size_t from : {1000UL, 10000UL}) {
    const std::size_t k = from + 1000;
    const double dist = [&] {
      double sum = 0;
      for (std::size_t i = from + 1; i <= k; ++i) {
        const AxisVec d = r.traj.pos[i] - r.traj.pos[i - 1];
        sum += norm(d.xyz());
      }
      return sum;
    }();
    const double v_mm_s = dist / (static_cast<double>(k - from) * m.period_s);
    EXPECT_GT(v_mm_s, 0.998 * limit_mm_s) << "from sample " << from;
    EXPECT_LE(v_mm_s, limit_mm_s * (1 + 1e-9)) << "from sample " << from;
  }
}

// The case the search is for: the kernel's zones must hold for every placement of its samples,
// the search places them so that the staircase's turns cancel within a pair of steps.
TEST(SampleSearch, StaircaseOfRoundedChordsRunsFasterThanTheAccelerationType) {
  const MachineConfig m = machine();
  const Prog p = rounded_circle(25.4, 0.016, 45);
  const SearchRun r = run_search(m, p.blocks);
  expect_clean(m, p, r, "rounded circle");
  EXPECT_EQ(r.allocations, 0);
  const std::uint64_t k = kernel_cycles(m, p.blocks);
  std::printf("rounded circle, 45°: search %llu cycles, acceleration type %llu (%.3f)\n",
              static_cast<unsigned long long>(r.cycles), static_cast<unsigned long long>(k),
              static_cast<double>(r.cycles) / static_cast<double>(k));
  EXPECT_LT(static_cast<double>(r.cycles), 0.95 * static_cast<double>(k));
}

// A small window (the front waits for segments a braking distance ahead) and a short lag (the
// commits are forced): the same rules hold.
TEST(SampleSearch, SmallWindowAndForcedCommitsKeepEveryLimit) {
  const MachineConfig m = machine();
  const Prog p = rounded_circle(25.4, 0.016, 30);
  SampleSearchOptions o;
  o.window_segments = 1024;
  o.max_lag_cycles = 16;
  const SearchRun r = run_search(m, p.blocks, o);
  expect_clean(m, p, r, "small window, lag 16");
  EXPECT_GT(r.stats.forced, 0u);
  EXPECT_EQ(r.allocations, 0);
}

// Exact stops (G9) and a waiting M-code stop the tool on their points; a zig-zag's corners.
TEST(SampleSearch, StopsAndCornersKeepEveryLimit) {
  const MachineConfig m = machine();
  Prog p;
  p.line_to(Vec3{10, 0, 0}, 6000, PathMode::kExactStop);
  p.line_to(Vec3{10, 5, 0}, 6000);
  p.aux('M', 0, true);
  for (int i = 0; i < 10; ++i) p.line_to(Vec3{i % 2 == 0 ? 0.0 : 10.0, 6.0 + i, 0}, 10000);
  p.rapid_to(Vec3{0, 0, 5});
  const SearchRun r = run_search(m, p.blocks);
  expect_clean(m, p, r, "stops and corners");
  EXPECT_EQ(r.allocations, 0);
}

TEST(SampleSearch, UnsupportedBlocksAreRefused) {
  const MachineConfig m = machine();
  SampleSearch ss(planner::make_limits(m, false), {});
  Prog p;
  p.line_to(Vec3{1, 0, 0}, 600).dwell(0.5);
  EXPECT_TRUE(ss.push(p.blocks[0]));
  EXPECT_FALSE(ss.push(p.blocks[1]));
}

RC_GTEST_PROP(SampleSearch, RandomProgramsKeepEveryLimit, ()) {
  MachineConfig m = machine();
  testing::gen::BlockGenOptions g;
  g.max_blocks = 10;
  g.min_feed_mm_min = 600;
  g.max_len_mm = 20;
  g.stops = false;  // (dwells are not supported)
  Prog p;
  p.blocks = *testing::gen::blocks(g);
  p.pos = program_end(AxisVec{}, p.blocks);
  SampleSearchOptions o;
  o.max_lag_cycles = *rc::gen::element<std::size_t>(16, 128);
  const SearchRun r = run_search(m, p.blocks, o);
  RC_ASSERT(r.error.empty());
  const auto rep = testing::check_trajectory(r.traj, p.blocks, testing::limits_from_config(m));
  RC_ASSERT(rep.ok());
}

}  // namespace
}  // namespace cncore::motion::test
