// An I J K arc whose end radius differs from its start radius within the tolerance runs as one
// spiral about the programmed centre, as in LinuxCNC: measured on the simulated machine's
// interpolated path, every sample's distance to the programmed centre is the radius blended
// linearly with the swept angle, r(t) = r0 + (r1 − r0)·t. And a G18 arc in a coordinate system
// rotated with G10 L2 R stays on its circle in the vertical plane turned with the system.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "config/machine_config.hpp"
#include "simulation/run.hpp"

namespace cncore::interp::test {
namespace {

struct Keep : sim::SampleObserver {
  std::vector<motion::Sample> samples;
  std::vector<Block> blocks;
  void on_block(const Block& b) override { blocks.push_back(b); }
  void on_sample(const motion::Sample& s) override { samples.push_back(s); }
};

TEST(SpiralArc, RadiusBlendsAlongTheSweepAboutTheProgrammedCentre) {
  // Centre (0.02, 0): r0 = 50.02 at the start, r1 = 49.98 at the end (0.04 mm apart, 0.08 %:
  // inside LinuxCNC's tolerance); a clockwise half turn over the top.
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / "spiral_arc.ngc";
  std::ofstream(path) << "G21 G90 G17\nG0 X-50 Y0\nG2 X50 Y0 I50.02 J0 F3000\nM30\n";
  Keep keep;
  sim::run_program(path.string(), default_machine_config(), {}, {&keep});

  std::size_t arcs = 0;
  for (const Block& b : keep.blocks) arcs += b.kind == BlockKind::kArc ? 1 : 0;
  EXPECT_EQ(arcs, 1u);  // one block, not pieces

  const double cx = 0.02, r0 = 50.02, r1 = 49.98;
  const double theta0 = std::numbers::pi;  // the start (−50, 0) seen from the centre
  std::size_t on_arc = 0;
  double worst = 0, mid_r = 0;
  for (const motion::Sample& s : keep.samples) {
    if (s.line != 3) continue;
    const double x = s.path_position[kX] - cx, y = s.path_position[kY];
    // Clockwise from θ0 = π over the top: the swept angle is θ0 − θ, θ in [0, π].
    const double theta = std::atan2(y, x);
    const double t = std::clamp((theta0 - theta) / std::numbers::pi, 0.0, 1.0);
    const double want = r0 + (r1 - r0) * t;
    worst = std::max(worst, std::fabs(std::hypot(x, y) - want));
    if (std::fabs(t - 0.5) < 0.01) mid_r = std::hypot(x, y);
    ++on_arc;
  }
  ASSERT_GT(on_arc, 100u);
  EXPECT_LT(worst, 1e-6) << "largest distance from the blended radius (mm)";
  // Half way the radius is the mean: neither circle through the start nor through the end.
  EXPECT_NEAR(mid_r, 0.5 * (r0 + r1), 5e-4);
  const motion::Sample& last = keep.samples.back();
  EXPECT_NEAR(last.path_position[kX], 50.0, 1e-9);
  EXPECT_NEAR(last.path_position[kY], 0.0, 1e-9);
}

// G10 L2 R30: program X runs along (cos 30°, sin 30°). A G18 G2 of radius 20 from program
// (30, 0, 0) about (30, 0, 20) to (50, 0, 20) is a quarter turn in the vertical plane through
// that direction, about the machine axis (−sin 30°, cos 30°, 0).
TEST(RotatedPlaneArc, G18ArcStaysOnItsCircleInTheTurnedPlane) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / "rotated_g18_arc.ngc";
  std::ofstream(path) << "G21 G90 G10 L2 P1 X5 Y-10 Z-60 R30\nG54 G0 X30 Y0 Z0\n"
                         "G18 G2 X50 Z20 K20 F3000\nM30\n";
  Keep keep;
  sim::run_program(path.string(), default_machine_config(), {}, {&keep});
  const double c30 = std::cos(std::numbers::pi / 6), s30 = std::sin(std::numbers::pi / 6);
  auto machine = [&](double x, double z) { return Vec3{5 + x * c30, -10 + x * s30, -60 + z}; };
  const Vec3 centre = machine(30, 20);
  const Vec3 normal{-s30, c30, 0};
  std::size_t on_arc = 0;
  double worst_r = 0, worst_plane = 0;
  for (const motion::Sample& s : keep.samples) {
    if (s.line != 3) continue;
    const Vec3 d = s.path_position.xyz() - centre;
    worst_r = std::max(worst_r, std::fabs(norm(d) - 20));
    worst_plane = std::max(worst_plane, std::fabs(dot(d, normal)));
    ++on_arc;
  }
  ASSERT_GT(on_arc, 100u);
  EXPECT_LT(worst_r, 1e-6);
  EXPECT_LT(worst_plane, 1e-9);
  const Vec3 end = keep.samples.back().path_position.xyz();
  const Vec3 want = machine(50, 20);
  EXPECT_NEAR(end.x, want.x, 1e-9);
  EXPECT_NEAR(end.y, want.y, 1e-9);
  EXPECT_NEAR(end.z, want.z, 1e-9);
}

}  // namespace
}  // namespace cncore::interp::test
