// The acceleration type with a jerk limit and with the post-interpolation filter on the programs
// of bench/run.sh (the seed's example, a zig-zag of 200 strokes of 5 mm, a circle of 360 chords,
// a 3-D raster) on the built-in machine (every axis at Amax, so a diagonal's turn and speed
// change meet on one axis). Everything is measured from the output positions by the independent
// checker (tests/support/trajectory_checker.hpp), by finite differences:
// - path jerk: s[k] the path position of sample k (its projection on the programmed path),
//   j[k] = (s[k+2] − 3·s[k+1] + 3·s[k] − s[k−1])/τ³ ≤ Jmax·1.005 + 16q/τ³ (q = 1e-9 mm), over
//   every window of four samples that stays on one straight or curved piece (a window that turns
//   a corner measures the turn, which the normal and per-axis accelerations bound);
// - per-axis acceleration |Δ²P_i|/τ² ≤ A_i·1.005 at every sample, corners included;
// - path speed ≤ feed (and every cap), tangential and normal acceleration ≤ Amax;
// - distance to the programmed path ≤ 1 µm, or ≤ the contour tolerance with the post filter;
// - the last sample on the programmed end (1e-9 mm) at rest.
// The jerk limit is the path's: the resultant third difference |Δ³P|/τ³ at a corner passed
// within one cycle is of the order of Amax/τ whatever Jmax is (printed, not checked).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "files.hpp"
#include "limits.hpp"
#include "motion_test_util.hpp"
#include "program_blocks.hpp"
#include "program_gen.hpp"
#include "trajectory_checker.hpp"

namespace cncore::motion::test {
namespace {

struct Program {
  std::string name;
  std::vector<Block> blocks;
};

std::vector<Block> interpret(const std::string& name, const std::string& text,
                             const MachineConfig& m) {
  const std::filesystem::path p = std::filesystem::path(::testing::TempDir()) / name;
  testing::write_file(p, text);
  return testing::read_blocks(p.string(), m);
}

std::vector<Program> programs(const MachineConfig& m) {
  namespace gen = testing::gen;
  return {
      {"seed example", seed_example(8000).blocks},
      {"zig-zag 200 x 5 mm", interpret("jerk_zz.ngc", gen::zigzag(200, 5), m)},
      {"circle of 360 chords", interpret("jerk_circle.ngc", gen::circle_chords(360, 50), m)},
      {"3-D raster", interpret("jerk_raster.ngc", gen::raster_3d(60, 30, 1, 0.5), m)},
  };
}

struct Filters {
  double jerk_mm_s3 = 0;
  double post_s = 0;
};

// The built-in machine (limits as `cncore machine` prints them) with the filters set.
MachineConfig machine(const Filters& f) {
  MachineConfig m = machine_config_or_default("");
  m.max_jerk_mm_s3 = f.jerk_mm_s3;
  m.post_filter_s = f.post_s;
  m.contour_tolerance_mm = 0.01;
  return m;
}

void expect_limits_held(const Filters& f) {
  const MachineConfig m = machine(f);
  const testing::Limits lim = testing::limits_from_config(m);
  RunOpts o;
  o.kernel.accdec = AccDecType::kAcceleration;
  for (const Program& p : programs(m)) {
    const RunResult r = run(m, p.blocks, o);
    const testing::CheckReport rep = testing::check_trajectory(r.traj, p.blocks, lim);
    const std::string where = p.name + ", J " + std::to_string(f.jerk_mm_s3) + " mm/s³, post " +
                              std::to_string(f.post_s) + " s";
    EXPECT_TRUE(rep.ok()) << where << ": " << rep.summary();
    if (f.jerk_mm_s3 > 0) {
      EXPECT_LE(rep.max_tangential_jerk_mm_s3, f.jerk_mm_s3 * 1.005) << where;
      // Not vacuous: the ramps use the jerk the limit allows.
      EXPECT_GT(rep.max_tangential_jerk_mm_s3, 0.3 * f.jerk_mm_s3) << where;
    }
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_LE(rep.max_axis_accel_mm_s2[i], m.axes[i].max_accel_mm_s2 * 1.005) << where;
    }
    EXPECT_LE(rep.max_tangential_accel_mm_s2, m.max_accel_mm_s2 * 1.005) << where;
    EXPECT_LE(rep.max_speed_ratio, 1.005) << where;
    EXPECT_LE(rep.max_path_error_mm, f.post_s > 0 ? m.contour_tolerance_mm : 1e-3) << where;
    ASSERT_FALSE(r.samples.empty());
    const AxisVec end = program_end(p.blocks.front().start, p.blocks);
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      EXPECT_NEAR(r.samples.back().position[i], end[i], 1e-9) << where << ", axis " << i;
    }
    EXPECT_EQ(r.samples.back().feed_mm_min, 0.0) << where;
    std::printf(
        "%-22s J %-8g post %-5g %8.3f s  jerk %9.0f mm/s³  axis accel %6.1f %6.1f %6.1f  "
        "tangential %6.1f mm/s²  speed/limit %.4f  path error %.4f mm  (resultant jerk %.3g "
        "mm/s³)\n",
        p.name.c_str(), f.jerk_mm_s3, f.post_s, r.time_s(), rep.max_tangential_jerk_mm_s3,
        rep.max_axis_accel_mm_s2[0], rep.max_axis_accel_mm_s2[1], rep.max_axis_accel_mm_s2[2],
        rep.max_tangential_accel_mm_s2, rep.max_speed_ratio, rep.max_path_error_mm,
        rep.max_resultant_jerk_mm_s3);
  }
}

TEST(AccelJerk, JerkStageT2Is4) {
  expect_limits_held({1e6, 0});
}
TEST(AccelJerk, JerkStageT2Is40) {
  expect_limits_held({1e5, 0});
}
TEST(AccelJerk, PostFilter16ms) {
  expect_limits_held({0, 0.016});
}
TEST(AccelJerk, JerkStageT2Is40AndPostFilter16ms) {
  expect_limits_held({1e5, 0.016});
}

}  // namespace
}  // namespace cncore::motion::test
