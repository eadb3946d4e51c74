// The jerk-aware bound (jerk_bound.hpp): closed forms where they exist, never below the
// acceleration bound, and never above what the kernel's jerk-limited motion takes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bound.hpp"
#include "config/machine_config.hpp"
#include "files.hpp"
#include "jerk_bound.hpp"
#include "limits.hpp"
#include "motion/kernel.hpp"
#include "program_blocks.hpp"
#include "program_gen.hpp"

namespace cncore::bound {
namespace {

constexpr double kA = 2000;          // the built-in machine's Amax, mm/s²
constexpr double kV = 10000.0 / 60;  // its top feed, mm/s

Block line(double x0, double x1, double feed) {
  Block b;
  b.kind = BlockKind::kLine;
  b.start[kX] = x0;
  b.end[kX] = x1;
  b.feed_mm_min = feed;
  return b;
}

testing::Limits with_jerk(double jerk_mm_s3) {
  testing::Limits lim;
  lim.max_jerk_mm_s3 = jerk_mm_s3;
  return lim;
}

// From rest to rest over L at the feed V, reaching Amax and V: the time-optimal jerk-limited
// profile (7 phases, cruise included) takes V/A + A/J + L/V.
double s_curve_s(double length, double v, double a, double j) {
  return v / a + a / j + length / v;
}

TEST(JerkBound, OneLineIsTheClosedFormSCurve) {
  for (const double j : {1e6, 1e5}) {
    const double exact = s_curve_s(100, kV, kA, j);
    const BoundResult r = optimal_profile({line(0, 100, 10000)}, with_jerk(j));
    std::printf("100 mm line, J %g: bound %.6f s, S-curve %.6f s, acceleration bound %.6f s\n", j,
                r.time_s, exact, r.accel_motion_time_s);
    EXPECT_LE(r.time_s, exact + 1e-12) << "J " << j;
    EXPECT_GE(r.time_s, exact - 0.03 * kA / j) << "J " << j;
    EXPECT_NEAR(r.accel_motion_time_s, kV / kA + 100 / kV, 1e-12);
  }
}

// A line too short for the feed, from rest to rest: jerk up, Amax for t_a, jerk down, then the
// mirror image; with t_J = A/J, L/A = (t_a + t_J)·(t_a + 2·t_J) and T = 2·(t_a + 2·t_J). The
// peak's cap (peak_caps) is what brings the bound close: without it the top stays sharp.
TEST(JerkBound, ShortLineIsCloseToTheClosedFormTriangle) {
  for (const double j : {1e6, 1e5}) {
    const double tj = kA / j, l = 10;
    const double ta = (-3 * tj + std::sqrt(tj * tj + 4 * l / kA)) / 2;
    const double exact = 2 * (ta + 2 * tj);
    const BoundResult r = optimal_profile({line(0, l, 10000)}, with_jerk(j));
    std::printf("10 mm line, J %g: bound %.6f s, closed form %.6f s, acceleration bound %.6f s\n",
                j, r.time_s, exact, r.accel_motion_time_s);
    EXPECT_LE(r.time_s, exact + 1e-12) << "J " << j;
    // Within a tenth of what the jerk limit costs.
    EXPECT_GE(r.time_s, exact - 0.1 * (exact - r.accel_motion_time_s)) << "J " << j;
  }
}

TEST(JerkBound, AnExactStopIsTwoSCurves) {
  std::vector<Block> b = {line(0, 100, 10000), line(100, 150, 10000)};
  b[0].path_mode = PathMode::kExactStop;
  const double j = 1e5;
  const double exact = s_curve_s(100, kV, kA, j) + s_curve_s(50, kV, kA, j);
  const double t = optimal_time_s(b, with_jerk(j));
  EXPECT_LE(t, exact + 1e-12);
  EXPECT_GE(t, exact - 0.06 * kA / j);
}

// The envelope alone: ∫ds/E is the acceleration bound's motion time; the jerk-aware time is at
// least that and falls towards it as J grows.
TEST(JerkBound, BetweenTheAccelerationBoundAndItPlusTheRoundings) {
  // Two 5 mm strokes meeting at a corner passed at 1.41 mm/s, from rest to rest.
  const double vg = 1.41421;
  const std::vector<EnvelopePiece> e = {{5, kV, 0, vg, kA, kA}, {5, kV, vg, 0, kA, kA}};
  const double acc = envelope_time_s(e);
  double last = acc;
  for (const double j : {1e9, 1e7, 1e6, 1e5}) {
    const double t = jerk_motion_time_s(e, kA, j);
    EXPECT_GE(t, last - 1e-15) << "J " << j;
    // Three roundings (start, corner, end), each at most A/J.
    EXPECT_LE(t, acc + 3 * kA / j) << "J " << j;
    last = t;
  }
  EXPECT_GT(last, acc + kA / 1e5) << "the corner's rounding counts, not only the stops'";
}

struct Generated {
  std::string name;
  std::vector<Block> blocks;
};

std::vector<Generated> programs(const MachineConfig& m) {
  namespace gen = testing::gen;
  auto interpret = [&](const std::string& file, const std::string& text) {
    const std::filesystem::path p = std::filesystem::path(::testing::TempDir()) / file;
    testing::write_file(p, text);
    return testing::read_blocks(p.string(), m);
  };
  return {
      {"zig-zag 200 x 5 mm", interpret("jb_zz.ngc", gen::zigzag(200, 5))},
      {"circle of 360 chords", interpret("jb_circle.ngc", gen::circle_chords(360, 50))},
      {"3-D raster", interpret("jb_raster.ngc", gen::raster_3d(60, 30, 1, 0.5))},
      {"random 2000", interpret("jb_random.ngc", gen::random_path(1, 2000))},
  };
}

double kernel_time_s(const MachineConfig& m, const std::vector<Block>& blocks) {
  motion::KernelOptions o;
  o.accdec = motion::AccDecType::kAcceleration;
  motion::Kernel k(m, o);
  std::size_t next = 0;
  motion::Sample s;
  double t = 0;
  for (std::uint64_t c = 0; c < 50'000'000; ++c) {
    while (next < blocks.size() && k.wants_block()) k.push(blocks[next++]);
    if (next == blocks.size()) k.end_of_program();
    if (!k.step(s)) break;
    t = s.t_s;
  }
  return t;
}

// The bound is a lower bound: the kernel's jerk-limited runs take at least as long, and it is
// at least the acceleration bound.
TEST(JerkBound, BelowTheKernelAndAboveTheAccelerationBound) {
  for (const double j : {1e6, 1e5}) {
    MachineConfig m = machine_config_or_default("");
    m.max_jerk_mm_s3 = j;
    for (const Generated& p : programs(m)) {
      const BoundResult r = optimal_profile(p.blocks, testing::limits_from_config(m));
      const double run_s = kernel_time_s(m, p.blocks);
      std::printf(
          "%-22s J %-6g kernel %8.3f s  jerk bound %8.3f s (%.3f)  acceleration bound %8.3f s\n",
          p.name.c_str(), j, run_s, r.time_s, run_s / r.time_s, r.accel_motion_time_s + r.dwell_s);
      EXPECT_LE(r.time_s, run_s) << p.name << ", J " << j;
      EXPECT_GE(r.motion_time_s, r.accel_motion_time_s) << p.name << ", J " << j;
    }
  }
}

}  // namespace
}  // namespace cncore::bound
