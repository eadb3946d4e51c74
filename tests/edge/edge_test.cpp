// Numeric edge cases, through the public APIs only (interpreter, sim::run_program):
// zero-length moves, arcs with a radius near zero and near the travel size, 179.9° and 0.001°
// corners, coordinates of 1e6 mm, a feed of 1e-6 mm/min, and a program of millions of blocks at
// flat memory. Each test checks an outcome measured on the produced samples (end point, finite
// values, speed and acceleration limits, the error message), not just "no crash".
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"
#include "simulation/run.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define CNCORE_EDGE_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CNCORE_EDGE_ASAN 1
#endif
#endif

namespace cncore {
namespace {

std::string program_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_EDGE_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

// Streams over the samples: keeps what the checks need, and the samples themselves only when
// asked (long runs keep none). Stops the run (throws StopRun) after max_cycles samples.
struct StopRun {};
struct Probe : sim::SampleObserver {
  double period_s = 0.001;
  std::uint64_t max_cycles = UINT64_MAX;
  bool keep = true;
  std::vector<motion::Sample> samples;
  std::uint64_t n = 0;
  bool finished = false;
  bool non_finite = false;
  double max_speed_mm_min = 0;  // finite differences of the path position
  double max_dv_mm_s = 0;       // largest velocity change (vector) between two cycles
  double max_feed_mm_min = 0;   // commanded path speed
  motion::Sample last, prev;
  Vec3 prev_v{};

  void on_sample(const motion::Sample& s) override {
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (!std::isfinite(s.position[a]) || !std::isfinite(s.path_position[a])) non_finite = true;
    }
    if (!std::isfinite(s.feed_mm_min) || !std::isfinite(s.t_s)) non_finite = true;
    max_feed_mm_min = std::max(max_feed_mm_min, s.feed_mm_min);
    if (n > 0) {
      const Vec3 d = s.path_position.xyz() - last.path_position.xyz();
      const Vec3 v = (1.0 / period_s) * d;
      max_speed_mm_min = std::max(max_speed_mm_min, norm(v) * 60.0);
      if (n > 1) max_dv_mm_s = std::max(max_dv_mm_s, norm(v - prev_v));
      prev_v = v;
    }
    prev = last;
    last = s;
    if (keep) samples.push_back(s);
    if (++n >= max_cycles) throw StopRun{};
  }
  void on_finish() override { finished = true; }
};

MachineConfig big_machine(double travel_mm, double speed_mm_min, double accel_mm_s2) {
  MachineConfig m = default_machine_config();
  m.max_feed_mm_min = speed_mm_min;
  m.rapid_mm_min = speed_mm_min;
  m.max_accel_mm_s2 = accel_mm_s2;
  for (std::size_t a : {kX, kY, kZ}) {
    m.axes[a].enabled = true;
    m.axes[a].min_mm = -travel_mm;
    m.axes[a].max_mm = travel_mm;
    m.axes[a].max_speed_mm_min = speed_mm_min;
    m.axes[a].max_accel_mm_s2 = accel_mm_s2;
  }
  return m;
}

void run(const std::string& name, const std::string& text, const MachineConfig& m, Probe& p) {
  p.period_s = m.period_s;
  sim::run_program(program_file(name, text), m, {}, {&p});
}

// ---------------------------------------------------------------------------------------------
// Zero-length moves

TEST(EdgeZeroLength, ZeroLengthMovesBetweenRealMovesAreHarmless) {
  Probe p;
  run("zero.ngc",
      "G21 G90\nG1 X10 F3000\nG1 X10\nG1 X10 Y0 Z0\nG0 X10\nG91 G1 X0\nG90 G1 Y10\nM30\n",
      default_machine_config(), p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  EXPECT_NEAR(p.last.position[kX], 10, 1e-9);
  EXPECT_NEAR(p.last.position[kY], 10, 1e-9);
  EXPECT_NEAR(p.last.position[kZ], 0, 1e-9);
  EXPECT_LE(p.max_speed_mm_min, 3000 * (1 + 1e-9));
  // 20 mm at 3000 mm/min (50 mm/s) is 0.4 s plus acc/dec: the run must not stall on the
  // zero-length blocks (a stop costs the filter time, 50/2000 s, at most a few times).
  EXPECT_LT(p.last.t_s, 1.0);
}

TEST(EdgeZeroLength, AProgramOfOnlyZeroLengthMovesEndsWhereItStarted) {
  Probe p;
  run("only_zero.ngc", "G1 X0 F100\nG0 X0 Y0\nG1 Z0\nM30\n", default_machine_config(), p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  for (const auto& s : p.samples) {
    ASSERT_EQ(s.position, AxisVec{}) << "t = " << s.t_s;
  }
  EXPECT_LT(p.n, 1000u) << "nothing to move: the run must end at once";
}

TEST(EdgeZeroLength, AnArcOfZeroRadiusIsAnInputError) {
  const std::string path = program_file("zero_arc.ngc", "G1 X10 F100\nG2 X10 Y0 I0 J0\nM30\n");
  Probe p;
  try {
    sim::run_program(path, default_machine_config(), {}, {&p});
    FAIL() << "a zero-radius arc ran";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2u) << e.formatted();
  }
  EXPECT_FALSE(p.non_finite);
  EXPECT_NEAR(p.last.position[kX], 10, 1e-9) << "stops at the end of the last good block";
}

// ---------------------------------------------------------------------------------------------
// Arcs: radius near zero (1e-4 mm) and near the travel size

TEST(EdgeArc, FullCircleOfRadiusOneTenthMicronFollowedByALine) {
  const double r = 1e-4;
  Probe p;
  run("tiny_circle.ngc", "G21 G90\nG1 X10 F1000\nG2 X10 Y0 I0.0001 J0\nG1 X20\nM30\n",
      default_machine_config(), p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  EXPECT_NEAR(p.last.position[kX], 20, 1e-9);
  EXPECT_NEAR(p.last.position[kY], 0, 1e-9);
  // Normal acceleration v²/R ≤ Amax on the arc: v ≤ √(R·Amax) = √(1e-4 · 2000) mm/s
  // = 0.447 mm/s = 26.8 mm/min (spec 01, shape passing speed Vb).
  const double vb_mm_min = std::sqrt(r * 2000) * 60;
  for (const auto& s : p.samples) {
    if (s.line == 3) {
      ASSERT_LE(s.feed_mm_min, vb_mm_min * 1.001) << "t = " << s.t_s;
      const double d = std::hypot(s.path_position[kX] - 10.0001, s.path_position[kY]);
      ASSERT_LE(d, r + 1e-6) << "off the circle at t = " << s.t_s;
    } else {
      ASSERT_NEAR(s.path_position[kY], 0, 1e-9) << "off the line at t = " << s.t_s;
    }
  }
}

TEST(EdgeArc, SemicircleOfRadiusOneTenthMicron) {
  Probe p;
  run("tiny_semicircle.ngc", "G21 G90\nG1 X10 F1000\nG3 X10.0002 Y0 R0.0001\nG1 X20\nM30\n",
      default_machine_config(), p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  EXPECT_NEAR(p.last.position[kX], 20, 1e-9);
  EXPECT_NEAR(p.last.position[kY], 0, 1e-9);
  EXPECT_LE(p.max_speed_mm_min, 1000 * (1 + 1e-9));
}

TEST(EdgeArc, SemicircleNearlyAsLargeAsTheTravel) {
  // Travel ±1000 mm; G2 from (−999, 0) to (999, 0) about the origin passes (0, 999).
  const MachineConfig m = big_machine(1000, 10000, 2000);
  Probe p;
  run("big_arc.ngc", "G21 G90\nG0 X-999 Y0\nG2 X999 Y0 R999 F6000\nM30\n", m, p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  EXPECT_NEAR(p.last.position[kX], 999, 1e-9);
  EXPECT_NEAR(p.last.position[kY], 0, 1e-9);
  double max_y = -1e9, max_arc_feed = 0;
  for (const auto& s : p.samples) {
    if (s.line != 3) continue;
    // P1: on the programmed circle within 1 µm (no post-interpolation filter configured).
    ASSERT_NEAR(std::hypot(s.path_position[kX], s.path_position[kY]), 999, 1e-6) << "t = " << s.t_s;
    max_y = std::max(max_y, s.path_position[kY]);
    max_arc_feed = std::max(max_arc_feed, s.feed_mm_min);
  }
  EXPECT_GT(max_y, 999 - 1e-3) << "the arc passes the top of the circle";
  EXPECT_LE(max_y, 1000);
  EXPECT_NEAR(max_arc_feed, 6000, 1e-6) << "a large arc runs at the programmed feed";
  EXPECT_LE(p.max_speed_mm_min, 10000 * (1 + 1e-9));
}

TEST(EdgeArc, AnArcBulgingPastTheTravelIsAnInputErrorNamingTheLimit) {
  const MachineConfig m = big_machine(1000, 10000, 2000);
  const std::string path =
      program_file("too_big_arc.ngc", "G21 G90\nG0 X-999 Y0\nG2 X999 Y0 I999 J45 F6000\nM30\n");
  try {
    sim::run_program(path, m, {}, {});
    FAIL() << "an arc of radius 1000.013 about (0, 45) ran on a ±1000 mm travel";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 3u) << e.formatted();
    EXPECT_NE(std::string(e.what()).find("travel"), std::string::npos) << e.formatted();
  }
}

// ---------------------------------------------------------------------------------------------
// Corners: the direction turns by 179.9° (nearly back) and by 0.001° (nearly straight)

// A line along +X to (50, 0), then a line of 50 mm turning by `turn_deg`.
std::string corner_program(double turn_deg, double feed_mm_min) {
  const double a = turn_deg * std::numbers::pi / 180;
  char buf[256];
  std::snprintf(buf, sizeof buf, "G21 G90\nG1 X50 F%.6f\nG1 X%.12f Y%.12f\nM30\n", feed_mm_min,
                50 + 50 * std::cos(a), 50 * std::sin(a));
  return buf;
}

// The path speed in the cycle that passes the joint (50, 0) between line 2 and line 3: the
// distance along the path, |p[i-1] − c| + |c − p[i]|, over one period.
double speed_at_joint_mm_min(const Probe& p) {
  const Vec3 c{50, 0, 0};
  for (std::size_t i = 1; i < p.samples.size(); ++i) {
    if (p.samples[i - 1].line == 2 && p.samples[i].line == 3) {
      const double d = norm(c - p.samples[i - 1].path_position.xyz()) +
                       norm(p.samples[i].path_position.xyz() - c);
      return d / p.period_s * 60;
    }
  }
  ADD_FAILURE() << "no joint between line 2 and line 3";
  return NAN;
}

TEST(EdgeCorner, NearReversalOf179_9DegreesSlowsToTheCornerLimit) {
  Probe p;
  run("corner_179_9.ngc", corner_program(179.9, 6000), default_machine_config(), p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  const double a = 179.9 * std::numbers::pi / 180;
  EXPECT_NEAR(p.last.position[kX], 50 + 50 * std::cos(a), 1e-9);
  EXPECT_NEAR(p.last.position[kY], 50 * std::sin(a), 1e-9);
  // Spec 01: V = Amax·τ / (2·sin(θ/2)) = 2000·0.001 / (2·sin 89.95°) mm/s = 1.0000004 mm/s
  // = 60.00002 mm/min.
  const double v_corner_mm_min = 2000 * 0.001 / (2 * std::sin(a / 2)) * 60;
  EXPECT_LE(speed_at_joint_mm_min(p), v_corner_mm_min * 1.01);
  EXPECT_LE(p.max_speed_mm_min, 6000 * (1 + 1e-9));
  // P3: the velocity vector never changes by more than √2·Amax·τ in a cycle (tangential and
  // normal parts each ≤ Amax·τ; 2 mm/s each here).
  EXPECT_LE(p.max_dv_mm_s, std::sqrt(2.0) * 2000 * 0.001 * 1.01);
}

TEST(EdgeCorner, TurnOf0_001DegreesKeepsTheProgrammedFeed) {
  Probe p;
  // The kernel's corner (merged, the two lines are one: the vertex is 0.44 µm off the chord).
  MachineConfig m = default_machine_config();
  m.merge_tolerance_mm = 0;
  run("corner_0_001.ngc", corner_program(0.001, 6000), m, p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  const double a = 0.001 * std::numbers::pi / 180;
  EXPECT_NEAR(p.last.position[kX], 50 + 50 * std::cos(a), 1e-9);
  EXPECT_NEAR(p.last.position[kY], 50 * std::sin(a), 1e-9);
  // V = 2000·0.001 / (2·sin 0.0005°) = 114 592 mm/s: no limit below the feed (100 mm/s), so
  // the tool passes the joint at the programmed 6000 mm/min.
  EXPECT_NEAR(speed_at_joint_mm_min(p), 6000, 6000 * 1e-6);
  EXPECT_LE(p.max_speed_mm_min, 6000 * (1 + 1e-9));
  EXPECT_LE(p.max_dv_mm_s, std::sqrt(2.0) * 2000 * 0.001 * 1.01);
}

// ---------------------------------------------------------------------------------------------
// Coordinates of 1e6 mm

TEST(EdgeHugeCoordinates, MovesAtAMillionMillimetres) {
  // A machine with ±2e6 mm of travel and 100 m/s (6e6 mm/min), 1e5 mm/s²: ~45 s of motion.
  const MachineConfig m = big_machine(2e6, 6e6, 1e5);
  Probe p;
  p.keep = false;
  run("huge.ngc",
      "G21 G90\nG0 X1000000 Y-1000000\nG1 X1000000.5 F600\nG1 X-1000000 Y1000000 F6000000\n"
      "M30\n",
      m, p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  EXPECT_EQ(p.last.position[kX], -1e6);
  EXPECT_EQ(p.last.position[kY], 1e6);
  EXPECT_LE(p.max_speed_mm_min, 6e6 * (1 + 1e-6));
  // Each axis: Amax 1e5 mm/s², so |Δv| ≤ √2·1e5·τ per cycle on the path (tangential only here,
  // the joints are stops or straight-through).
  EXPECT_LE(p.max_dv_mm_s, std::sqrt(2.0) * 1e5 * 0.001 * 1.01);
  // The path rate (6e6 mm/min = 1e5 mm/s) is the limit on both diagonals: 1.41e6 mm + 2.83e6 mm
  // at 1e5 mm/s is 42.4 s of motion at least.
  EXPECT_GT(p.last.t_s, 42);
}

TEST(EdgeHugeCoordinates, ShortFeedMoveAtAMillionMillimetresStaysOnThePath) {
  MachineConfig m = big_machine(2e6, 10000, 2000);
  m.start_position[kX] = 1e6;
  m.start_position[kY] = -1e6;
  Probe p;
  run("huge_short.ngc", "G21 G90\nG1 X1000000.5 F600\nG1 Y-999999.5\nM30\n", m, p);
  ASSERT_TRUE(p.finished);
  EXPECT_FALSE(p.non_finite);
  EXPECT_EQ(p.last.position[kX], 1000000.5);
  EXPECT_EQ(p.last.position[kY], -999999.5);
  // 0.5 mm at 600 mm/min (10 mm/s): 0.05 s plus acc/dec; positions move forward every cycle
  // (at 1e6 mm the double spacing is 1.2e-10 mm, far below the 0.01 mm per cycle).
  for (std::size_t i = 1; i < p.samples.size(); ++i) {
    const auto& a = p.samples[i - 1];
    const auto& b = p.samples[i];
    ASSERT_GE(b.position[kX], a.position[kX]);
    ASSERT_GE(b.position[kY], a.position[kY]);
    if (b.line == 3) {
      ASSERT_EQ(b.path_position[kX], 1000000.5);
    }
    if (b.line == 2) {
      ASSERT_EQ(b.path_position[kY], -1e6);
    }
  }
  EXPECT_LE(p.max_speed_mm_min, 600 * (1 + 1e-6));
  EXPECT_LT(p.last.t_s, 1.0);
}

// ---------------------------------------------------------------------------------------------
// A feed of 1e-6 mm/min: 1 mm takes 1.9 years. A controller runs what was programmed (there is
// no lower feed limit in RS274/NGC), so the run must be correct for as long as it is watched:
// the first 200 000 cycles (200 s) are checked, then the observer stops the run.

TEST(EdgeTinyFeed, OneMicroMillimetrePerMinuteMovesAtThatSpeed) {
  Probe p;
  p.max_cycles = 200000;
  p.keep = false;
  double min_dx = 1;
  struct Monotone : sim::SampleObserver {
    double last_x = 0, min_dx = 1;
    void on_sample(const motion::Sample& s) override {
      min_dx = std::min(min_dx, s.position[kX] - last_x);
      last_x = s.position[kX];
    }
  } mono;
  const std::string path = program_file("tiny_feed.ngc", "G21 G90\nG1 X1 F0.000001\nM30\n");
  EXPECT_THROW(sim::run_program(path, default_machine_config(), {}, {&p, &mono}), StopRun);
  min_dx = mono.min_dx;
  EXPECT_FALSE(p.non_finite);
  EXPECT_GE(min_dx, 0) << "never moves backwards";
  EXPECT_LE(p.max_feed_mm_min, 1e-6 * (1 + 1e-9));
  EXPECT_NEAR(p.last.feed_mm_min, 1e-6, 1e-12);
  // After the ramp (≤ 1 s) it moves 1e-6/60 mm/s: at t ≈ 200 s, x ≈ 3.33e-6 mm (±1 s of ramp).
  const double rate_mm_s = 1e-6 / 60;
  EXPECT_NEAR(p.last.position[kX], rate_mm_s * p.last.t_s, rate_mm_s * 1.0);
  EXPECT_GT(p.last.position[kX], 0);
}

TEST(EdgeTinyFeed, AtAMillionMillimetresTheStepsBelowTheDoubleSpacingStillAddUp) {
  // At X = 1e6 mm the spacing of doubles is 1.16e-10 mm, seven times the 1.67e-11 mm that
  // 1e-6 mm/min moves per cycle: the position must still advance at the programmed rate (the
  // kernel must not lose the sub-spacing steps, and the run driver's stall watchdog, 60 s
  // without motion, must not fire).
  MachineConfig m = big_machine(2e6, 10000, 2000);
  m.start_position[kX] = 1e6;
  Probe p;
  p.period_s = m.period_s;
  p.max_cycles = 300000;
  p.keep = false;
  const std::string path =
      program_file("tiny_feed_far.ngc", "G21 G90\nG1 X1000001 F0.000001\nM30\n");
  EXPECT_THROW(sim::run_program(path, m, {}, {&p}), StopRun);
  EXPECT_FALSE(p.non_finite);
  // 300 s at 1e-6/60 mm/s = 5.0e-6 mm, minus half the 0.08 s ramp: within one spacing + 1 s.
  const double rate_mm_s = 1e-6 / 60;
  EXPECT_NEAR(p.last.position[kX] - 1e6, rate_mm_s * p.last.t_s, rate_mm_s * 1.0 + 2.4e-10);
}

// ---------------------------------------------------------------------------------------------
// Millions of blocks through the interpreter at flat memory

long rss_kb() {
  // Current resident set (not the peak): /proc/self/statm field 2, in pages.
  long pages = 0, resident = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

long peak_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

TEST(EdgeLongProgram, MillionsOfBlocksAtFlatMemory) {
#ifdef CNCORE_EDGE_ASAN
  std::uint64_t n_blocks = 300000;  // the ASan build is ~10x slower
#else
  std::uint64_t n_blocks = 2000000;
#endif
  // By hand: CNCORE_EDGE_BLOCKS=10000000 edge_tests --gtest_filter='EdgeLongProgram*'
  if (const char* e = std::getenv("CNCORE_EDGE_BLOCKS")) n_blocks = std::stoull(e);
  const auto path = std::filesystem::path(CNCORE_EDGE_TMP_DIR) / "long.ngc";
  {
    // A zigzag: block i goes to X = i mod 100 (mm), Y = i / 1000 (a slow climb).
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("G21 G90 F5000\n", f);
    for (std::uint64_t i = 1; i <= n_blocks; ++i) {
      std::fprintf(f, "G1 X%llu Y%.3f\n", static_cast<unsigned long long>(i % 100),
                   static_cast<double>(i % 200000) / 1000.0);
    }
    std::fputs("M30\n", f);
    std::fclose(f);
  }
  const long rss_before = rss_kb();
  const long peak_before = peak_rss_kb();
  std::uint64_t motion = 0;
  Block b;
  Block last_motion;
  long rss_mid = 0;
  const auto t0 = std::chrono::steady_clock::now();
  {
    interp::Interpreter in(path.string(), default_machine_config(), interp::Options{});
    while (in.next(b)) {
      if (b.kind == BlockKind::kLine) {
        ++motion;
        last_motion = b;
        if (motion == n_blocks / 10) rss_mid = rss_kb();
      }
    }
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const long rss_after = rss_kb();
  const long peak_after = peak_rss_kb();
  std::filesystem::remove(path);
  std::printf(
      "%llu blocks in %.2f s (%.2f M blocks/s); RSS %ld kB before, %ld kB at 10%%, %ld kB "
      "after; peak %ld kB -> %ld kB\n",
      static_cast<unsigned long long>(motion), secs, static_cast<double>(motion) / secs / 1e6,
      rss_before, rss_mid, rss_after, peak_before, peak_after);
  EXPECT_EQ(motion, n_blocks);
  EXPECT_EQ(last_motion.end[kX], static_cast<double>(n_blocks % 100));
  EXPECT_NEAR(last_motion.end[kY], static_cast<double>(n_blocks % 200000) / 1000.0, 1e-9);
  EXPECT_EQ(last_motion.line, n_blocks + 1);
#ifdef CNCORE_EDGE_ASAN
  GTEST_SKIP() << "memory figures are meaningless under ASan (quarantine); blocks checked";
#else
  // Flat memory: from 10 % to 100 % of the program the resident set may not grow by more than
  // 4 MB (the program itself is ~40 MB), and the peak not by more than 16 MB over the start.
  EXPECT_LT(rss_after - rss_mid, 4096) << "memory grows with program length";
  EXPECT_LT(peak_after - peak_before, 16384);
#endif
}

}  // namespace
}  // namespace cncore
