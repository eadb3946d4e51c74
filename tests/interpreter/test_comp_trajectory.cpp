// Cutter radius compensation run on the simulated machine: the axis set-points of the executed
// path (every interpolation cycle, after acc/dec) stay one tool radius from the programmed
// contour, within the machine's contour tolerance, along the straight parts of the contour.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "comp_contour.hpp"
#include "config/machine_config.hpp"
#include "simulation/run.hpp"

namespace cncore::interp::test {
namespace {

struct Keep : sim::SampleObserver {
  std::vector<motion::Sample> samples;
  void on_sample(const motion::Sample& s) override { samples.push_back(s); }
};

TEST(CutterCompTrajectory, ExecutedPathStaysOneRadiusFromTheContour) {
  // A 60 × 40 rectangle, counter-clockwise from the middle of its first side; D8 (r = 4).
  const std::vector<Piece> contour = {{{30, 0}, {60, 0}, false, false, {}},
                                      {{60, 0}, {60, 40}, false, false, {}},
                                      {{60, 40}, {0, 40}, false, false, {}},
                                      {{0, 40}, {0, 0}, false, false, {}},
                                      {{0, 0}, {40, 0}, false, false, {}}};
  const double radius = 4;
  const MachineConfig machine = default_machine_config();
  for (const char* comp : {"G41.1 D8", "G42.1 D8"}) {
    SCOPED_TRACE(comp);
    const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / "comp_rectangle.ngc";
    {
      std::ofstream out(path);
      out << "G21 G90 G94 G17 F3000\nG0 X20 Y0\n"
          << comp << "\nG1 X30 Y0\n"
          << contour_gcode(contour, plane_words(17)) << "G40\nG1 X40 Y-20\nM30\n";
    }
    Keep keep;
    sim::run_program(path.string(), machine, {}, {&keep});
    // Lines 5…9 are the contour; a sample on a straight part has its nearest contour point
    // inside a side, at least the radius away from the corners.
    std::size_t straight = 0;
    double worst = 0;
    for (const motion::Sample& s : keep.samples) {
      if (s.line < 5 || s.line > 9) continue;
      const P2 q{s.position[kX], s.position[kY]};
      const Foot f = nearest(contour, q);
      if (f.at_end) continue;
      bool near_corner = false;
      for (const Piece& p : contour) {
        near_corner = near_corner || std::hypot(f.at.a - p.from.a, f.at.b - p.from.b) < radius;
      }
      if (near_corner) continue;
      ++straight;
      worst = std::max(worst, std::fabs(f.distance - radius));
    }
    EXPECT_GT(straight, 1000u);
    EXPECT_LE(worst, machine.contour_tolerance_mm) << "largest |distance − radius| (mm)";
    ASSERT_FALSE(keep.samples.empty());
    EXPECT_NEAR(keep.samples.back().position[kX], 40, 1e-9);
    EXPECT_NEAR(keep.samples.back().position[kY], -20, 1e-9);
  }
}

}  // namespace
}  // namespace cncore::interp::test
