// The height map's sweep against closed-form geometry: a slot removes w·d·L, a stadium-shaped
// slot removes (w·L + πR²)·d, a ball plunge leaves a spherical dimple, a second pass removes
// nothing, and every tool's swept envelope matches a brute-force minimum over densely sampled
// tool positions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "simulation/cutting/heightmap.hpp"

namespace cncore::cut {
namespace {

constexpr double kPi = std::numbers::pi;

ToolProfile flat(double d) {
  return {d / 2, 0, ToolShape::kFlat};
}
ToolProfile ball(double d) {
  return {d / 2, d / 2, ToolShape::kBall};
}
ToolProfile bull(double d, double rc) {
  return {d / 2, rc, ToolShape::kBullNose};
}

// Moves the tool a → b in steps of at most step_mm (as interpolation cycles would).
double sweep_path(HeightMap& m, const ToolProfile& t, Vec3 a, Vec3 b, double step_mm) {
  const Vec3 d = b - a;
  const double len = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  const int n = std::max(1, static_cast<int>(std::ceil(len / step_mm)));
  double removed = 0;
  Vec3 p = a;
  for (int k = 1; k <= n; ++k) {
    const Vec3 q = a + (static_cast<double>(k) / n) * d;
    removed += m.sweep(t, p, q);
    p = q;
  }
  return removed;
}

TEST(HeightMapSweep, StraightSlotRemovesWidthTimesDepthTimesLength) {
  // Stock 50 × 20 × 10, slot across the whole X length: w = 6, d = 2, L = 50.
  // Discretisation bound: each column of cells (one X cell) counts the cell centres within
  // |y − y0| ≤ R, i.e. between 2R/h − 1 and 2R/h + 1 cells, so |V − w·d·L| ≤ h·d·L.
  const double h = 0.1, w = 6, d = 2, L = 50;
  for (const double y0 : {10.0, 10.03, 10.05, 9.987}) {
    HeightMap m(0, 0, h, 500, 200, -10, 0);
    const double v = sweep_path(m, flat(w), {-10, y0, -d}, {60, y0, -d}, 0.033);
    // (10.05: both edges fall on cell centres, the bound is reached.)
    EXPECT_NEAR(v, w * d * L, h * d * L * (1 + 1e-9)) << "y0 = " << y0;
    EXPECT_NEAR(m.volume_mm3(), 50 * 20 * 10 - v, 1e-6 * v);
    // Floor at −d under the tool, untouched outside.
    EXPECT_FLOAT_EQ(m.at(250, static_cast<std::size_t>(y0 / h)), -2.0f);
    EXPECT_FLOAT_EQ(m.at(250, static_cast<std::size_t>((y0 + w / 2 + 0.2) / h)), 0.0f);
    EXPECT_FLOAT_EQ(m.at(250, static_cast<std::size_t>((y0 - w / 2 - 0.2) / h)), 0.0f);
  }
}

TEST(HeightMapSweep, ObliqueSlotInsideTheStockRemovesAStadium) {
  // A slot that starts and ends inside the stock removes a stadium: (w·L + π·R²)·d. Counting
  // cell centres misses at most the band of half-width h/√2 (half a cell's diagonal) around the
  // outline of perimeter P = 2L + 2πR: |V − V0| ≤ d·(√2·h·P + π·h²/2).
  const double h = 0.1, w = 8, r = w / 2, d = 1.5;
  for (const double angle_deg : {0.0, 17.0, 45.0, 90.0, 123.0, 200.0}) {
    HeightMap m(-40, -40, h, 800, 800, -20, 0);
    const double a = angle_deg * kPi / 180, len = 30;
    const Vec3 p0{-10 * std::cos(a) + 0.013, -10 * std::sin(a) - 0.021, -d};
    const Vec3 p1 = p0 + Vec3{len * std::cos(a), len * std::sin(a), 0};
    const double v = sweep_path(m, flat(w), p0, p1, 0.05);
    const double v0 = (w * len + kPi * r * r) * d;
    const double bound = d * (std::sqrt(2.0) * h * (2 * len + 2 * kPi * r) + kPi * h * h / 2);
    EXPECT_NEAR(v, v0, bound) << angle_deg << " deg";
    // The observed error is far inside the bound (errors on opposite sides cancel).
    EXPECT_LT(std::fabs(v - v0), 0.25 * bound) << angle_deg << " deg";
  }
}

TEST(HeightMapSweep, BallPlungeLeavesASphericalDimple) {
  // Ball R = 5 plunged vertically to 3 mm below the top at an off-grid point: every cell centre
  // within the dimple sits on the sphere z = −3 + R − √(R² − r²), the rest is untouched.
  const double h = 0.1, R = 5, depth = 3;
  const double cx = 25.03, cy = 24.96;
  HeightMap m(0, 0, h, 500, 500, -20, 0);
  const double v = sweep_path(m, ball(2 * R), {cx, cy, 10}, {cx, cy, -depth}, 0.05);
  double worst = 0;
  for (std::size_t j = 0; j < m.ny(); ++j) {
    for (std::size_t i = 0; i < m.nx(); ++i) {
      const double r = std::hypot(m.x_of(i) - cx, m.y_of(j) - cy);
      const double sphere = r < R ? -depth + R - std::sqrt(R * R - r * r) : 1e9;
      const double expect = std::min(0.0, sphere);
      worst = std::max(worst, std::fabs(m.at(i, j) - expect));
    }
  }
  EXPECT_LT(worst, 2e-6);  // float storage
  // Dimple radius √(R² − (R − d)²) = √21; the cap's volume π·d²·(3R − d)/3, within the band
  // of half a cell diagonal around its rim (perimeter 2π·√21) at most d deep.
  const double cap = kPi * depth * depth * (3 * R - depth) / 3;
  const double rim = std::sqrt(R * R - (R - depth) * (R - depth));
  EXPECT_NEAR(v, cap, depth * std::sqrt(2.0) * h * 2 * kPi * rim);
  EXPECT_NEAR(v, cap, 0.01 * cap);
  // Just inside and outside the rim.
  const auto cell = [&](double x, double y) {
    return m.at(static_cast<std::size_t>(x / h), static_cast<std::size_t>(y / h));
  };
  EXPECT_LT(cell(cx + rim - 0.15, cy), 0.0f);
  EXPECT_EQ(cell(cx + rim + 0.15, cy), 0.0f);
}

TEST(HeightMapSweep, SecondPassOverTheSamePathRemovesNothing) {
  // A 3D path (ramps, diagonals) swept twice with different cycle lengths: the second pass
  // finds every cell already at the envelope. Float storage allows a few ulp per cell.
  for (const ToolProfile& t : {flat(6), ball(6), bull(8, 1.5)}) {
    HeightMap m(-20, -20, 0.1, 400, 400, -20, 0);
    const Vec3 path[] = {{-25, -3, 2}, {-5, -3, -2}, {8, 9, -2.5}, {15, -10, -1}, {25, -10, -1}};
    double first = 0, second = 0;
    for (std::size_t k = 0; k + 1 < std::size(path); ++k) {
      first += sweep_path(m, t, path[k], path[k + 1], 0.05);
    }
    for (std::size_t k = 0; k + 1 < std::size(path); ++k) {
      second += sweep_path(m, t, path[k], path[k + 1], 0.0377);
    }
    EXPECT_GT(first, 100);
    EXPECT_LT(second, 1e-4) << "first pass removed " << first;
  }
}

TEST(HeightMapSweep, EnvelopeMatchesBruteForceForEveryShape) {
  // One ramp segment; the reference lowers each cell by the tool at 20 000 positions along
  // it. The exact sweep is never higher than the samples (it is the minimum) and lower only
  // by what the sampling misses (a tool step of 2e-3 mm at slopes below 1 → < 2e-3 mm).
  const Vec3 a{-3.3, -2.1, 1.2}, b{4.1, 3.7, -2.4};
  for (const ToolProfile& t : {flat(5), ball(5), bull(5, 1)}) {
    HeightMap m(-8, -8, 0.1, 160, 160, -10, 0);
    m.sweep(t, a, b);
    double worst_above = 0, worst_below = 0;
    constexpr int kSteps = 20000;
    for (std::size_t j = 0; j < m.ny(); j += 5) {
      for (std::size_t i = 0; i < m.nx(); i += 5) {
        double z = 0;  // the stock top
        for (int k = 0; k <= kSteps; ++k) {
          const Vec3 p = a + (static_cast<double>(k) / kSteps) * (b - a);
          const double r = std::hypot(m.x_of(i) - p.x, m.y_of(j) - p.y);
          if (r <= t.radius_mm) z = std::min(z, p.z + t.height_at(r));
        }
        const double got = m.at(i, j);
        worst_above = std::max(worst_above, got - z);
        worst_below = std::max(worst_below, z - got);
      }
    }
    EXPECT_LT(worst_above, 1e-5) << "shape " << static_cast<int>(t.shape);
    EXPECT_LT(worst_below, 2e-3) << "shape " << static_cast<int>(t.shape);
  }
}

TEST(HeightMapSweep, RandomShortSegmentsMatchBruteForce) {
  // Per-cycle-sized segments in random directions and slopes (steep ones included), each on a
  // fresh map: every cell equals the brute-force minimum over 2 000 tool positions to within
  // what the sampling can miss, and is never above it.
  std::uint64_t state = 12345;
  auto uniform = [&state](double lo, double hi) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return lo + (hi - lo) * static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  for (const ToolProfile& t : {flat(4), ball(4), bull(4, 0.7)}) {
    for (int k = 0; k < 20; ++k) {
      HeightMap m(-4, -4, 0.1, 80, 80, -10, 0);
      const Vec3 a{uniform(-0.5, 0.5), uniform(-0.5, 0.5), uniform(-1.5, -0.5)};
      const double len = uniform(0.01, 0.5), dir = uniform(0, 2 * kPi);
      const Vec3 b = a + Vec3{len * std::cos(dir), len * std::sin(dir), uniform(-0.4, 0.4)};
      m.sweep(t, a, b);
      double above = 0, below = 0;
      constexpr int kSteps = 2000;
      for (std::size_t j = 0; j < m.ny(); j += 2) {
        for (std::size_t i = 0; i < m.nx(); i += 2) {
          double z = 0;
          for (int s = 0; s <= kSteps; ++s) {
            const Vec3 p = a + (static_cast<double>(s) / kSteps) * (b - a);
            const double r = std::hypot(m.x_of(i) - p.x, m.y_of(j) - p.y);
            if (r <= t.radius_mm) z = std::min(z, p.z + t.height_at(r));
          }
          above = std::max(above, m.at(i, j) - z);
          below = std::max(below, z - m.at(i, j));
        }
      }
      EXPECT_LT(above, 1e-5) << "shape " << static_cast<int>(t.shape) << " segment " << k;
      EXPECT_LT(below, 1e-3) << "shape " << static_cast<int>(t.shape) << " segment " << k;
    }
  }
}

TEST(HeightMapSweep, CutsNothingAboveTheStockOrOutsideIt) {
  HeightMap m(0, 0, 0.1, 100, 100, -5, 0);
  EXPECT_EQ(m.sweep(flat(6), {-20, 5, -1}, {-10, 5, -1}), 0.0);  // beside
  EXPECT_EQ(m.sweep(ball(6), {0, 0, 0.5}, {10, 10, 0.5}), 0.0);  // above
  EXPECT_EQ(m.sweep(flat(6), {5, 5, 0}, {6, 5, 0}), 0.0);        // touching the top
  // Through the bottom: only the stock's own thickness goes.
  const double v = m.sweep(flat(2), {5, 5, -50}, {5, 5, -50});
  EXPECT_NEAR(
      v,
      5 * 0.01 *
          std::count_if(m.heights().begin(), m.heights().end(), [](float z) { return z == -5.0f; }),
      1e-9);
  EXPECT_GT(v, 5 * kPi * 0.9 * 0.9);
}

}  // namespace
}  // namespace cncore::cut
