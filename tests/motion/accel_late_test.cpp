// Late blocks with a filter after the acceleration-limited type (accel_limited_late.cpp, 6.;
// accel_limited.cpp, 8.). A block is *late* when the producer delivers it only after the tool has
// started to brake for the window's last end point (a stop until its successor arrives). With a
// jerk stage (T2) and/or the post-interpolation filter (Tp) the output averages the commanded steps
// of the last lag = T2 + Tp cycles, so the caps of the late block (a corner, a slower feed, an arc)
// reach lag·V behind their position — possibly behind the commanded position, over steps that are
// already in the filter. Without a filter too (the first filter of each sweep; 6.): a late cap's
// key may bind below the braking tool's step. Everything is measured on the produced positions by
// the independent checker (tests/support): path speed and joint speed, tangential/normal/per-axis
// acceleration, tangential jerk, distance to the programmed path, end point.
#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "limits.hpp"
#include "motion_test_util.hpp"
#include "program_gen_rc.hpp"
#include "trajectory_checker.hpp"

namespace cncore::motion::test {
namespace {

constexpr double kPi = std::numbers::pi;

// Runs the kernel with block i available from cycle ready[i] on (non-decreasing): until then
// the window ends at the last block pushed, and the kernel brakes for it as for a stop.
RunResult run_late(const MachineConfig& m, const std::vector<Block>& blocks,
                   const std::vector<std::uint64_t>& ready, std::uint64_t max_cycles = 2'000'000) {
  RunResult r;
  KernelOptions ko;
  ko.accdec = AccDecType::kAcceleration;
  ko.check_reference_walk = true;
  Kernel k(m, ko);
  std::size_t next = 0;
  Sample s;
  r.traj.period_s = m.period_s;
  for (std::uint64_t c = 0; c < max_cycles; ++c) {
    while (next < blocks.size() && ready[next] <= c && k.wants_block()) k.push(blocks[next++]);
    if (next == blocks.size()) k.end_of_program();
    if (!k.step(s)) break;
    r.samples.push_back(s);
    r.traj.add_sample(s);
  }
  r.mismatches = k.reference_mismatches();
  return r;
}

// The output's braking ramp for the end of the first `n` blocks when nothing follows them:
// the last cycle at top speed and the first cycle at rest after it (sample indices).
struct Ramp {
  std::uint64_t brake = 0, stop = 0;
};
Ramp braking_ramp(const MachineConfig& m, const std::vector<Block>& blocks, std::size_t n) {
  const std::vector<Block> head(blocks.begin(), blocks.begin() + static_cast<std::ptrdiff_t>(n));
  // Never ends (no end_of_program): step until well after the tool has come to rest.
  KernelOptions ko;
  ko.accdec = AccDecType::kAcceleration;
  Kernel k(m, ko);
  for (const Block& b : head) k.push(b);
  std::vector<double> feed;
  Sample s;
  std::uint64_t still = 0;
  for (std::uint64_t c = 0; c < 1'000'000 && still < 50; ++c) {
    k.step(s);
    feed.push_back(s.feed_mm_min);
    still = (c > 2 && s.feed_mm_min == 0) ? still + 1 : 0;
  }
  Ramp r;
  const double top = *std::max_element(feed.begin(), feed.end());
  for (std::uint64_t i = 0; i < feed.size(); ++i) {
    if (feed[i] >= 0.999 * top) r.brake = i;
  }
  r.stop = r.brake;
  while (r.stop < feed.size() && feed[r.stop] > 0) ++r.stop;
  return r;
}

// Arrival cycles over the braking for the window's end: before the output brakes (the
// commanded position brakes up to lag cycles earlier), along the output's ramp, at its end and
// after the output has come to rest (the post filter still settling).
std::vector<std::uint64_t> arrival_points(const Ramp& r, std::uint64_t lag) {
  std::vector<std::uint64_t> out;
  if (r.brake > lag) out.push_back(r.brake - lag);
  if (r.brake > lag / 2) out.push_back(r.brake - lag / 2);
  const double len = static_cast<double>(r.stop - r.brake);
  for (double f : {0.0, 0.25, 0.5, 0.75, 0.9, 0.95, 0.98, 1.0}) {
    out.push_back(r.brake + static_cast<std::uint64_t>(std::lround(f * len)));
  }
  out.push_back(r.stop + 2);
  out.push_back(r.stop + lag + 2);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

struct Filter {
  double jerk_mm_s3 = 0;
  double post_s = 0;
};
std::string name(const Filter& f) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "J %g post %g s", f.jerk_mm_s3, f.post_s);
  return buf;
}

MachineConfig machine_for(const Filter& f, bool slow_axes = false) {
  MachineConfig m = test_machine();
  if (slow_axes) {
    m.axes[kX].max_accel_mm_s2 = 1500;
    m.axes[kY].max_accel_mm_s2 = 800;
  } else {
    // Every axis at Amax (the built-in machine's way): a corner's turn uses the axis budget.
    for (std::size_t i = 0; i < 3; ++i) m.axes[i].max_accel_mm_s2 = m.max_accel_mm_s2;
  }
  m.max_jerk_mm_s3 = f.jerk_mm_s3;
  m.post_filter_s = f.post_s;
  m.lookahead_blocks = 64;  // short programs; the reference walk runs over every cap slot
  return m;
}

std::uint64_t lag_cycles(const MachineConfig& m) {
  const double t2 = m.max_jerk_mm_s3 > 0
                        ? std::ceil(2 * m.max_accel_mm_s2 / (m.max_jerk_mm_s3 * m.period_s))
                        : 0.0;
  return static_cast<std::uint64_t>(t2 + std::lround(m.post_filter_s / m.period_s));
}

// The filters of these tests: jerk stages of 200, 40 and 4 cycles, post filters of 8 and 16.
const Filter kFilters[] = {{0, 0},      {0, 0.008}, {0, 0.016},      {20000, 0},
                           {100000, 0}, {1e6, 0},   {100000, 0.008}, {20000, 0.016}};

struct LateResult {
  testing::CheckReport rep;
  RunResult run;
};

// Runs `blocks` with blocks [n, end) arriving at cycle `at` (the first n at once) and checks
// every limit with the checker's 0.5 % margin, the reference walk and the exact end point.
LateResult run_checked_late(const MachineConfig& m, const std::vector<Block>& blocks, std::size_t n,
                            std::uint64_t at, const std::string& what) {
  std::vector<std::uint64_t> ready(blocks.size(), 0);
  for (std::size_t i = n; i < blocks.size(); ++i) ready[i] = at;
  LateResult out{{}, run_late(m, blocks, ready)};
  const auto lim = testing::limits_from_config(m);
  out.rep = testing::check_trajectory(out.run.traj, blocks, lim);
  const std::string where = what + ", arriving at cycle " + std::to_string(at);
  EXPECT_TRUE(out.rep.ok()) << where << ": " << out.rep.summary();
  EXPECT_EQ(out.run.mismatches, 0u) << where;
  if (m.max_jerk_mm_s3 > 0) {
    EXPECT_LE(out.rep.max_tangential_jerk_mm_s3, m.max_jerk_mm_s3 * 1.005) << where;
  }
  EXPECT_LE(out.rep.max_tangential_accel_mm_s2, m.max_accel_mm_s2 * 1.005) << where;
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_LE(out.rep.max_axis_accel_mm_s2[i], m.axes[i].max_accel_mm_s2 * 1.005)
        << where << ", axis " << i;
  }
  EXPECT_LE(out.rep.max_path_error_mm, lim.path_tolerance_mm * 1.005) << where;
  const AxisVec end = blocks.back().end;
  EXPECT_FALSE(out.run.samples.empty()) << where;
  if (!out.run.samples.empty()) {
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_NEAR(out.run.samples.back().position[i], end[i], 1e-9) << where << ", axis " << i;
    }
    EXPECT_EQ(out.run.samples.back().feed_mm_min, 0.0) << where;
  }
  return out;
}

// For each filter: the first n blocks, then the rest arriving late at every point of the
// braking ramp for the end of block n.
void sweep_late(const Prog& p, std::size_t n, const std::string& what, bool slow_axes = false) {
  for (const Filter& f : kFilters) {
    const MachineConfig m = machine_for(f, slow_axes);
    const Ramp ramp = braking_ramp(m, p.blocks, n);
    ASSERT_GT(ramp.stop, ramp.brake) << what << ", " << name(f);
    for (std::uint64_t at : arrival_points(ramp, lag_cycles(m))) {
      run_checked_late(m, p.blocks, n, at, what + ", " + name(f));
    }
  }
}

// A shrunk case of the property below: its own arrival cycles (`ready`, one per block), checked
// for every limit and the reference walk.
testing::CheckReport check_arrivals(const MachineConfig& m, const std::vector<Block>& blocks,
                                    const std::vector<std::uint64_t>& ready) {
  const RunResult r = run_late(m, blocks, ready);
  const auto rep = testing::check_trajectory(r.traj, blocks, testing::limits_from_config(m));
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_EQ(r.mismatches, 0u);
  return rep;
}

// Blocks [n, end) arriving at every cycle of the braking for the end of the first n.
void sweep_braking(const MachineConfig& m, const std::vector<Block>& blocks, std::size_t n,
                   const std::string& what) {
  const Ramp ramp = braking_ramp(m, blocks, n);
  ASSERT_GT(ramp.stop, ramp.brake) << what;
  for (std::uint64_t at = ramp.brake; at <= ramp.stop; ++at) {
    run_checked_late(m, blocks, n, at, what);
  }
}

// A 30 mm line along a diagonal, then a line turned by `deg` (the late block).
Prog corner(double deg, double feed_late = 10000, double len_late = 20) {
  Prog p;
  const double a0 = kPi / 6;
  const double a1 = a0 + deg * kPi / 180;
  p.line_to(Vec3{30 * std::cos(a0), 30 * std::sin(a0), 0}, 10000);
  p.line_to(p.pos.xyz() + Vec3{len_late * std::cos(a1), len_late * std::sin(a1), 0}, feed_late);
  return p;
}

TEST(AccelLate, CornersArrivingLateKeepEveryLimit) {
  for (double deg : {30.0, 90.0, 135.0, 179.0}) {
    sweep_late(corner(deg), 1, "corner " + std::to_string(deg) + " deg");
  }
}

// The same along the axes with slow X and Y (1 500 and 800 mm/s²): the corner's cap is set by
// the slower axis.
TEST(AccelLate, CornersArrivingLateKeepSlowAxisLimits) {
  for (double deg : {30.0, 90.0, 135.0, 179.0}) {
    sweep_late(corner(deg), 1, "slow axes, corner " + std::to_string(deg) + " deg", true);
  }
}

// A slower feed arriving late, straight on and at a 30° corner: the feed cap reaches lag·F
// behind the joint. F60 is 1 µm/cycle, below A0 = 2 µm/cycle² (6.: the tail's last steps).
TEST(AccelLate, SlowerFeedArrivingLateKeepsEveryLimit) {
  for (double feed : {2000.0, 300.0, 60.0}) {
    sweep_late(corner(0, feed), 1, "straight on at F" + std::to_string(feed));
    sweep_late(corner(30, feed), 1, "30 deg at F" + std::to_string(feed));
  }
}

// Arcs: a late arc after a line (tangent, and at a 90° corner), and a late line after an arc.
TEST(AccelLate, ArcsArrivingLateKeepEveryLimit) {
  {
    Prog p;  // tangent: the arc's own speed cap √(R·A) is what arrives late
    p.line_to(Vec3{30, 0, 0}, 10000);
    p.arc_to(Vec3{30, 4, 0}, Vec3{30, 2, 0}, 10000);
    p.line_to(Vec3{0, 4, 0}, 10000);
    sweep_late(p, 1, "tangent R2 arc");
  }
  {
    Prog p;  // a quarter circle entered at 90°
    p.line_to(Vec3{30, 0, 0}, 10000);
    p.arc_to(Vec3{40, 10, 0}, Vec3{40, 0, 0}, 10000);
    sweep_late(p, 1, "arc at a 90 deg corner");
  }
  {
    Prog p;  // an arc, then a line leaving it at 135° arriving late
    p.line_to(Vec3{20, 0, 0}, 10000);
    p.arc_to(Vec3{30, 10, 0}, Vec3{20, 10, 0}, 10000);
    p.line_to(Vec3{30 - 10 * std::cos(kPi / 4), 10 - 10 * std::sin(kPi / 4), 0}, 10000);
    sweep_late(p, 2, "line at 135 deg after an arc");
  }
}

// Found by the property below (no filter, slow X/Y): a 0.1 mm arc in XY, then a helix about X
// (R 0.1 mm, one extra turn) arriving while the tool brakes for the arc's end. The test whether
// the tool is near enough for a late cap to bind looked only lag·V back: with no filter it saw
// nothing, and arriving at cycles 10–20 drove Y to 956 mm/s² (limit 800).
TEST(AccelLate, HelixArrivingLateAfterAShortArcKeepsTheSlowAxis) {
  const MachineConfig m = machine_for(Filter{0, 0}, true);
  Prog p;
  p.arc_to(Vec3{-0.010190036479384323, -0.10582757509949886, 0}, Vec3{-0.55462571295791074, 0, 0},
           6000, Vec3{0, 0, -1});
  p.arc_to(Vec3{-4.0101900364793845, -0.10582757509949886, 0},
           Vec3{-0.010190036479384323, -0.20582757509949887, 0}, 6000, Vec3{1, 0, 0}, 1);
  p.blocks.back().path_mode = PathMode::kExactStop;
  for (std::uint64_t at : {0, 5, 10, 15, 18, 19, 20, 21, 25}) {
    run_checked_late(m, p.blocks, 1, at, "helix after a short arc");
  }
}

// Found by the property below (T2 = 4, slow X/Y): a 1 µm rapid with an exact stop, turned 14°,
// arriving while the tool brakes for the first rapid's end. No cap of it binds, but its joint
// zone (7.) lowers r ahead of the tool, so σ up to the new stop shrank under the braking tool:
// Y 960 mm/s² (limit 800) when it arrived at cycle 60.
TEST(AccelLate, TinyRapidArrivingLateAtAGentleCornerKeepsTheSlowAxis) {
  const MachineConfig m = machine_for(Filter{1e6, 0}, true);
  Prog p;
  p.rapid_to(Vec3{0.40255841794763941, 0.7539249215833751, 0.034825020817244139});
  p.rapid_to(Vec3{0.40317597153530021, 0.7547040802981998, 0.03471759985336853});
  p.blocks.back().path_mode = PathMode::kExactStop;
  for (std::uint64_t at : {0, 40, 50, 55, 58, 59, 60, 61, 62, 65}) {
    run_checked_late(m, p.blocks, 1, at, "tiny rapid at 14 deg");
  }
}

// Found by the property below (no filter): a 1 µm rapid between a near-reversal and an 8° turn,
// the rapid after it arriving while the tool brakes: its joint zone lowered σ ahead of the tool
// and on_joint()'s cap for both corners in one cycle then held the block at the old stop, whose
// bound had dropped: 2 011.7 mm/s² (A 2 000) when it arrived at cycle 5.
TEST(AccelLate, RapidAfterAMicronSegmentArrivingLateKeepsTheLimit) {
  const MachineConfig m = machine_for(Filter{0, 0});
  Prog p;
  p.rapid_to(Vec3{0.019387320112476486, 0, 0});
  p.rapid_to(Vec3{0.018382668887250288, -0.00035774020953447885, -3.6619858409704351e-05});
  p.rapid_to(Vec3{0.0089173622413837358, -0.0024561481732018418, -0.00035259361227054807});
  p.blocks.back().path_mode = PathMode::kExactStop;
  for (std::uint64_t at : {0, 2, 3, 4, 5, 6, 7, 8, 10}) {
    run_checked_late(m, p.blocks, 2, at, "rapid after a 1 um segment");
  }
}

// A held late corner followed by 300 short blocks that arrive while the hold lasts: their caps
// wait and are inserted a bounded number per cycle with the tool at rest (6.), so the release
// takes several cycles; every limit holds and the tool reaches the end.
TEST(AccelLate, ManyBlocksArrivingDuringAHoldAreReleasedOverSeveralCycles) {
  for (const Filter f : {Filter{0, 0}, Filter{20000, 0}, Filter{0, 0.016}}) {
    const MachineConfig m = machine_for(f);
    Prog p = corner(90);
    const double a1 = kPi / 6 + kPi / 2;
    for (int i = 0; i < 300; ++i) {
      const double turn = (i % 2 == 0 ? 1 : -1) * 0.2;  // a gentle zig-zag of 0.1 mm lines
      p.line_to(p.pos.xyz() + Vec3{0.1 * std::cos(a1 + turn), 0.1 * std::sin(a1 + turn), 0}, 6000);
    }
    p.blocks.back().path_mode = PathMode::kExactStop;
    const Ramp ramp = braking_ramp(m, p.blocks, 1);
    ASSERT_GT(ramp.stop, ramp.brake) << name(f);
    for (std::uint64_t at : arrival_points(ramp, lag_cycles(m))) {
      run_checked_late(m, p.blocks, 1, at, "300 blocks after a late corner, " + name(f));
    }
  }
}

// Found by the property below (no filter, slow X/Y): a helix in the XZ plane rising along Y,
// braking on it for the exact stop of a short G0, with 10.'s arc braking (its curve to W at e,
// the arc's end). A 1 µm line after a dwell arrived then: its lattice cap (10 000 mm/min, c
// at the stop) enters V before c, inside the arc, so e moved back and the curve dropped by
// 1.41·A0 in one cycle: tangential 2 827 > 2 000, X 1 813 > 1 500, Y 1 940 > 800 mm/s².
TEST(AccelLate, LineAfterADwellArrivingLateWhileAHelixBrakesKeepsEveryLimit) {
  const MachineConfig m = machine_for(Filter{0, 0}, true);
  Prog p;
  p.rapid_to(Vec3{0, 0.001, 0});
  p.arc_to(Vec3{-1.8454775422013645, 1.841, -0.54665535264949616},
           Vec3{0, 0.001, -3.3884415613920256}, 6000, Vec3{0, -1, 0});
  p.rapid_to(Vec3{-1.8876825384157794, 1.856444835357772, -0.57260276513891062});
  p.blocks.back().path_mode = PathMode::kExactStop;
  p.dwell(0);
  p.line_to(Vec3{-1.8886825384157793, 1.856444835357772, -0.57260276513891062}, 3000,
            PathMode::kExactStop);
  // The property's arrivals: the helix after 1.2 s at rest, then one block after another.
  check_arrivals(m, p.blocks, {0, 1200, 1220, 1221, 1281});
  // The line arriving at every cycle of the braking on the helix (the rest in time).
  sweep_braking(m, p.blocks, 4, "line after a dwell, after a helix");
}

// Found by the property below (T2 = 4): a 30 mm line at F6000, braking for the end of a slow
// 0.1 mm helix, when a fast helix (R 0.1 mm, one extra turn, r = 0.29 on its arc) arrived and
// its end became the window's stop: the stop's landing bound with the lowest r up to it fell
// below the braking step at once (2.02·A0 in one cycle, 2 126 mm/s² after the jerk stage).
TEST(AccelLate, FastHelixArrivingLateWhileALineBrakesKeepsTheLimit) {
  const MachineConfig m = machine_for(Filter{1e6, 0}, true);
  Prog p;
  p.rapid_to(Vec3{0.00092783625389892003, 0, -0.00037298778257580898});
  p.blocks.back().path_mode = PathMode::kExactStop;
  p.line_to(Vec3{0.00092783625389892003, 0, -30.727103689056158}, 6000);
  p.rapid_to(Vec3{-7.2163746101079986e-05, 0, -30.727103689056158});
  p.arc_to(Vec3{-0.0018174043898294312, 0, -30.727118919540519},
           Vec3{-7.2163746101079986e-05, 0, -30.827103689056159}, 60, Vec3{0, -1, 0}, 1);
  p.arc_to(Vec3{-0.0018174043898294312, 1, -30.727118919540519},
           Vec3{-0.0018174043898294312, 0, -30.827118919540521}, 15000, Vec3{0, -1, 0}, 1);
  p.blocks.back().path_mode = PathMode::kExactStop;
  check_arrivals(m, p.blocks, {0, 5, 25, 175, 325});
  // The fast helix arriving at every cycle of the braking (the rest in time).
  sweep_braking(m, p.blocks, 4, "fast helix after a line");
}

// Found by the property below (T2 = 200, slow X/Y): a 1 µm G0 and a short one arriving while
// the tool crept along a G0 after a slow line. The first one's joint zone reached back 0.66 mm
// over the G0 (the jerk stage's lag) and lowered σ under the tool; re-keying the caps there, one
// of them bound at once, the hold began in the middle and the rest kept their old keys: a
// 0.54 µm/cycle joint cap met at 4.97 µm/cycle (22 258 mm/s³ on a 20 000 mm/s³ limit).
TEST(AccelLate, MicronRapidArrivingLateWithALongJerkStageKeepsTheJerkLimit) {
  const MachineConfig m = machine_for(Filter{20000, 0}, true);
  Prog p;
  p.arc_to(Vec3{-0.54729147749336737, 1.02, -0.17782578061800336}, Vec3{0, 0, -0.93110787546783047},
           3000, Vec3{0, -1, 0});
  p.line_to(Vec3{-0.64769783722165952, 1.02, -0.17782578061800336}, 60);
  p.rapid_to(Vec3{-0.21321762361354468, 1.2831305704133305, -0.41576581813436142});
  p.rapid_to(Vec3{-0.21321762361354468, 1.2821305704133306, -0.41576581813436142});
  p.rapid_to(Vec3{-0.21363780607435337, 1.2813164818093337, -0.41616670021736218});
  p.blocks.back().path_mode = PathMode::kExactStop;
  const auto rep = check_arrivals(m, p.blocks, {0, 5, 5, 405, 405});
  EXPECT_LE(rep.max_tangential_jerk_mm_s3, m.max_jerk_mm_s3 * 1.005);
  // The two G0s arriving at other cycles of the creep along the first G0.
  for (std::uint64_t at : {100, 200, 300, 400, 500, 600, 700, 800, 900}) {
    run_checked_late(m, p.blocks, 3, at, "1 um rapid with T2 = 200");
  }
}

// Found by the property below (no filter, slow X/Y): a 1.5 µm G0 reversed by the next one,
// both arriving one cycle after the line before them. The step after the crossing rose by A0
// (9.), but the sample 0.005 µm before the fold lies on the second G0 as well, and the checker's
// reading of it there (the lowest speed over the two cycles around it) measures the crossing as
// |β − α| = 0.99 µm: 0.99 → 3.0 µm/cycle, 2 010 mm/s².
TEST(AccelLate, RapidReversedRightAfterALateLineKeepsTheTangentialLimit) {
  const MachineConfig m = machine_for(Filter{0, 0}, true);
  Prog p;
  p.line_to(Vec3{-0.001, 0, 0}, 600, PathMode::kExactStop);
  p.line_to(Vec3{-1.6170053039978906e-06, 0.0035048507341108128, -0.00065789776155734752}, 600);
  p.rapid_to(Vec3{-1.6170053039978906e-06, 0.0035048507341108128, -0.0021182712835113673});
  p.rapid_to(Vec3{-1.6170053039978906e-06, 0.0035048507341108128, 0.0045240480503849888});
  p.blocks.back().path_mode = PathMode::kExactStop;
  for (std::uint64_t late : {0, 1, 2, 3}) {
    const std::vector<std::uint64_t> ready{0, 400, 400 + late, 400 + late};
    const RunResult r = run_late(m, p.blocks, ready);
    const auto rep = testing::check_trajectory(r.traj, p.blocks, testing::limits_from_config(m));
    EXPECT_TRUE(rep.ok()) << "G0s " << late << " cycles after the line: " << rep.summary();
    EXPECT_LE(rep.max_tangential_accel_mm_s2, m.max_accel_mm_s2 * 1.005) << late;
  }
}

// Random short programs (lines down to 1 µm, arcs, helices, rapids, exact stops, dwells), each
// block arriving at a random cycle (often while the tool brakes for the end of the one before),
// with a jerk stage of 200, 40 or 4 cycles (or none), slow X/Y or every axis at Amax. Not with
// the post filter: at the exact reversals the generator makes (axis-aligned moves) its output
// turns back short of the joint, and the checker's projection then jumps between the two
// overlapping segments and reports speeds that are not there — with blocks in time too (an F60
// line reversed by a G0: "4.06 mm/s at the joint" for 1 mm/s of motion; accel_filter_test.cpp
// says the same). The post filter is covered by the programs above.
// A block in full precision, for turning a shrunk case into a fixed test.
std::string describe(const Block& b) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "kind %d mode %d feed %.17g end (%.17g, %.17g, %.17g) center (%.17g, %.17g, "
                "%.17g) normal (%g, %g, %g) turns %u dwell %g",
                static_cast<int>(b.kind), static_cast<int>(b.path_mode), b.feed_mm_min, b.end[0],
                b.end[1], b.end[2], b.center.x, b.center.y, b.center.z, b.normal.x, b.normal.y,
                b.normal.z, b.turns, b.dwell_s);
  return buf;
}

RC_GTEST_PROP(AccelLate, RandomProgramsWithLateBlocksKeepEveryLimit, ()) {
  const Filter f{*rc::gen::element(0.0, 20000.0, 100000.0, 1e6), 0.0};
  const bool slow_axes = *rc::gen::arbitrary<bool>();
  const MachineConfig m = machine_for(f, slow_axes);
  testing::gen::BlockGenOptions g;
  g.max_blocks = 8;
  const auto blocks = *testing::gen::blocks(g);
  // Gaps between arrivals: none, a few cycles, or long enough to be well into the braking.
  std::vector<std::uint64_t> ready(blocks.size(), 0);
  std::uint64_t c = 0;
  for (std::size_t i = 1; i < blocks.size(); ++i) {
    c += *rc::gen::element<std::uint64_t>(0, 0, 1, 5, 20, 60, 150, 400, 1200);
    ready[i] = c;
  }
  const RunResult r = run_late(m, blocks, ready, 3'000'000);
  auto lim = testing::limits_from_config(m);
  const auto rep = testing::check_trajectory(r.traj, blocks, lim);
  if (!rep.ok()) {
    RC_LOG() << name(f) << (slow_axes ? ", slow X/Y" : "") << ": " << rep.summary() << "\n";
    for (std::size_t i = 0; i < ready.size(); ++i) {
      RC_LOG() << "ready " << ready[i] << ": " << describe(blocks[i]) << "\n";
    }
  }
  RC_ASSERT(rep.ok());
  RC_ASSERT(r.mismatches == 0u);
  const AxisVec end = program_end(g.start, blocks);
  for (std::size_t i = 0; i < 3; ++i)
    RC_ASSERT(std::abs(r.samples.back().position[i] - end[i]) <= 1e-9);
}

}  // namespace
}  // namespace cncore::motion::test
