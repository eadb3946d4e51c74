// The HTML report's time lost: the same figures as the summary (one accounting, TimeShare), on
// programs whose blocks are far shorter than a cycle's travel; causes that add up to the time
// lost against the program as written, each checked against a value computed here from the
// program and the machine.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "io/report.hpp"
#include "simulation/run.hpp"

namespace cncore::io {
namespace {

namespace fs = std::filesystem;

// A program of G1 moves (and G0 where asked) and the time each takes at its F as written.
struct Program {
  std::string text = "G21 G90 G17\n";
  double ideal_s = 0;  // Σ length / F over the moves
  double x = 0, y = 0;
  void move(double to_x, double to_y, double feed_mm_min, bool rapid = false) {
    text += fmt::format("{} X{:.6f} Y{:.6f}{}\n", rapid ? "G0" : "G1", to_x, to_y,
                        rapid ? std::string() : fmt::format(" F{:g}", feed_mm_min));
    ideal_s += std::hypot(to_x - x, to_y - y) / feed_mm_min * 60;
    x = to_x;
    y = to_y;
  }
  fs::path write(const std::string& name) const {
    const fs::path dir = fs::path(CNCORE_TEST_TMP_DIR) / "losses";
    fs::create_directories(dir);
    const fs::path p = dir / name;
    std::ofstream(p) << text << "M2\n";
    return p;
  }
};

struct Outcome {
  Summary summary;
  ReportLosses losses;
  std::vector<ReportSlowSpot> slowest, rapids;
};

// shared: the report listens to the summary observer (as `cncore run` does); else it runs its
// own accounting.
Outcome run(const fs::path& program, bool shared, double override_pct = 100,
            motion::Mode mode = motion::Mode::kLookahead) {
  const MachineConfig m = default_machine_config();
  const std::string mode_name = mode == motion::Mode::kStop ? "stop" : "lookahead";
  SummaryObserver summary(m, mode_name);
  ReportObserver report(m, mode_name, ReportOptions{}, shared ? &summary : nullptr);
  sim::RunOptions o;
  o.kernel.override_pct = override_pct;
  o.kernel.mode = mode;
  sim::run_program(program.string(), m, o, {&summary, &report});
  return {summary.summary(), report.losses(), report.slowest(), report.slowest_rapids()};
}

double cause(const ReportLosses& l, LossCause c) {
  return l.cause_s[static_cast<std::size_t>(c)];
}

// The report's time lost is the summary's: in all, and line by line for the summary's worst.
void expect_same_accounting(const Outcome& r) {
  EXPECT_NEAR(r.losses.cutting_s + r.losses.rapid_s, r.summary.time_lost_s, 1e-9);
  ASSERT_FALSE(r.summary.slowest.empty());
  std::map<std::uint32_t, double> report_lost;
  for (const ReportSlowSpot& s : r.slowest) report_lost[s.line] = s.lost_s;
  for (const SlowSpot& s : r.summary.slowest) {
    ASSERT_TRUE(report_lost.contains(s.line)) << "line " << s.line;
    EXPECT_NEAR(report_lost[s.line], s.lost_s, 1e-12) << "line " << s.line;
  }
}

TEST(ReportLosses, AFineCircleAgreesWithTheSummary) {
  // 36 000 chords of 8.7 µm at F6000 (0.1 mm per cycle): about 11 chords pass in a cycle.
  Program p;
  constexpr int kChords = 36000;
  constexpr double kR = 50;
  p.move(kR, 0, 6000);
  for (int i = 1; i <= kChords; ++i) {
    const double a = 2 * std::numbers::pi * i / kChords;
    p.move(kR * std::cos(a), kR * std::sin(a), 6000);
  }
  const fs::path path = p.write("circle36000.ngc");
  for (const bool shared : {true, false}) {
    SCOPED_TRACE(shared ? "listening to the summary" : "own accounting");
    const Outcome r = run(path, shared);
    expect_same_accounting(r);
    // Every block passed has its share: the time lost is the cycle time less the time at F.
    EXPECT_NEAR(r.summary.time_lost_s, r.summary.cycle_time_s - p.ideal_s, 1e-3);
    EXPECT_NEAR(r.losses.total_s(), r.summary.cycle_time_s - p.ideal_s, 1e-3);
    EXPECT_EQ(r.losses.rapid_s, 0);
    // R 50 mm allows √(A·R) = 18 974 mm/min: only the start, the 90° turn from the line into
    // the circle and the end slow the tool.
    EXPECT_GT(cause(r.losses, LossCause::kStops) + cause(r.losses, LossCause::kCorners),
              0.99 * r.losses.total_s());
  }
}

TEST(ReportLosses, RandomShortLinesAgreeWithTheSummary) {
  // 4 000 lines of 25 µm in random directions at F3000.
  Program p;
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> heading(0, 2 * std::numbers::pi);
  for (int i = 0; i < 4000; ++i) {
    const double a = heading(rng);
    p.move(p.x + 0.025 * std::cos(a), p.y + 0.025 * std::sin(a), 3000);
  }
  const fs::path path = p.write("random25um.ngc");
  for (const bool shared : {true, false}) {
    SCOPED_TRACE(shared ? "listening to the summary" : "own accounting");
    const Outcome r = run(path, shared);
    expect_same_accounting(r);
    // (Not the cycle time less the time at F: a cycle's step cuts across the turns it passes,
    // so the distance measured is shorter than the path.)
    EXPECT_NEAR(r.losses.total_s(), r.summary.time_lost_s, 1e-9);
    // Turns of 90° on average every 25 µm: the corners.
    EXPECT_GT(cause(r.losses, LossCause::kCorners), 0.9 * r.losses.total_s());
  }
}

TEST(ReportLosses, AChainOfFineChordsIsTheShortSegments) {
  // Three turns of a circle of R 2 mm in chords of 3.5 µm at F6000, 0.1° turns each: no corner,
  // no arc, but the chain's curvature allows √(A·R) = 3 795 mm/min.
  Program p;
  constexpr int kChords = 3600;
  constexpr double kR = 2;
  p.move(kR, 0, 6000);
  for (int i = 1; i <= 3 * kChords; ++i) {
    const double a = 2 * std::numbers::pi * i / kChords;
    p.move(kR * std::cos(a), kR * std::sin(a), 6000);
  }
  const Outcome r = run(p.write("small-circle.ngc"), true);
  expect_same_accounting(r);
  // Three turns of 12.6 mm: all but the braking distance (2.5 mm at F6000) after the 90° turn
  // from the first line and before the end.
  EXPECT_GT(cause(r.losses, LossCause::kShortSegments), 0.5 * r.losses.total_s());
  EXPECT_EQ(cause(r.losses, LossCause::kArcs), 0);
  EXPECT_EQ(cause(r.losses, LossCause::kAcceleration), 0);
}

TEST(ReportLosses, FeedLimitAndOverrideAreTheTimeTheyAdd) {
  // A square of 100 mm sides. At F20000, twice the machine's 10 000 mm/min, the feed limit adds
  // 400 mm·(1/10000 − 1/20000) min = 1.2 s; at F6000 and override 50 % the override adds
  // 400 mm·(1/3000 − 1/6000) min = 4 s. The corners and the stops at both ends add the rest.
  struct Case {
    double feed_mm_min, override_pct, limit_s, override_s;
  };
  for (const Case c : {Case{20000, 100, 1.2, 0}, Case{6000, 50, 0, 4}}) {
    SCOPED_TRACE(fmt::format("F{} at {} %", c.feed_mm_min, c.override_pct));
    Program p;
    p.move(100, 0, c.feed_mm_min);
    p.move(100, 100, c.feed_mm_min);
    p.move(0, 100, c.feed_mm_min);
    p.move(0, 0, c.feed_mm_min);
    const Outcome r = run(p.write("square.ngc"), true, c.override_pct);
    EXPECT_NEAR(cause(r.losses, LossCause::kFeedLimit), c.limit_s, 1e-3);
    EXPECT_NEAR(cause(r.losses, LossCause::kOverride), c.override_s, 1e-3);
    EXPECT_NEAR(r.losses.total_s(), r.summary.cycle_time_s - p.ideal_s, 2e-3);
    EXPECT_NEAR(r.losses.total_s() - c.limit_s - c.override_s, r.summary.time_lost_s, 2e-3);
    EXPECT_GT(cause(r.losses, LossCause::kCorners), 0);
    EXPECT_GT(cause(r.losses, LossCause::kStops), 0);
    EXPECT_NEAR(cause(r.losses, LossCause::kCorners) + cause(r.losses, LossCause::kStops),
                r.summary.time_lost_s, 1e-3);
  }
}

TEST(ReportLosses, ASmallArcIsTheArcs) {
  // A tangent R 1 mm quarter arc between two long lines at F6000 (v ≤ √(A·R) = 2683 mm/min):
  // the only slow-down apart from the start and the end.
  Program p;
  p.text += "G1 X40 F6000\nG3 X41 Y1 I0 J1\nG1 Y40\n";
  const Outcome r = run(p.write("arc.ngc"), true);
  const double arcs = cause(r.losses, LossCause::kArcs);
  const double stops = cause(r.losses, LossCause::kStops);
  EXPECT_GT(arcs, 0.01);
  EXPECT_GT(arcs + stops, 0.99 * r.summary.time_lost_s);
  EXPECT_EQ(cause(r.losses, LossCause::kCorners), 0);
}

TEST(ReportLosses, RapidsAreRankedApart) {
  Program p;
  for (int i = 0; i < 8; ++i) {
    p.move(10.0 * i + 10, 0, 1, true);
    p.move(10.0 * i + 15, 0, 2000);
    p.move(10.0 * i + 15, 5, 2000);
  }
  const Outcome r = run(p.write("rapids.ngc"), true);
  ASSERT_FALSE(r.slowest.empty());
  ASSERT_FALSE(r.rapids.empty());
  double rapid_lost = 0;
  for (const ReportSlowSpot& s : r.slowest) EXPECT_FALSE(s.rapid) << "line " << s.line;
  for (const ReportSlowSpot& s : r.rapids) {
    EXPECT_TRUE(s.rapid) << "line " << s.line;
    rapid_lost += s.lost_s;
  }
  // Eight rapids, all listed: their sum is the rapids' total.
  EXPECT_EQ(r.rapids.size(), 8u);
  EXPECT_NEAR(rapid_lost, r.losses.rapid_s, 1e-9);
  EXPECT_GT(r.losses.cutting_s, 0);
}

}  // namespace
}  // namespace cncore::io
