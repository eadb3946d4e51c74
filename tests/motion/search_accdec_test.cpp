// The acc/dec type "search" (motion/search_accdec.hpp) inside the kernel: the samples of whole
// runs go to the independent checker (P1–P5), with override steps, feed hold, dwells, exact
// stops, waiting events and late blocks, and its cycle counts are compared with the
// acceleration type's on the same blocks.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "motion_test_util.hpp"
#include "program_gen_rc.hpp"
#include "trajectory_checker.hpp"

namespace cncore::motion::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

RunOpts search_opts() {
  RunOpts o;
  o.kernel.accdec = AccDecType::kSearch;
  return o;
}

RunResult run_checked(const MachineConfig& m, const Prog& p, const RunOpts& o, const char* what) {
  RunResult r = run(m, p.blocks, o);
  const auto rep = testing::check_trajectory(r.traj, p.blocks, testing::limits_from_config(m));
  EXPECT_TRUE(rep.ok()) << what << ": " << rep.summary();
  EXPECT_FALSE(r.samples.empty()) << what;
  if (!r.samples.empty()) {
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_NEAR(r.samples.back().position[i], p.pos[i], 1e-9) << what;
    }
    EXPECT_EQ(r.samples.back().feed_mm_min, 0.0) << what << ": not at rest at the end";
  }
  return r;
}

std::size_t cycles(const RunResult& r) {
  return r.samples.size() - 1;
}

std::size_t acceleration_cycles(const MachineConfig& m, const Prog& p) {
  RunOpts o;
  o.kernel.accdec = AccDecType::kAcceleration;
  return cycles(run(m, p.blocks, o));
}

// The test machine with the built-in machine's axes: each axis's acceleration limit is Amax.
MachineConfig amax_axes_machine() {
  MachineConfig m = test_machine();
  for (std::size_t i = 0; i < 3; ++i) m.axes[i].max_accel_mm_s2 = m.max_accel_mm_s2;
  return m;
}

// circle_small_segments' staircase: 16 µm chords of a 1-inch circle, rounded to 4 decimals of an
// inch.
Prog rounded_circle(double sweep_deg) {
  auto rnd = [](double v) { return std::round(v / 25.4 * 1e4) / 1e4 * 25.4; };
  const double r_mm = 25.4;
  Prog p;
  p.line_to(Vec3{0, r_mm, 0}, 10000);
  const double sweep = sweep_deg * kPi / 180;
  const int n = static_cast<int>(std::lround(sweep * r_mm / 0.016));
  for (int k = 1; k <= n; ++k) {
    const double a = sweep * k / n;
    p.line_to(Vec3{rnd(r_mm * std::sin(a)), rnd(r_mm * std::cos(a)), 0}, 10000);
  }
  return p;
}

TEST(SearchAccDec, ExamplesKeepEveryLimitAndAreNoSlowerThanTheAccelerationType) {
  const MachineConfig m = test_machine();
  struct Case {
    const char* name;
    Prog p;
  };
  for (const Case& c :
       {Case{"seed example", seed_example()}, Case{"corner example", corner_example()},
        Case{"contour example", contour_example()}}) {
    const RunResult r = run_checked(m, c.p, search_opts(), c.name);
    const std::size_t k = acceleration_cycles(m, c.p);
    std::printf("%s: search %zu cycles, acceleration type %zu\n", c.name, cycles(r), k);
    // Measured: 746, 981 and 4 062 cycles against 750, 987 and 4 067 (before the guide braked
    // to a sharp corner's cap one step early, the zig-zag took 4 177: narrow beams lost their
    // states that braked latest).
    EXPECT_LE(cycles(r), k) << c.name;
  }
}

// Axes whose acceleration limit is Amax (the built-in machine's): braking by exactly a along X
// reads a second difference of a ± ulps. Compared strictly, braking at the full rate failed,
// and the search braked a/8 short every cycle: 273 cycles here against the acceleration type's
// 250 (with the comparison up to rounding: 245).
TEST(SearchAccDec, BrakingAlongAnAxisAtItsLimitIsNoSlowerThanTheAccelerationType) {
  const MachineConfig m = amax_axes_machine();
  Prog p;
  p.line_to(Vec3{5, 0, 0}, 10000);
  p.line_to(Vec3{5, 1, 0}, 10000);
  p.line_to(Vec3{0, 1, 0}, 10000);
  const RunResult r = run_checked(m, p, search_opts(), "zig-zag on axes at Amax");
  const std::size_t k = acceleration_cycles(m, p);
  std::printf("zig-zag on axes at Amax: search %zu cycles, acceleration type %zu\n", cycles(r), k);
  EXPECT_LE(cycles(r), k);
}

// zigzag_0.002's strokes: 52 µm turning by 53° every ~9 cycles. The guide's sharp-corner term
// (brake to the cap one step early) wins where corners are far apart and loses here, where the
// beam needs the states that fail only it: 519 cycles against the acceleration type's 508 while
// the guide dropped them, 506 with them kept as a class of their own.
TEST(SearchAccDec, ShortZigZagStrokesAreNoSlowerThanTheAccelerationType) {
  const MachineConfig m = amax_axes_machine();
  Prog p;
  for (int k = 1; k <= 56; ++k)
    p.line_to(Vec3{0.0508 * k, k % 2 == 1 ? -0.0127 : 0.0127, 0}, 10000);
  const RunResult r = run_checked(m, p, search_opts(), "short zig-zag strokes");
  const std::size_t k = acceleration_cycles(m, p);
  std::printf("short zig-zag strokes: search %zu cycles, acceleration type %zu\n", cycles(r), k);
  EXPECT_LE(cycles(r), k);
}

TEST(SearchAccDec, StaircaseOfRoundedChordsRunsFasterThanTheAccelerationType) {
  const MachineConfig m = test_machine();
  const Prog p = rounded_circle(45);
  const RunResult r = run_checked(m, p, search_opts(), "rounded circle");
  const std::size_t k = acceleration_cycles(m, p);
  std::printf("rounded circle, 45°: search %zu cycles, acceleration type %zu (%.3f)\n", cycles(r),
              k, static_cast<double>(cycles(r)) / static_cast<double>(k));
  EXPECT_LT(static_cast<double>(cycles(r)), 0.95 * static_cast<double>(k));
}

TEST(SearchAccDec, OverrideStepsAndFeedHold) {
  const MachineConfig m = test_machine();
  RunOpts o = search_opts();
  o.override_steps = p5_override_steps();
  run_checked(m, corner_example(6000), o, "override steps");
  RunOpts h = search_opts();
  h.hold_steps = {{0.2, true}, {0.6, false}};
  const RunResult r = run_checked(m, seed_example(10000), h, "feed hold");
  // Stopped within Vmax/Amax (+2 cycles) of the hold, until the resume: positions unchanged.
  for (std::size_t i = 1; i < r.samples.size(); ++i) {
    const double t = r.samples[i].t_s;
    if (t >= 0.2 + 10000.0 / 60 / 2000 + 0.002 && t < 0.6) {
      ASSERT_EQ(r.samples[i].position[0], r.samples[i - 1].position[0]) << "t " << t;
      ASSERT_EQ(r.samples[i].position[1], r.samples[i - 1].position[1]) << "t " << t;
    }
  }
}

// An operator turning the override knob: a step every 37 ms on the staircase of rounded chords.
// Each step replans from the tool's sample; the new plan must neither break a limit nor bring
// the tool to rest (a death of the search is met by a brake to rest: committing from a beam only
// a few cycles deep, to keep the replanning cycle short, does that 2 times here).
TEST(SearchAccDec, FrequentOverrideStepsNeverBringTheToolToRest) {
  const MachineConfig m = test_machine();
  const Prog p = rounded_circle(30);
  const std::size_t plain = cycles(run(m, p.blocks, search_opts()));
  RunOpts o = search_opts();
  for (int k = 1; k < 40; ++k) o.override_steps.emplace_back(0.037 * k, k % 3 == 0 ? 100 : 95);
  const RunResult r = run_checked(m, p, o, "override steps every 37 ms");
  std::size_t first = 0, last = 0;
  for (std::size_t i = 1; i < r.samples.size(); ++i) {
    if (r.samples[i].position == r.samples[i - 1].position) continue;
    if (first == 0) first = i;
    last = i;
  }
  for (std::size_t i = first; i <= last; ++i)
    ASSERT_NE(r.samples[i].position, r.samples[i - 1].position) << "at rest at sample " << i;
  std::printf("override steps every 37 ms: %zu cycles, without steps %zu\n", cycles(r), plain);
  EXPECT_LE(static_cast<double>(cycles(r)), 1.01 * static_cast<double>(plain));
}

TEST(SearchAccDec, DwellsExactStopsAndEventsStopTheTool) {
  const MachineConfig m = test_machine();
  Prog p;
  p.line_to(Vec3{10, 0, 0}, 6000, PathMode::kExactStop);
  p.line_to(Vec3{10, 5, 0}, 6000);
  p.dwell(0.1);
  p.line_to(Vec3{0, 5, 0}, 6000);
  p.aux('M', 0, true);
  p.aux('M', 8, false);
  for (int i = 0; i < 6; ++i) p.line_to(Vec3{i % 2 == 0 ? 2.0 : 0.0, 6.0 + i, 0}, 10000);
  const RunResult r = run_checked(m, p, search_opts(), "stops");
  // The dwell: at rest on (10, 5) for 0.1 s.
  std::size_t still = 0;
  for (std::size_t i = 1; i < r.samples.size(); ++i) {
    const AxisVec& q = r.samples[i].position;
    if (q[0] == 10 && q[1] == 5 && r.samples[i - 1].position == q) ++still;
  }
  EXPECT_GE(static_cast<double>(still), 0.1 / m.period_s - 1);
  bool m8 = false;
  for (const Sample& s : r.samples) m8 = m8 || (s.aux_letter == 'M' && s.aux_value == 8);
  EXPECT_TRUE(m8);
}

// A dwell or a waiting event before the first move: the tool waits for it at the start.
TEST(SearchAccDec, DwellBeforeTheFirstMove) {
  const MachineConfig m = test_machine();
  // (At 50 % the override differs from the search's initial plan: its replan must keep the
  // wait; it did not, in `cncore run`.)
  for (const double override_pct : {100.0, 50.0}) {
    for (const std::size_t feed_every : {0UL, 1UL}) {
      Prog p;
      p.dwell(0.01);
      p.rapid_to(Vec3{0, 0, 5});
      p.line_to(Vec3{5, 8, 5}, 400);
      RunOpts o = search_opts();
      o.kernel.override_pct = override_pct;
      o.feed_every = feed_every;
      const RunResult r = run_checked(m, p, o, "dwell first");
      for (std::size_t i = 0; i <= 10 && i < r.samples.size(); ++i) {
        EXPECT_EQ(r.samples[i].position[2], 0.0)
            << "sample " << i << ", feed_every " << feed_every << ", " << override_pct << " %";
      }
    }
  }
}

TEST(SearchAccDec, LateBlocksKeepEveryLimit) {
  MachineConfig m = test_machine();
  m.lookahead_blocks = 8;
  RunOpts o = search_opts();
  o.feed_every = 1;  // one block per cycle: the window's end comes at the tool
  run_checked(m, contour_example(), o, "late blocks");
  run_checked(m, rounded_circle(10), o, "late blocks, staircase");
}

// With late blocks the plan rests 10–20 nm before the window's end (a wall); the next block
// reverses the path there. The checker may read the rest sample as lying just past the fold (the
// reading that needs the lowest speed), and the step after the crossing then measured 2 018 mm/s²
// on 2 000 (RapidCheck, seed 21) until the search kept a fold's crossing step ≤ the step before
// it + y (SampleSearch::step_ok), so that its own reading is the cheaper one; and the same past a
// fold (SampleSearch::expand). Also a reversal in a program known at once, crossed from speed.
TEST(SearchAccDec, ReversalsAfterARestOrAtSpeedKeepEveryLimit) {
  MachineConfig m = test_machine();
  m.lookahead_blocks = 4;
  Prog p;
  p.rapid_to(Vec3{-0.001, 0, 0});
  p.rapid_to(Vec3{-0.001, 0.001, 0});
  Block& last = p.rapid_to(Vec3{-0.001, -0.0048288561728783109, 0}).blocks.back();
  last.path_mode = PathMode::kExactStop;
  RunOpts o = search_opts();
  o.feed_every = 1;
  run_checked(m, p, o, "late reversal");
  o.feed_every = 0;
  run_checked(m, p, o, "reversal");
  // A sample 26 nm past a 1.08 µm reversal is read 26 nm before it unless the next step keeps
  // that reading the dearer one (RapidCheck, seed 10: 2 971 → 947 nm/cycle read, 2 024 mm/s²).
  Prog r;
  r.rapid_to(Vec3{-0.0059417296438274841, 0, 0});
  r.rapid_to(Vec3{-0.0048592786588311067, 0, 0}).blocks.back().path_mode = PathMode::kExactStop;
  run_checked(m, r, o, "sample just past a reversal");
  Prog q;
  q.line_to(Vec3{3, 0, 0}, 3000);
  q.line_to(Vec3{2.9995, 0.0001, 0}, 3000);  // 167° back
  q.line_to(Vec3{6, 1, 0}, 3000);            // and back again
  for (const std::size_t feed_every : {0UL, 1UL}) {
    o.feed_every = feed_every;
    run_checked(m, q, o, "reversals at speed");
  }
}

TEST(SearchAccDec, RefusesAJerkStageOrAPostFilter) {
  MachineConfig m = test_machine();
  m.max_jerk_mm_s3 = 1e6;
  EXPECT_THROW(Kernel(m, search_opts().kernel), std::invalid_argument);
  m = test_machine();
  m.post_filter_s = 0.008;
  EXPECT_THROW(Kernel(m, search_opts().kernel), std::invalid_argument);
}

RC_GTEST_PROP(SearchAccDec, RandomProgramsWithOverrideStepsKeepEveryLimit, ()) {
  MachineConfig m = test_machine();
  m.lookahead_blocks = *rc::gen::inRange(4, 40);
  testing::gen::BlockGenOptions g;
  g.max_blocks = 10;
  g.min_feed_mm_min = 600;
  g.max_len_mm = 20;
  Prog p;
  p.blocks = *testing::gen::blocks(g);
  p.pos = program_end(AxisVec{}, p.blocks);
  RunOpts o = search_opts();
  o.max_cycles = 2'000'000;
  o.feed_every = *rc::gen::element<std::size_t>(0, 0, 1);
  o.override_steps = *testing::gen::override_steps(2.0);
  if (!o.override_steps.empty()) o.override_steps.emplace_back(2.5, 100.0);
  const RunResult r = run(m, p.blocks, o);
  const auto rep = testing::check_trajectory(r.traj, p.blocks, testing::limits_from_config(m));
  if (!rep.ok()) {
    RC_LOG() << rep.summary() << " feed_every " << o.feed_every << " buffer " << m.lookahead_blocks
             << "\n";
    for (const Block& b : p.blocks) {
      RC_LOG() << "kind " << static_cast<int>(b.kind) << " line " << b.line << " (" << b.start[0]
               << "," << b.start[1] << "," << b.start[2] << ") -> (" << b.end[0] << "," << b.end[1]
               << "," << b.end[2] << ") F " << b.feed_mm_min << " mode "
               << static_cast<int>(b.path_mode) << " dwell " << b.dwell_s << "\n";
    }
    for (std::size_t i = 0; i < r.traj.size(); ++i)
      RC_LOG() << "sample " << i << " x " << r.traj.pos[i][0] << " y " << r.traj.pos[i][1] << " z "
               << r.traj.pos[i][2] << "\n";
  }
  RC_ASSERT(rep.ok());
  RC_ASSERT(!r.samples.empty());
  for (std::size_t i = 0; i < 3; ++i)
    RC_ASSERT(std::abs(r.samples.back().position[i] - p.pos[i]) <= 1e-9);
}

}  // namespace
}  // namespace cncore::motion::test
