// G5 splines through the simulated machine (sim::run_program, the driver of `cncore run`): every
// interpolated sample lies within the contour tolerance of the exact curve (evaluated here), the
// independent checker (tests/support) finds no violation of the speed and acceleration limits
// against the blocks the kernel ran, and the curve runs no slower than the same curve given as
// 2000 fine G1 samples with path smoothing on (or, for a circle, than its G3 arc).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <numbers>
#include <string>

#include "config/machine_config.hpp"
#include "files.hpp"
#include "limits.hpp"
#include "simulation/run.hpp"
#include "trajectory.hpp"
#include "trajectory_checker.hpp"

namespace cncore::interp::test {
namespace {

namespace fs = std::filesystem;
constexpr double kTol = 0.01;  // the built-in machine's contour tolerance

struct Recorder : sim::SampleObserver {
  std::vector<Block> blocks;
  testing::Trajectory tr;
  std::vector<Vec3> path;  // on-path points (before any post filter)
  void on_block(const Block& b) override {
    if (!b.piece) blocks.push_back(b);
  }
  void on_sample(const motion::Sample& s) override {
    tr.add_sample(s);
    path.push_back(s.path_position.xyz());
  }
};

struct Measured {
  double time_s = 0;
  Recorder rec;
  testing::CheckReport checker;
};

Measured run(const std::string& name, const std::string& text, const MachineConfig& m) {
  const fs::path p = fs::path(CNCORE_TEST_TMP_DIR) / name;
  testing::write_file(p, text);
  Measured r;
  sim::run_program(p.string(), m, {}, {&r.rec});
  r.time_s = static_cast<double>(r.rec.tr.size()) * m.period_s;
  r.checker = testing::check_trajectory(r.rec.tr, r.rec.blocks, testing::limits_from_config(m));
  return r;
}

double seg_distance(Vec3 p, Vec3 a, Vec3 b) {
  const Vec3 d = b - a;
  const double l2 = dot(d, d);
  const double t = l2 > 0 ? std::clamp(dot(p - a, d) / l2, 0.0, 1.0) : 0;
  return norm(p - (a + t * d));
}

// The largest distance of the samples on `line` to the curve (a dense polyline of it).
double curve_error(const Measured& r, std::uint32_t line,
                   const std::function<Vec3(double)>& curve) {
  constexpr int kN = 4000;
  std::vector<Vec3> exact;
  for (int k = 0; k <= kN; ++k) exact.push_back(curve(static_cast<double>(k) / kN));
  double worst = 0;
  for (std::size_t i = 0; i < r.rec.path.size(); ++i) {
    if (r.rec.tr.line[i] != line) continue;
    double best = 1e300;
    for (std::size_t k = 0; k + 1 < exact.size(); ++k) {
      best = std::min(best, seg_distance(r.rec.path[i], exact[k], exact[k + 1]));
    }
    worst = std::max(worst, best);
  }
  return worst;
}

std::string g1_samples(const std::function<Vec3(double)>& curve, int n) {
  std::string o;
  char buf[96];
  for (int k = 1; k <= n; ++k) {
    const Vec3 q = curve(static_cast<double>(k) / n);
    std::snprintf(buf, sizeof buf, "G1 X%.5f Y%.5f\n", q.x, q.y);
    o += buf;
  }
  return o;
}

Vec3 cubic(double t) {
  const Vec3 p0{0, 0, 0}, p1{30, 40, 0}, p2{50, -30, 0}, p3{60, 20, 0};
  const double s = 1 - t;
  return (s * s * s) * p0 + (3 * s * s * t) * p1 + (3 * s * t * t) * p2 + (t * t * t) * p3;
}

TEST(SplineRun, CubicStaysWithinTheToleranceOfTheCurveAndRunsAsFastAsSmoothedChords) {
  const MachineConfig m = default_machine_config();
  const Measured g5 =
      run("g5_cubic.ngc", "G21 G90 G17 G0 X0 Y0\nG5 X60 Y20 I30 J40 P-10 Q-50 F6000\nM30\n", m);
  EXPECT_TRUE(g5.checker.ok()) << g5.checker.summary();
  EXPECT_LE(curve_error(g5, 2, cubic), kTol + 1e-9);
  const Vec3 end = g5.rec.path.back();
  EXPECT_NEAR(end.x, 60, 1e-9);
  EXPECT_NEAR(end.y, 20, 1e-9);

  MachineConfig smooth = m;
  smooth.smooth_tolerance_mm = kTol;
  const Measured g1 =
      run("g5_cubic_chords.ngc",
          "G21 G90 G17 G0 X0 Y0\nF6000\n" + g1_samples(cubic, 2000) + "M30\n", smooth);
  EXPECT_TRUE(g1.checker.ok()) << g1.checker.summary();
  EXPECT_LE(g5.time_s, 1.05 * g1.time_s)
      << "G5 " << g5.time_s << " s, chords " << g1.time_s << " s";
}

TEST(SplineRun, NurbsQuarterCircleRunsAsItsArc) {
  const MachineConfig m = default_machine_config();
  const Measured nurbs = run("g52_circle.ngc",
                             "G21 G90 G17 G0 X40 Y0\nF8000\nG5.2 L3\nX40 Y40 P0.70710678118654752\n"
                             "X0 Y40\nG5.3\nM30\n",
                             m);
  const Measured arc = run("g3_circle.ngc", "G21 G90 G17 G0 X40 Y0\nG3 X0 Y40 R40 F8000\nM30\n", m);
  EXPECT_TRUE(nurbs.checker.ok()) << nurbs.checker.summary();
  auto circle = [](double t) {
    const double a = t * std::numbers::pi / 2;
    return Vec3{40 * std::cos(a), 40 * std::sin(a), 0};
  };
  EXPECT_LE(curve_error(nurbs, 6, circle), 1e-6);
  EXPECT_LE(nurbs.time_s, 1.05 * arc.time_s) << nurbs.time_s << " s against " << arc.time_s;
}

}  // namespace
}  // namespace cncore::interp::test
