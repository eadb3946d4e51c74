// The run's figures against the program as written: sim::run_program with the summary observer on
// programs whose pieces are merged into lines, shorter than a cycle's travel, and arcs. The
// expected values are computed here from the programmed geometry and the recorded samples.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "io/summary.hpp"
#include "simulation/run.hpp"

namespace cncore {
namespace {

// A programmed move in the XY plane: a line, or an arc about `centre` (counter-clockwise for
// ccw) from angle a0 sweeping `sweep` rad.
struct Move {
  std::uint32_t line = 0;
  Vec3 from, to;
  bool arc = false;
  Vec3 centre;
  double radius = 0, a0 = 0, sweep = 0;
  double feed_mm_min = 0;
  double length() const { return arc ? radius * std::fabs(sweep) : norm(to - from); }
  double distance(Vec3 p) const {
    if (!arc) {
      const Vec3 d = to - from;
      const double t = std::clamp(dot(p - from, d) / dot(d, d), 0.0, 1.0);
      return norm(p - (from + t * d));
    }
    const Vec3 q = p - centre;
    double a = std::atan2(q.y, q.x) - a0;
    if (sweep < 0) a = -a;
    a = std::fmod(std::fmod(a, 2 * std::numbers::pi) + 2 * std::numbers::pi, 2 * std::numbers::pi);
    if (a <= std::fabs(sweep)) return std::hypot(std::hypot(q.x, q.y) - radius, q.z);
    return std::min(norm(p - from), norm(p - to));
  }
};

// Writes a program line by line and keeps the geometry of its moves.
class Program {
 public:
  Program() {
    text_ = "G21 G90 G17 G64\nG0 X0 Y0 Z0\n";
    lines_ = 2;
  }
  void feed(double f) {
    feed_ = f;
    add(format("F{:.0f}", f));
  }
  void line_to(Vec3 p) {
    add(format("G1 X{:.6f} Y{:.6f}", p.x, p.y));
    Move m;
    m.line = lines_;
    m.from = at_;
    m.to = p;
    m.feed_mm_min = feed_;
    moves_.push_back(m);
    at_ = p;
  }
  // A counter-clockwise (G3) or clockwise (G2) arc to p about the centre c.
  void arc_to(Vec3 p, Vec3 c, bool ccw) {
    add(format("{} X{:.6f} Y{:.6f} I{:.6f} J{:.6f}", ccw ? "G3" : "G2", p.x, p.y, c.x - at_.x,
               c.y - at_.y));
    Move m;
    m.line = lines_;
    m.from = at_;
    m.to = p;
    m.arc = true;
    m.centre = c;
    m.radius = norm(at_ - c);
    m.a0 = std::atan2(at_.y - c.y, at_.x - c.x);
    double s = std::atan2(p.y - c.y, p.x - c.x) - m.a0;
    if (ccw && s <= 0) s += 2 * std::numbers::pi;
    if (!ccw && s >= 0) s -= 2 * std::numbers::pi;
    m.sweep = s;
    m.feed_mm_min = feed_;
    moves_.push_back(m);
    at_ = p;
  }
  Vec3 at() const { return at_; }
  const std::vector<Move>& moves() const { return moves_; }
  std::string write(const std::string& name) const {
    const auto path = std::filesystem::temp_directory_path() / name;
    std::ofstream(path) << text_ << "M2\n";
    return path.string();
  }

 private:
  template <typename... A>
  static std::string format(const char* f, A... a) {
    return fmt::format(fmt::runtime(f), a...);
  }
  void add(const std::string& l) {
    text_ += l + "\n";
    ++lines_;
  }
  std::string text_;
  std::uint32_t lines_ = 0;
  double feed_ = 0;
  Vec3 at_;
  std::vector<Move> moves_;
};

struct Recorder : sim::SampleObserver {
  std::vector<motion::Sample> samples;
  void on_sample(const motion::Sample& s) override { samples.push_back(s); }
};

struct Outcome {
  io::Summary summary;
  std::vector<motion::Sample> samples;
};

Outcome run(const std::string& path, double merge_tolerance_mm) {
  MachineConfig machine = default_machine_config();
  machine.merge_tolerance_mm = merge_tolerance_mm;
  sim::RunOptions options;
  options.kernel = motion::kernel_options_for(machine);
  io::SummaryObserver summary(machine, "lookahead");
  Recorder rec;
  sim::run_program(path, machine, options, {&summary, &rec});
  return {summary.summary(), std::move(rec.samples)};
}

// A line along X cut into 0.1 mm pieces whose ends wobble by ±0.2 µm (merged into one line),
// a curve of 10 µm chords turning 0.02 rad each (shorter than a cycle's travel, not merged: they
// turn by more than a line's rounding) and a half circle.
Program mixed_program() {
  Program p;
  p.feed(3000);
  for (int i = 1; i <= 200; ++i) p.line_to({0.1 * i, i % 2 == 0 ? 0.0002 : -0.0002, 0});
  p.line_to({20.1, 0, 0});
  double heading = 0;
  for (int i = 0; i < 100; ++i) {
    heading += 0.02;
    const Vec3 a = p.at();
    p.line_to({a.x + 0.01 * std::cos(heading), a.y + 0.01 * std::sin(heading), 0});
  }
  const Vec3 a = p.at();
  const Vec3 d{std::cos(heading), std::sin(heading), 0};
  const Vec3 b = a + 2.0 * d;
  p.line_to(b);
  const Vec3 n{-d.y, d.x, 0};  // the centre 5 mm to the left: a G3 half circle
  p.arc_to(b + 10.0 * n, b + 5.0 * n, true);
  return p;
}

// The largest distance of the servo set-points to the programmed path (all of it).
double max_distance(const std::vector<motion::Sample>& samples, const std::vector<Move>& moves) {
  double worst = 0;
  for (const motion::Sample& s : samples) {
    double best = INFINITY;
    for (const Move& m : moves) best = std::min(best, m.distance(s.position.xyz()));
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(ProgrammedPath, ContourErrorIsTheDistanceToTheProgrammedPathWithMergedPieces) {
  const Program p = mixed_program();
  const std::string path = p.write("cncore_programmed_mixed.ngc");
  for (const double tol : {0.0005, 0.001}) {
    const Outcome r = run(path, tol);
    const double expected = max_distance(r.samples, p.moves());
    EXPECT_NEAR(r.summary.max_contour_error_mm, expected, 1e-6) << "merge tolerance " << tol;
    // The merged line leaves the wobbling pieces by up to their wobble (0.2 µm), within tol.
    EXPECT_GT(r.summary.max_contour_error_mm, 1.5e-4);
    EXPECT_LE(r.summary.max_contour_error_mm, tol + 1e-9);
  }
  const Outcome off = run(path, 0);
  EXPECT_NEAR(off.summary.max_contour_error_mm, max_distance(off.samples, p.moves()), 1e-6);
  EXPECT_LT(off.summary.max_contour_error_mm, 1e-6);
}

TEST(ProgrammedPath, EachSampleNamesTheProgrammedBlockUnderTheTool) {
  const Program p = mixed_program();
  const Outcome r = run(p.write("cncore_programmed_lines.ngc"), 0.0005);
  std::multimap<std::uint32_t, const Move*> by_line;
  for (const Move& m : p.moves()) by_line.emplace(m.line, &m);
  std::size_t named = 0;
  std::map<std::uint32_t, int> seen;
  for (const motion::Sample& s : r.samples) {
    const auto [lo, hi] = by_line.equal_range(s.line);
    if (lo == hi) continue;  // the G0 to the start, M2 at the end
    double best = INFINITY;
    for (auto it = lo; it != hi; ++it)
      best = std::min(best, it->second->distance(s.path_position.xyz()));
    EXPECT_LE(best, 0.0005 + 1e-9) << "t = " << s.t_s << " line " << s.line;
    ++named;
    ++seen[s.line];
  }
  EXPECT_GT(named, r.samples.size() * 9 / 10);
  // The 0.1 mm pieces of the merged line take about two cycles each: most of them are named.
  int pieces_named = 0;
  for (const Move& m : p.moves()) pieces_named += m.line <= 203 && seen.contains(m.line) ? 1 : 0;
  EXPECT_GT(pieces_named, 150);
}

TEST(ProgrammedPath, EveryBlockOfAFineCircleHasItsShareOfTheTimeLost) {
  Program p;
  p.feed(6000);
  constexpr int kChords = 36000;
  constexpr double kR = 50;
  p.line_to({kR, 0, 0});
  for (int i = 1; i <= kChords; ++i) {
    const double a = 2 * std::numbers::pi * i / kChords;
    p.line_to({kR * std::cos(a), kR * std::sin(a), 0});
  }
  const Outcome r = run(p.write("cncore_programmed_circle.ngc"), 0.0005);
  double ideal_s = 0;  // the program's time at its programmed feed
  for (const Move& m : p.moves()) ideal_s += m.length() / m.feed_mm_min * 60;
  EXPECT_EQ(r.summary.blocks_timed, p.moves().size());
  EXPECT_NEAR(r.summary.time_lost_s, r.summary.cycle_time_s - ideal_s, 1e-3);
  // Far more blocks than cycles: most blocks are passed within a cycle.
  EXPECT_LT(r.summary.cycles, p.moves().size() / 5);
}

}  // namespace
}  // namespace cncore
