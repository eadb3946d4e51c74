// The cutting simulation of `cncore serve` (a machine with [stock]): a served program cuts a
// pocket, measured on the published height map and on the spindle load of the served samples;
// and the ring between the cycle and the simulation, filled beyond its capacity, loses no
// material removal.
#include "runtime/cutting.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <thread>

#include "served.hpp"

namespace cncore::runtime {
namespace {

using testing::Served;

// The built-in mill with a 60 × 60 × 20 mm stock (top at Z 0) in cells of 0.25 mm, and a flat
// Ø6 end mill.
MachineConfig stock_machine() {
  return parse_machine_config(R"(
[stock]
min_mm = [-30, -30, -20]
size_mm = [60, 60, 20]
cell_mm = 0.25

[cutting]
material = "aluminium_6061"
spindle_power_kw = 5.5

[[tools]]
number = 1
type = "flat"
diameter_mm = 6
)",
                              "stock.toml");
}

std::string write_program(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

// The map's height at the cell holding (x, y).
double height_at(const HeightMapGrid& g, double x, double y) {
  const auto i = static_cast<std::size_t>(std::floor((x - g.x0_mm) / g.cell_mm));
  const auto j = static_cast<std::size_t>(std::floor((y - g.y0_mm) / g.cell_mm));
  return g.heights_mm.at(j * g.nx + i);
}

// Waits until the published map satisfies `ok` (it is published at most twice a second).
template <typename Ok>
std::shared_ptr<const HeightMapGrid> wait_map(
    const std::function<std::shared_ptr<const HeightMapGrid>()>& get, Ok ok,
    double timeout_s = 20) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  std::shared_ptr<const HeightMapGrid> g;
  while (std::chrono::steady_clock::now() < end) {
    g = get();
    if (g && ok(*g)) return g;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return g;
}

// A raster pocket 3 mm deep: tool centre over X −10…10, Y −10…10 in passes 5 mm apart (a Ø6
// tool: the passes overlap), so the pocket is X, Y within ±13 mm; rapids in air before and
// after, and a dwell in air at the end.
constexpr const char* kPocket = R"(G21 G90 G17
T1 M6
G0 X-25 Y-25 Z5
G0 X-10 Y-10 Z5
G1 Z-3 F600
G1 X10 F3000
G1 Y-5
G1 X-10
G1 Y0
G1 X10
G1 Y5
G1 X-10
G1 Y10
G1 X10
G0 Z5
G0 X25 Y25
G4 P0.6
M30
)";
constexpr std::uint32_t kFirstRapidLine = 3, kFirstCutLine = 6, kLastCutLine = 14;
constexpr std::uint32_t kDwellLine = 17;

TEST(Cutting, ServedPocketIsInTheHeightMapAndTheLoadFollowsTheCut) {
  Served sv(stock_machine());
  Controller& c = sv.c();
  const auto get = [&c] { return c.heightmap(); };
  ASSERT_NE(c.heightmap(), nullptr);
  // An MDI cut before the program: a dimple at (25, 25) that the program's fresh stock removes.
  ASSERT_TRUE(c.mdi("G0 X20 Y20 Z5\nG1 Z-1 F3000\nG0 Z5").ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  auto g = wait_map(get, [](const HeightMapGrid& m) { return height_at(m, 20, 20) < -0.99; });
  ASSERT_NEAR(height_at(*g, 20, 20), -1, 1e-4) << "the MDI line cut its dimple";

  ASSERT_TRUE(c.load_program(write_program("pocket.ngc", kPocket)).ok);
  const std::uint64_t first = c.status().cycle;
  ASSERT_TRUE(c.cycle_start().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  g = wait_map(get, [](const HeightMapGrid& m) {
    return height_at(m, 0, 0) < -2.99 && height_at(m, 10, 10) < -2.99 && height_at(m, 20, 20) > -1;
  });
  // Inside the pocket: the programmed depth; outside: the stock's top, untouched.
  for (const auto& [x, y] :
       {std::pair{0.0, 0.0}, {-8.0, 8.0}, {8.0, -8.0}, {12.0, 2.5}, {-12.5, -10.0}, {2.5, 12.5}}) {
    EXPECT_NEAR(height_at(*g, x, y), -3, 1e-4) << "inside the pocket at " << x << ", " << y;
  }
  for (const auto& [x, y] :
       {std::pair{20.0, 20.0}, {16.0, 0.0}, {0.0, -16.0}, {-25.0, 25.0}, {29.0, -29.0}}) {
    EXPECT_EQ(height_at(*g, x, y), 0) << "outside the pocket at " << x << ", " << y;
  }

  // The spindle load of the served samples: > 0 while cutting, 0 in the air before the cut and
  // once the load meter's window (20 ms) and the simulation's lag have passed after it.
  const std::vector<motion::Sample> samples = sv.samples();
  std::size_t cutting = 0, loaded = 0, air = 0, dwell = 0;
  std::uint64_t dwell_start = 0;
  const Status st = c.status();
  for (std::uint64_t n = first; n < samples.size(); ++n) {
    const motion::Sample& s = samples[n];
    if (s.line == kFirstRapidLine) {
      ++air;
      EXPECT_EQ(s.load_pct, 0) << "cycle " << n << " is a rapid in the air";
    }
    if (s.line >= kFirstCutLine && s.line <= kLastCutLine && s.feed_mm_min > 0) {
      ++cutting;
      if (s.load_pct > 0) ++loaded;
    }
    if (s.line == kDwellLine) {
      if (dwell_start == 0) dwell_start = n;
      // 0.2 s into the dwell: beyond the window and the lag (reported below).
      if (n >= dwell_start + 200) {
        ++dwell;
        EXPECT_EQ(s.load_pct, 0) << "cycle " << n << " dwells in the air";
      }
    }
  }
  std::cout << cutting << " cutting cycles, " << loaded << " with load > 0; lag "
            << st.cutting_lag_cycles << " cycles at the end, " << st.cutting_coalesced
            << " cycles merged\n";
  EXPECT_GT(air, 20U);
  EXPECT_GT(dwell, 200U);
  ASSERT_GT(cutting, 1000U);
  EXPECT_GE(static_cast<double>(loaded), 0.97 * static_cast<double>(cutting));
  EXPECT_EQ(st.load_pct, 0);

  // Reset stock: the whole map at the stock's top again.
  ASSERT_TRUE(c.reset_stock().ok);
  g = wait_map(get, [](const HeightMapGrid& m) { return height_at(m, 0, 0) == 0; });
  for (const float h : g->heights_mm) ASSERT_EQ(h, 0);
}

// A full-width slot 5 mm deep with a Ø10 flat end mill at F3000: 2 500 mm³/s, 31.8 % of 5.5 kW
// in aluminium. Served with [adaptive] on (target 20 %) and off; measured from X 5 to X 22 (the
// slot ends at X 25): the speed by differences of the served set-points, and the samples' load.
struct SlotRun {
  double speed_mm_min = 0;
  double load_pct = 0;
};

SlotRun serve_slot(bool adaptive) {
  MachineConfig m = stock_machine();
  m.cutting.tools[0].diameter_mm = 10;
  m.adaptive.enabled = adaptive;
  m.adaptive.target_load_pct = 20;
  m.adaptive.ki = 20;  // the integral settles in ≈ 0.2 s (5 /s, the default: ≈ 0.8 s)
  Served sv(m);
  const std::string program = write_program("slot.ngc", R"(G21 G90
G0 X-25 Y0 Z5
G1 Z-5 F600
G1 X25 F3000
G0 Z5
M30
)");
  EXPECT_TRUE(sv.c().load_program(program).ok);
  EXPECT_TRUE(sv.c().cycle_start().ok);
  EXPECT_TRUE(sv.wait_state(MachineState::kIdle));
  const std::vector<motion::Sample> samples = sv.samples();
  // Cycles with the tool between X 5 and X 22 on the slot's line (4).
  std::size_t first = 0, last = 0;
  double load_sum = 0;
  for (std::size_t n = 1; n < samples.size(); ++n) {
    const motion::Sample& s = samples[n];
    if (s.line != 4 || s.position[kX] < 5 || s.position[kX] > 22) continue;
    if (first == 0) first = n;
    last = n;
    load_sum += s.load_pct;
  }
  EXPECT_GT(last, first + 100);
  const double t_s = static_cast<double>(last - first) * m.period_s;
  return {(samples[last].position[kX] - samples[first].position[kX]) / t_s * 60,
          load_sum / static_cast<double>(last - first + 1)};
}

TEST(Cutting, AdaptiveFeedHoldsTheSimulatedLoadAtItsTarget) {
  const SlotRun off = serve_slot(false);
  const SlotRun on = serve_slot(true);
  std::cout << "slot without adaptive feed: " << off.speed_mm_min << " mm/min, load "
            << off.load_pct << " %; with (target 20 %): " << on.speed_mm_min << " mm/min, load "
            << on.load_pct << " %\n";
  EXPECT_NEAR(off.speed_mm_min, 3000, 30);
  EXPECT_NEAR(off.load_pct, 31.8, 1.5);
  EXPECT_NEAR(on.load_pct, 20, 2);
  EXPECT_LT(on.speed_mm_min, 0.75 * 3000);
}

TEST(Cutting, WithoutStockThereIsNoSimulation) {
  Served sv(default_machine_config());
  EXPECT_EQ(sv.c().heightmap(), nullptr);
  EXPECT_FALSE(sv.c().reset_stock().ok);
  EXPECT_EQ(sv.c().status().heightmap_version, 0U);
}

// The cycle fills a ring of 8 with 2 000 cycles of a groove before the simulation starts: the
// cycles that found it full are merged, and the groove is cut over its whole length.
TEST(Cutting, AFullRingMergesCyclesWithoutLosingMaterial) {
  const MachineConfig m = stock_machine();
  CuttingThread cutting(m, 8, false);
  Status st;
  constexpr int kCycles = 2000;
  for (int n = 0; n <= kCycles; ++n) {
    motion::Sample s;
    s.position[kX] = -20 + 40.0 * n / kCycles;
    s.position[kZ] = -1;
    cutting.on_cycle(static_cast<std::uint64_t>(n), s, st);
  }
  EXPECT_GT(st.cutting_coalesced, kCycles - 10U);
  cutting.start();
  // One more cycle hands over the merged rest.
  motion::Sample last;
  last.position[kX] = 20;
  last.position[kZ] = -1;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (cutting.cycles_done() < kCycles + 2 && std::chrono::steady_clock::now() < end) {
    cutting.on_cycle(kCycles + 1, last, st);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_GE(cutting.cycles_done(), kCycles + 2U) << "every cycle reached the simulation";
  const auto g = wait_map([&cutting] { return cutting.heightmap(); },
                          [](const HeightMapGrid& map) { return height_at(map, 19.9, 0) < -0.99; });
  for (double x = -19.9; x < 20; x += 0.25) {
    for (const double y : {-2.5, 0.0, 2.5}) {
      ASSERT_NEAR(height_at(*g, x, y), -1, 1e-4) << "the groove at " << x << ", " << y;
    }
  }
  EXPECT_EQ(height_at(*g, 0, 3.5), 0);
  EXPECT_EQ(height_at(*g, -23.5, 0), 0);
}

}  // namespace
}  // namespace cncore::runtime
