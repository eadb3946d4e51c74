// cncore-gen refine: a program written back from its blocks, cut into k pieces per block, runs
// the same path. Interpreted back, every refined block lies on the original path and the
// lengths, stops and time-optimal structure match. Uses the interpreter's public API.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "config/machine_config.hpp"
#include "program_blocks.hpp"
#include "program_gen.hpp"
#include "trajectory_checker.hpp"

namespace cncore::testing {
namespace {

// ctest runs each test in its own process, in parallel: the file names carry the test's name.
std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                           name;
  std::ofstream(path) << text;
  return path;
}

void expect_same_path(const std::string& program_text, int k) {
  const MachineConfig m = default_machine_config();
  const auto orig = read_blocks(write_temp("refine_orig.ngc", program_text), m);
  std::ostringstream fine_text;
  gen::GcodeWriter w(fine_text, k);
  for (const auto& b : orig) w.add(b);
  w.finish();
  const auto fine = read_blocks(write_temp("refine_fine.ngc", fine_text.str()), m);
  const Path a = build_path(orig), b = build_path(fine);
  EXPECT_NEAR(a.length_mm, b.length_mm, 1e-6 * (1 + a.length_mm)) << fine_text.str();
  ASSERT_GE(b.segments.size(), a.segments.size());
  std::size_t stops_a = 0, stops_b = 0;
  for (const auto& s : a.segments) stops_a += s.stop_after;
  for (const auto& s : b.segments) stops_b += s.stop_after;
  EXPECT_EQ(stops_a, stops_b);
  // Every refined point (ends and midpoints) lies on the original path: a "trajectory" through
  // them has no P1 violation at 1e-6 mm.
  Trajectory tr;
  double t = 0;
  tr.add(t, 0, b.start);
  for (const auto& s : b.segments) {
    for (int q = 1; q <= 4; ++q) tr.add(t += 0.001, s.line, s.point_at(q / 4.0));
  }
  Limits lim;
  lim.path_tolerance_mm = 1e-6;
  const auto rep = check_trajectory(tr, a, lim);
  EXPECT_EQ(rep.count(Property::kPath), 0u) << rep.summary();
  EXPECT_LT(rep.end_error_mm, 1e-9);
}

TEST(RefineRoundTrip, LinesArcsInEveryPlaneHelicesStopsAndDwells) {
  const std::string prog =
      "G21 G90 G17 F3000\n"
      "G0 X10 Y0 Z0\n"
      "G1 X20 Y5 Z-1\n"
      "G3 X30 Y15 I0 J10\n"     // quarter circle, G17 CCW
      "G2 X40 Y5 Z-3 I10 J0\n"  // helical, CW
      "G9 G1 X45 Y5\n"          // exact stop
      "G4 P0.2\n"
      "G18 G2 X55 Z-3 I5 K0\n"      // half circle in ZX
      "G19 G3 Y15 Z-3 J5 K0\n"      // half circle in YZ
      "G17 G2 X55 Y15 I-5 J0 P2\n"  // two full turns (multi-turn stays whole)
      "G0 Z10\n"
      "M30\n";
  expect_same_path(prog, 1);
  expect_same_path(prog, 7);
}

TEST(RefineRoundTrip, GeneratedRandomPath) {
  expect_same_path(gen::random_path(3, 200), 10);
}

}  // namespace
}  // namespace cncore::testing
