// The HTML report's observer: extremes survive decimation, memory stays flat, the slowest lines
// are explained by what makes them slow (values checked by hand against the machine limits).
#include "io/report.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "io/report_page.hpp"
#include "simulation/run.hpp"

namespace cncore::io {
namespace {

namespace fs = std::filesystem;

fs::path write_program(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(CNCORE_TEST_TMP_DIR) / "work";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p;
}

struct Run {
  ReportObserver report;
  SummaryObserver summary;
};

std::unique_ptr<Run> run(const fs::path& program, double override_pct = 100,
                         motion::AccDecType accdec = motion::KernelOptions{}.accdec) {
  const MachineConfig m = default_machine_config();
  auto r = std::unique_ptr<Run>(
      new Run{ReportObserver(m, "lookahead"), SummaryObserver(m, "lookahead")});
  sim::RunOptions o;
  o.kernel.override_pct = override_pct;
  o.kernel.accdec = accdec;
  sim::run_program(program.string(), m, o, {&r->report, &r->summary});
  return r;
}

const ReportSlowSpot* spot(const ReportObserver& r, std::uint32_t line) {
  static std::vector<ReportSlowSpot> keep;
  keep = r.slowest();
  for (const ReportSlowSpot& s : keep) {
    if (s.line == line) return &s;
  }
  return nullptr;
}

// Synthetic samples: X moves at 100 mm/s (6000 mm/min), 1 ms period, except one cycle at
// sample `spike` that moves 0.05 mm further (150 mm/s = 9000 mm/min, then back).
motion::Sample line_sample(std::uint64_t k, std::uint64_t spike) {
  motion::Sample s;
  s.t_s = static_cast<double>(k) * 1e-3;
  s.line = 1;
  s.position[0] = 0.1 * static_cast<double>(k) + (k >= spike ? 0.05 : 0.0);
  s.path_position = s.position;
  return s;
}

TEST(ReportObserver, BucketsKeepTheExtremesAndMemoryIsFlat) {
  const MachineConfig m = default_machine_config();
  ReportObserver r(m, "lookahead");
  constexpr std::uint64_t kSpike = 777'777, kSamples = 1'000'000;
  std::size_t mem_at_100k = 0;
  for (std::uint64_t k = 0; k < kSamples; ++k) {
    r.on_sample(line_sample(k, kSpike));
    if (k == 100'000) mem_at_100k = r.memory_bytes();
  }
  r.on_finish();
  EXPECT_EQ(r.samples(), kSamples);
  EXPECT_LE(r.buckets().size(), 2u * ReportOptions{}.buckets);
  EXPECT_GE(r.buckets().size(), ReportOptions{}.buckets);
  EXPECT_LE(r.path().size(), ReportOptions{}.path_points);
  EXPECT_LE(r.memory_bytes(), mem_at_100k + 1024) << "memory grows with the run";
  // The single fast cycle is still there after 8 merges, in the bucket that holds its time.
  double vmax = 0, vmin = 1e9;
  bool found = false;
  std::uint64_t counted = 0;
  for (const ReportBucket& b : r.buckets()) {
    vmax = std::max(vmax, b.speed_max_mm_min);
    if (b.t_first_s > 0.01) vmin = std::min(vmin, b.speed_min_mm_min);
    if (b.t_first_s <= 777.777 && b.t_last_s >= 777.777) found = b.speed_max_mm_min > 8999;
    counted += b.samples;
  }
  EXPECT_EQ(counted, kSamples);
  EXPECT_NEAR(vmax, 9000, 1e-3);
  EXPECT_NEAR(vmin, 6000, 1e-3);
  EXPECT_TRUE(found);
}

TEST(ReportObserver, CornerAndEndOfProgram) {
  // Lines 2-4: a square's three sides at F6000; 90° corners between them. Both acc/dec types:
  // the moving average stops at the corners and creeps into the end point, the acceleration
  // type passes the corners at Vg and lands on the end point with one step ≤ Amax·τ².
  const fs::path program =
      write_program("corner.ngc", "G21 G90 G17\nG1 X50 F6000\nG1 Y50\nG1 X0\nM2\n");
  const MachineConfig m = default_machine_config();
  // Standstill in cycles: the last step before rest is at most what one cycle at Amax takes
  // away, Amax·τ² (2 µm, i.e. 120 mm/min, on the built-in machine).
  const double stop_step_mm = m.max_accel_mm_s2 * m.period_s * m.period_s;
  for (const motion::AccDecType accdec :
       {motion::AccDecType::kMovingAverage, motion::AccDecType::kAcceleration}) {
    SCOPED_TRACE(accdec == motion::AccDecType::kAcceleration ? "acceleration" : "moving_average");
    const auto r = run(program, 100, accdec);
    const ReportSlowSpot* s3 = spot(r->report, 3);
    ASSERT_NE(s3, nullptr);
    EXPECT_NE(s3->why.find("corner 90° from the previous line"), std::string::npos) << s3->why;
    const ReportSlowSpot* s4 = spot(r->report, 4);
    ASSERT_NE(s4, nullptr);
    EXPECT_NE(s4->why.find("stop at the end of the program"), std::string::npos) << s4->why;
    // The slowest cycle of line 4 is at a standstill at one of its ends: the end point X 0 Y 50
    // (the acceleration type lands there with a step ≤ Amax·τ²), or its start X 50 Y 50
    // where the moving average stops for the corner — not somewhere along the line.
    EXPECT_GE(s4->min_speed_mm_min, 0);
    EXPECT_LE(s4->min_speed_mm_min, stop_step_mm / m.period_s * 60);
    EXPECT_NEAR(s4->y_mm, 50, stop_step_mm);
    EXPECT_LE(std::min(std::fabs(s4->x_mm), std::fabs(s4->x_mm - 50)), stop_step_mm) << s4->x_mm;
    EXPECT_DOUBLE_EQ(s4->target_mm_min, 6000);
    // Time lost cannot exceed the time spent on the line.
    for (const ReportSlowSpot& s : r->report.slowest()) EXPECT_LE(s.lost_s, s.time_s + 1e-12);
  }
}

// At slow feeds 2 % of F is below the last step a sampled stop may land with (Amax·τ = 120
// mm/min here): the end of the program is still named as a stop.
TEST(ReportObserver, EndOfProgramIsNamedAtSlowFeedsToo) {
  for (const int feed : {1000, 500}) {
    const fs::path program = write_program(
        "slow.ngc", fmt::format("G21 G90 G17\nG1 X50 F{}\nG1 Y50\nG1 X0\nM2\n", feed));
    for (const motion::AccDecType accdec :
         {motion::AccDecType::kMovingAverage, motion::AccDecType::kAcceleration}) {
      SCOPED_TRACE(fmt::format(
          "F{} {}", feed,
          accdec == motion::AccDecType::kAcceleration ? "acceleration" : "moving_average"));
      const auto r = run(program, 100, accdec);
      const ReportSlowSpot* s4 = spot(r->report, 4);
      ASSERT_NE(s4, nullptr);
      EXPECT_NE(s4->why.find("stop at the end of the program"), std::string::npos) << s4->why;
    }
  }
}

TEST(ReportObserver, SmallArcIsLimitedByNormalAcceleration) {
  // A tangent quarter arc of R 1 mm between two lines at F6000: v ≤ √(A·R) = √(2000·1) mm/s
  // = 44.7 mm/s = 2683 mm/min on the built-in machine (A = 2000 mm/s²).
  const auto r =
      run(write_program("arc.ngc", "G21 G90 G17\nG1 X10 F6000\nG3 X11 Y1 I0 J1\nG1 Y30\nM2\n"));
  const ReportSlowSpot* s = spot(r->report, 3);
  ASSERT_NE(s, nullptr);
  EXPECT_NE(s->why.find("arc R 1 mm: v ≤ √(A·R) = 2683 mm/min"), std::string::npos) << s->why;
  EXPECT_EQ(s->why.find("corner"), std::string::npos) << "the arc is tangent: " << s->why;
  EXPECT_LE(s->min_speed_mm_min, 2683 * 1.01);
  EXPECT_GT(s->min_speed_mm_min, 1000);
}

TEST(ReportObserver, OverrideIsNamedAndShown) {
  const auto r = run(write_program("ovr.ngc", "G21 G90 G17\nG1 X50 F6000\nG1 Y50\nM2\n"), 50);
  EXPECT_TRUE(r->report.has_override());
  EXPECT_FALSE(r->report.has_correction());
  EXPECT_FALSE(r->report.has_load());
  const ReportSlowSpot* s = spot(r->report, 3);
  ASSERT_NE(s, nullptr);
  EXPECT_NE(s->why.find("feed override 50 %"), std::string::npos) << s->why;
  EXPECT_DOUBLE_EQ(s->target_mm_min, 3000);  // F6000 × 50 %
}

TEST(ReportObserver, ShortSegmentsCannotReachTheFeed) {
  // 0.5 mm zig-zag at F6000, stop mode: between stops v ≤ √(A·L) = √(2000·0.5) mm/s = 1897
  // mm/min.
  std::string prog = "G21 G90 G17\n";
  for (int i = 1; i <= 20; ++i) prog += "G1 X" + std::to_string(i * 0.5) + " F6000\n";
  prog += "M2\n";
  const MachineConfig m = default_machine_config();
  ReportObserver rep(m, "stop");
  sim::RunOptions o;
  o.kernel.mode = motion::Mode::kStop;
  sim::run_program(write_program("short.ngc", prog).string(), m, o, {&rep});
  const auto slow = rep.slowest();
  ASSERT_EQ(slow.size(), 10u);
  for (const ReportSlowSpot& s : slow) {
    EXPECT_NE(s.why.find("short segment 0.5 mm"), std::string::npos) << s.why;
    EXPECT_NE(s.why.find("1897 mm/min"), std::string::npos) << s.why;
  }
}

TEST(ReportHtml, OneMillionSamplesGiveABoundedPageFast) {
  const MachineConfig m = default_machine_config();
  ReportObserver r(m, "lookahead");
  SummaryObserver summary(m, "lookahead");
  const fs::path prog = write_program("x.ngc", "G1 X100000 F6000\n");
  Block b;
  b.kind = BlockKind::kLine;
  b.line = 1;
  b.end[0] = 100000;
  b.feed_mm_min = 6000;
  r.on_block(b);
  const auto t0 = std::chrono::steady_clock::now();
  for (std::uint64_t k = 0; k < 1'000'000; ++k) r.on_sample(line_sample(k, 500'000));
  r.on_finish();
  const std::string html = render_report_html(r, summary.summary(), m, {prog.string(), "", {}});
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(html.size(), 2'000'000u);
  EXPECT_LT(s, 10.0);  // ~0.3 s optimised; generous for the sanitizer build
  EXPECT_NE(html.find("<title>cncore report: x.ngc</title>"), std::string::npos);
  EXPECT_NE(html.find("uPlot"), std::string::npos);
  // Nothing in the inlined library or the data ends a script early: exactly our 5 blocks (error
  // hooks, uPlot, chart helpers, data, page).
  std::size_t scripts = 0;
  for (std::size_t p = html.find("</script"); p != std::string::npos;
       p = html.find("</script", p + 1)) {
    ++scripts;
  }
  EXPECT_EQ(scripts, 5u);
  // The program line is quoted in the table of slow lines.
  EXPECT_NE(html.find("<code>G1 X100000 F6000</code>"), std::string::npos);
}

TEST(ReportHtml, MergedPiecesAreNamedByTheirOwnLines) {
  // 1 mm along X in 10 pieces (lines 2–11) that the planner merges into one line, then a 90°
  // corner (its own line): the slow spots are the program's own lines, the pieces one by one.
  std::string prog = "G21 G90 F3000\n";
  for (int i = 1; i <= 10; ++i) prog += fmt::format("G1 X{:.1f}\n", 0.1 * i);
  prog += "G1 Y1\nM2\n";
  const fs::path path = write_program("merged.ngc", prog);
  const auto r = run(path);
  const std::vector<ReportSlowSpot> slow = r->report.slowest();
  ASSERT_GE(slow.size(), 3u);
  bool corner = false;
  for (const ReportSlowSpot& s : slow) {
    EXPECT_GE(s.line, 2u);
    EXPECT_LE(s.line, 12u);
    EXPECT_EQ(s.last_line, 0u);
    corner = corner || s.line == 12;
  }
  EXPECT_TRUE(corner);
  const std::string html = render_report_html(r->report, r->summary.summary(),
                                              default_machine_config(), {path.string(), "", {}});
  EXPECT_NE(html.find("<td class=\"num\">12</td><td><code>G1 Y1</code></td>"), std::string::npos);
  EXPECT_EQ(html.find("collinear lines run as one"), std::string::npos);
}

TEST(ReportHtml, Base64OfTheRfcVectors) {
  EXPECT_EQ(page::base64(""), "");
  EXPECT_EQ(page::base64("f"), "Zg==");
  EXPECT_EQ(page::base64("fo"), "Zm8=");
  EXPECT_EQ(page::base64("foo"), "Zm9v");
  EXPECT_EQ(page::base64("foob"), "Zm9vYg==");
  EXPECT_EQ(page::base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(page::base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(page::base64(std::string("\xff\x00\xfe", 3)), "/wD+");
}

TEST(ReportHtml, HeightMapIsInlinedWithItsScale) {
  const MachineConfig m = default_machine_config();
  const fs::path prog = write_program("hm.ngc", "G21 G90\nG1 X10 F6000\nM2\n");
  ReportObserver r(m, "lookahead");
  SummaryObserver summary(m, "lookahead");
  sim::run_program(prog.string(), m, {}, {&r, &summary});
  ReportInput input{
      prog.string(), "", {"foobar", -12.5, 0, {"rgb(20,30,110)", "rgb(240,235,210)"}}};
  const std::string html = render_report_html(r, summary.summary(), m, input);
  EXPECT_NE(html.find("src=\"data:image/png;base64,Zm9vYmFy\""), std::string::npos);
  EXPECT_NE(html.find("linear-gradient(to top,rgb(20,30,110),rgb(240,235,210))"),
            std::string::npos);
  EXPECT_NE(html.find("Z 0.000 mm"), std::string::npos);
  EXPECT_NE(html.find("Z -12.500 mm"), std::string::npos);
  // Without a map, no section.
  const std::string plain = render_report_html(r, summary.summary(), m, {prog.string(), "", {}});
  EXPECT_EQ(plain.find("id=\"heightmap\""), std::string::npos);
}

TEST(ReportHtml, ProgramTextIsEscaped) {
  const MachineConfig m = default_machine_config();
  const fs::path prog =
      write_program("esc.ngc", "G21 G90\nG1 X10 F6000 (a <b> & \"c\" </script>)\nM2\n");
  ReportObserver r(m, "lookahead");
  SummaryObserver summary(m, "lookahead");
  sim::run_program(prog.string(), m, {}, {&r, &summary});
  const std::string html =
      render_report_html(r, summary.summary(), m, {prog.string(), "T <x>", {}});
  EXPECT_NE(html.find("<title>T &lt;x&gt;</title>"), std::string::npos);
  EXPECT_NE(html.find("(a &lt;b&gt; &amp; &quot;c&quot; &lt;/script&gt;)"), std::string::npos);
}

}  // namespace
}  // namespace cncore::io
