// Summary maths on hand-made sample sequences whose speeds and accelerations are known in closed
// form (worked out in the comments), plus the JSON keys of spec 05.
#include "io/summary.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <nlohmann/json.hpp>

#include "test_dir.hpp"

namespace cncore::io {
namespace {

constexpr double kTau = 0.001;

motion::Sample at(double t, std::uint32_t line, Vec3 p) {
  motion::Sample s;
  s.t_s = t;
  s.line = line;
  s.position.set_xyz(p);
  s.path_position = s.position;
  return s;
}

Block line_block(std::uint32_t line, double feed) {
  Block b;
  b.kind = BlockKind::kLine;
  b.line = line;
  b.feed_mm_min = feed;
  return b;
}

// Constant acceleration a = 1000 mm/s² from rest along (3, 4, 0)/5 for 0.1 s (101 samples):
// s(t) = a t²/2. Second differences of a quadratic are exact: tangential 1000, X 600, Y 800.
// Path length s(0.1) = 5 mm; the fastest interval is the last one,
// (s(0.1) − s(0.099))/τ = 500·(0.01 − 0.009801)/0.001 = 99.5 mm/s = 5970 mm/min.
TEST(Summary, ConstantAccelerationIsMeasuredExactly) {
  SummaryObserver obs(default_machine_config(), "lookahead");
  const Vec3 dir{0.6, 0.8, 0};
  for (int k = 0; k <= 100; ++k) {
    const double t = k * kTau;
    obs.on_sample(at(t, 1, (0.5 * 1000 * t * t) * dir));
  }
  obs.on_finish();
  const Summary& s = obs.summary();
  EXPECT_EQ(s.cycles, 101u);
  EXPECT_NEAR(s.cycle_time_s, 0.1, 1e-12);
  EXPECT_NEAR(s.path_length_mm, 5.0, 1e-9);
  EXPECT_NEAR(s.max_feed_mm_min, 5970.0, 1e-6);
  EXPECT_NEAR(s.max_tangential_accel_mm_s2, 1000.0, 1e-4);
  EXPECT_NEAR(s.max_path_accel_mm_s2, 1000.0, 1e-4);
  EXPECT_NEAR(s.max_axis_accel_mm_s2[kX], 600.0, 1e-4);
  EXPECT_NEAR(s.max_axis_accel_mm_s2[kY], 800.0, 1e-4);
  EXPECT_EQ(s.max_axis_accel_mm_s2[kZ], 0.0);
  EXPECT_NEAR(s.max_axis_speed_mm_min[kY], 0.8 * 5970.0, 1e-6);
  EXPECT_EQ(s.max_contour_error_mm, 0.0);
  EXPECT_TRUE(s.warnings.empty());
}

// Uniform circle R = 10 mm at v = 100 mm/s: ω = 10 rad/s, ωτ = 0.01. Chord 2R·sin(ωτ/2), so the
// measured speed is 20·sin(0.005)/τ = 99.99958 mm/s; second difference 4R·sin²(ωτ/2)/τ² =
// 999.9917 mm/s² (= v²/R up to O((ωτ)²)); the speed is constant, so tangential ≈ 0.
TEST(Summary, UniformCircleHasNormalButNoTangentialAcceleration) {
  SummaryObserver obs(default_machine_config(), "lookahead");
  const int n = 700;  // > one full turn (628 cycles)
  for (int k = 0; k < n; ++k) {
    const double phi = 10.0 * k * kTau;
    obs.on_sample(at(k * kTau, 5, {10 * std::cos(phi), 10 * std::sin(phi), -1}));
  }
  obs.on_finish();
  const Summary& s = obs.summary();
  const double chord = 20 * std::sin(0.005);
  EXPECT_NEAR(s.max_feed_mm_min, chord / kTau * 60, 1e-6);
  EXPECT_NEAR(s.path_length_mm, (n - 1) * chord, 1e-9);
  const double a = 40 * std::sin(0.005) * std::sin(0.005) / (kTau * kTau);
  EXPECT_NEAR(a, 999.9917, 1e-4);
  EXPECT_NEAR(s.max_path_accel_mm_s2, a, 1e-4);
  // Per axis a·|cos φ| (X) and a·|sin φ| (Y) at the samples φ = 0.01·k; the nearest samples to
  // φ = π and φ = π/2 miss by 0.0016 and 0.0008 rad, so the maxima are a·(1 − 1.3e-6) and
  // a·(1 − 3e-7).
  EXPECT_NEAR(s.max_axis_accel_mm_s2[kX], a * std::fabs(std::cos(3.14)), 1e-6);
  EXPECT_NEAR(s.max_axis_accel_mm_s2[kY], a * std::sin(1.57), 1e-6);
  EXPECT_LT(s.max_tangential_accel_mm_s2, 1e-3);
}

// The servo set-point lags 5 cycles behind on a straight path and sits 0.003 mm beside it: the
// contour error is the 0.003 mm beside the path, not the 0.5 mm lag along it.
TEST(Summary, ContourErrorIsTheDistanceToThePathNotTheLag) {
  SummaryObserver obs(default_machine_config(), "lookahead");
  for (int k = 0; k < 100; ++k) {
    motion::Sample s;
    s.t_s = k * kTau;
    s.line = 1;
    s.path_position[kX] = 0.1 * k;  // 100 mm/s
    s.position[kX] = 0.1 * std::max(0, k - 5);
    s.position[kY] = k >= 10 ? 0.003 : 0;
    obs.on_sample(s);
  }
  obs.on_finish();
  EXPECT_NEAR(obs.summary().max_contour_error_mm, 0.003, 1e-12);
  // The lag itself: 5 cycles · 0.1 mm beside 0.003 mm, √(0.5² + 0.003²).
  EXPECT_NEAR(obs.summary().max_servo_lag_mm, std::hypot(0.5, 0.003), 1e-12);
}

// Three lines at F6000 (100 mm/s). Line 10 runs 1 s at 50 mm/s: lost 1·(1 − 50/100) = 0.5 s.
// Line 20 runs at 50 mm/s with override 50 %: the target is 3000 mm/min, nothing lost.
// Line 30 runs 0.2 s at 75 mm/s: lost 0.2·0.25 = 0.05 s.
TEST(Summary, SlowestSpotsRankTimeLostAgainstTheProgrammedFeed) {
  SummaryObserver obs(default_machine_config(), "lookahead");
  obs.on_block(line_block(10, 6000));
  obs.on_block(line_block(20, 6000));
  obs.on_block(line_block(30, 6000));
  double t = 0, x = 0;
  obs.on_sample(at(t, 0, {x, 0, 0}));
  auto run = [&](std::uint32_t line, int cycles, double v_mm_s, double override_pct) {
    for (int k = 0; k < cycles; ++k) {
      t += kTau;
      x += v_mm_s * kTau;
      motion::Sample s = at(t, line, {x, 0, 0});
      s.override_pct = override_pct;
      obs.on_sample(s);
    }
  };
  run(10, 1000, 50, 100);
  run(20, 500, 50, 50);
  run(30, 200, 75, 100);
  obs.on_finish();
  const Summary& s = obs.summary();
  ASSERT_EQ(s.slowest.size(), 2u);
  EXPECT_EQ(s.slowest[0].line, 10u);
  EXPECT_NEAR(s.slowest[0].lost_s, 0.5, 1e-9);
  EXPECT_NEAR(s.slowest[0].time_s, 1.0, 1e-9);
  EXPECT_NEAR(s.slowest[0].average_feed_mm_min(), 3000, 1e-6);
  EXPECT_NEAR(s.slowest[0].programmed_feed_mm_min, 6000, 1e-9);
  EXPECT_EQ(s.slowest[1].line, 30u);
  EXPECT_NEAR(s.slowest[1].lost_s, 0.05, 1e-9);
  EXPECT_EQ(s.blocks, 3u);
}

// A line merged from collinear pieces 10…14 (planner/line_merge) runs as one kernel block whose
// samples carry line 10: the spot names the whole range, in the text and the JSON.
TEST(Summary, AMergedLineIsReportedAsTheRangeOfItsSourceLines) {
  SummaryObserver obs(default_machine_config(), "lookahead");
  Block merged = line_block(10, 6000);
  merged.last_line = 14;
  obs.on_block(merged);
  obs.on_block(line_block(20, 6000));
  double t = 0, x = 0;
  obs.on_sample(at(t, 0, {x, 0, 0}));
  for (std::uint32_t line : {10u, 20u}) {
    for (int k = 0; k < 100; ++k) {
      t += kTau;
      x += (line == 10 ? 25.0 : 50.0) * kTau;  // line 10…14 at half its F6000 (100 mm/s)
      obs.on_sample(at(t, line, {x, 0, 0}));
    }
  }
  obs.on_finish();
  const Summary& s = obs.summary();
  ASSERT_EQ(s.slowest.size(), 2u);
  EXPECT_EQ(s.slowest[0].line, 10u);
  EXPECT_EQ(s.slowest[0].last_line, 14u);
  EXPECT_NEAR(s.slowest[0].lost_s, 0.1 * 0.75, 1e-9);
  EXPECT_EQ(s.slowest[1].line, 20u);
  EXPECT_EQ(s.slowest[1].last_line, 0u);
  const std::string text = format_human_summary(s, default_machine_config(), "p.ngc");
  EXPECT_NE(text.find("lines 10-14 "), std::string::npos) << text;
  EXPECT_NE(text.find("line 20 "), std::string::npos) << text;
  const auto j = nlohmann::json::parse(summary_to_json(s, default_machine_config()));
  EXPECT_EQ(j["slowest_spots"][0]["line"], 10);
  EXPECT_EQ(j["slowest_spots"][0]["last_line"], 14);
  EXPECT_EQ(j["slowest_spots"][1]["last_line"], 20);  // a single line: its own
}

// A loop executes line 7 twice (with line 8 between): both passes add up on one entry.
// Each pass of line 7: 100 cycles at 25 mm/s against F3000 (50 mm/s): lost 0.1·0.5 = 0.05 s.
TEST(Summary, RepeatedLinesAddUp) {
  SummaryObserver obs(default_machine_config(), "lookahead");
  double t = 0, x = 0;
  obs.on_sample(at(t, 0, {0, 0, 0}));
  auto pass = [&](std::uint32_t line, double feed, double v_mm_s) {
    obs.on_block(line_block(line, feed));
    for (int k = 0; k < 100; ++k) {
      t += kTau;
      x += v_mm_s * kTau;
      obs.on_sample(at(t, line, {x, 0, 0}));
    }
  };
  pass(7, 3000, 25);
  pass(8, 3000, 50);
  pass(7, 3000, 25);
  obs.on_finish();
  const Summary& s = obs.summary();
  ASSERT_EQ(s.slowest.size(), 1u);
  EXPECT_EQ(s.slowest[0].line, 7u);
  EXPECT_EQ(s.slowest[0].visits, 2u);
  EXPECT_NEAR(s.slowest[0].lost_s, 0.1, 1e-9);
  EXPECT_NEAR(s.slowest[0].time_s, 0.2, 1e-9);
}

// A 90° corner (at 1 mm along X, then along Y) passed at a constant 0.1 mm per cycle, the
// corner 0.07 mm after a sample: the chord across it is shorter than the step along the path.
// Measured by the chord the speed dips (a tangential acceleration of thousands of mm/s²); with the
// kernel's path speed on the path it is 0. A recorded trajectory without speeds keeps the chord's
// measure.
TEST(Summary, TangentialAccelerationFollowsThePathAcrossACorner) {
  auto run = [](bool with_speed) {
    SummaryObserver obs(default_machine_config(), "lookahead");
    const double u = 0.1;  // mm per cycle: 100 mm/s
    for (int k = 0; k <= 40; ++k) {
      const double s_mm = 1.03 + u * (k - 20);  // path position: sample 19 at 0.93, 20 at 1.03
      const Vec3 p = s_mm <= 1.0 ? Vec3{s_mm, 0, 0} : Vec3{1.0, s_mm - 1.0, 0};
      motion::Sample smp = at(k * kTau, 1, p);
      if (with_speed) smp.feed_mm_min = k == 0 ? 0.0 : u / kTau * 60;
      obs.on_sample(smp);
    }
    obs.on_finish();
    return obs.summary().max_tangential_accel_mm_s2;
  };
  EXPECT_LT(run(true), 1e-6);
  EXPECT_GT(run(false), 1000.0);
}

TEST(Summary, WarnsOnTravelAndLimitViolations) {
  SummaryObserver obs(default_machine_config(), "stop");
  // X jumps to 301 mm (beyond +300) with a huge acceleration.
  obs.on_sample(at(0, 1, {299, 0, 0}));
  obs.on_sample(at(kTau, 1, {299, 0, 0}));
  obs.on_sample(at(2 * kTau, 1, {301, 0, 0}));
  obs.on_finish();
  const auto& w = obs.summary().warnings;
  auto has = [&](const std::string& frag) {
    for (const auto& s : w) {
      if (s.find(frag) != std::string::npos) return true;
    }
    return false;
  };
  EXPECT_TRUE(has("axis X leaves its travel")) << ::testing::PrintToString(w);
  EXPECT_TRUE(has("axis X acceleration"));
  EXPECT_TRUE(has("tangential acceleration"));
  EXPECT_TRUE(has("path speed"));
}

TEST(Summary, JsonHasTheSpecKeys) {
  SummaryObserver obs(default_machine_config(), "lookahead");
  for (int k = 0; k <= 100; ++k) {
    const double t = k * kTau;
    obs.on_sample(at(t, 1, {0, 0, -0.5 * 1000 * t * t}));
  }
  obs.on_finish();
  const auto j = nlohmann::json::parse(summary_to_json(obs.summary(), default_machine_config()));
  for (const char* key :
       {"cycle_time_s", "blocks", "path_length_mm", "max_feed_mm_min", "max_tangential_accel_mm_s2",
        "max_axis_accel_mm_s2", "max_contour_error_mm", "mode", "cycles", "warnings"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["mode"], "lookahead");
  EXPECT_EQ(j["cycles"], 101);
  EXPECT_TRUE(j["warnings"].is_array());
  const auto& axes = j["max_axis_accel_mm_s2"];
  EXPECT_EQ(axes.size(), 3u);
  EXPECT_NEAR(axes["z"].get<double>(), 1000, 1e-4);
  EXPECT_EQ(axes["x"].get<double>(), 0.0);

  const auto dir = test::fresh_dir();
  write_summary_json((dir / "s.json").string(), obs.summary(), default_machine_config());
  EXPECT_EQ(nlohmann::json::parse(test::slurp(dir / "s.json")), j);
  EXPECT_EQ(test::list_dir(dir), std::vector<std::string>{"s.json"});
}

// The summary keeps the accelerations only as maxima and divides only when a quotient can raise
// one (raise_max_quotient in summary.cpp). Its maxima must be the very doubles of taking the max
// of every cycle's FiniteDifferences::update(): a random walk with jumps, stalls, cycles that
// repeat the last acceleration (the early-return case), uneven sample times and a rotary axis.
TEST(Summary, AccelerationMaximaAreBitIdenticalToDividingEveryCycle) {
  MachineConfig m = default_machine_config();
  m.axes[kA].enabled = true;
  m.axes[kA].rotary = true;
  m.axes[kA].min_mm = -1e9;
  m.axes[kA].max_mm = 1e9;
  SummaryObserver obs(m, "lookahead");
  FiniteDifferences ref(m);
  std::array<double, kMaxAxes> axis{};
  double path = 0, tangential = 0;
  std::uint64_t state = 12345;
  auto uniform = [&state] {  // xorshift64*: reproducible, in [0, 1)
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return static_cast<double>((state * 2685821657736338717ull) >> 11) * 0x1.0p-53;
  };
  AxisVec p, v;
  double t = 0;
  for (int k = 0; k < 20000; ++k) {
    const double r = uniform();
    if (r < 0.05) {
      v = AxisVec{};  // stop
    } else if (r < 0.10) {
      for (std::size_t i = 0; i < 4; ++i) v[i] = 200 * (uniform() - 0.5);  // jump
    } else if (r < 0.6) {
      for (std::size_t i = 0; i < 4; ++i) v[i] += 1e-3 * (uniform() - 0.5);  // small change
    }  // else: the same velocity again
    t += kTau * (r < 0.01 ? 2.0 : 1.0) * (1 + 1e-9 * uniform());
    p = p + kTau * v;
    motion::Sample s = at(t, 1, p.xyz());
    s.position[kA] = p[kA];
    s.path_position = s.position;
    obs.on_sample(s);
    const CycleDifferences& d = ref.update(t, s.position);
    if (!d.accel) continue;
    for (std::size_t i = 0; i < kMaxAxes; ++i) axis[i] = std::max(axis[i], std::fabs(d.acc[i]));
    path = std::max(path, d.path_accel_mm_s2);
    tangential = std::max(tangential, std::fabs(d.tangential_accel_mm_s2));
  }
  const Summary& s = obs.summary();
  ASSERT_GT(path, 0.0);
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    EXPECT_EQ(s.max_axis_accel_mm_s2[i], axis[i]) << "axis " << i;
  }
  EXPECT_EQ(s.max_path_accel_mm_s2, path);
  EXPECT_EQ(s.max_tangential_accel_mm_s2, tangential);
}

// The queue of pending blocks against std::deque through growth and wrap-around.
TEST(GrowingFifo, BehavesLikeADeque) {
  GrowingFifo<int> fifo(5);  // grows from 5 (not a power of two)
  std::deque<int> ref;
  int next = 0;
  for (int round = 0; round < 2000; ++round) {
    const int pushes = round % 7 == 0 ? 150 : round % 3;
    for (int i = 0; i < pushes; ++i) {
      fifo.push_back(next);
      ref.push_back(next);
      ++next;
    }
    const std::size_t drop = std::min<std::size_t>(ref.size(), round % 5 == 0 ? 40 : 1);
    fifo.drop_front(drop);
    ref.erase(ref.begin(), ref.begin() + static_cast<std::ptrdiff_t>(drop));
    ASSERT_EQ(fifo.size(), ref.size());
    ASSERT_EQ(fifo.empty(), ref.empty());
    for (std::size_t j = 0; j < ref.size(); j += 17) ASSERT_EQ(fifo[j], ref[j]);
    if (!ref.empty()) {
      ASSERT_EQ(fifo.front(), ref.front());
      ASSERT_EQ(fifo.back(), ref.back());
    }
  }
}

}  // namespace
}  // namespace cncore::io
