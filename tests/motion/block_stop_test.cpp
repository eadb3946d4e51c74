// Kernel::request_stop_at_block_end measured on the produced set-points: on a zigzag of short and
// long blocks behind a 10 000-block look-ahead buffer, a request at an arbitrary cycle brings
// the tool to rest exactly on a programmed vertex, no farther than the first vertex past the
// distance the deceleration needs, with every limit held (the independent checker); once the
// stop is released the program runs to its end point. Each acc/dec type, and stop mode.
#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "motion_test_util.hpp"
#include "trajectory_checker.hpp"

namespace cncore::motion::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A zigzag along +X: blocks of 0.05–1.5 mm (one in ten 8 or 20 mm), each turned ±2°, 5°, 30° or
// 60° off the X axis with alternating sign, so the corners run from 4° to 120° and X grows at
// every vertex; after one block in five an event that does not wait (M8). Also the vertices
// and their path positions.
struct Zigzag {
  Prog p;
  std::vector<AxisVec> vertex;  // vertex[i]: end of block i
  std::vector<double> s_mm;     // path length from the start to vertex[i]
};

Zigzag zigzag(std::uint32_t seed, int blocks, double feed_mm_min) {
  std::mt19937 rng(seed);
  const double short_mm[] = {0.05, 0.3, 1.5};
  const double long_mm[] = {8, 20};
  const double angle_deg[] = {2, 5, 30, 60};
  Zigzag z;
  double s = 0;
  for (int i = 0; i < blocks; ++i) {
    const double len = rng() % 10 == 0 ? long_mm[rng() % 2] : short_mm[rng() % 3];
    const double a = (i % 2 == 0 ? 1 : -1) * angle_deg[rng() % 4] * kPi / 180;
    const Vec3 at = z.p.pos.xyz();
    z.p.line_to(at + Vec3{len * std::cos(a), len * std::sin(a), 0}, feed_mm_min);
    s += len;
    z.vertex.push_back(z.p.pos);
    z.s_mm.push_back(s);
    if (rng() % 5 == 0) z.p.aux('M', 8, false);  // an event that does not stop the tool
  }
  return z;
}

// One request: the cycle it was made before, and the sample at which the kernel first
// reported the tool resting on the stop (0: never).
struct Request {
  std::uint64_t cycle = 0;
  std::size_t stop_sample = 0;
  bool lifted = false;  // released before the tool got there
};

struct StopRun {
  RunResult r;
  std::vector<Request> requests;
};

// Feeds the kernel as motion_test_util's run() does; before each cycle of `at` asks for a stop
// at a block end, and once the tool rests there lets it stand `rest` cycles, then releases it.
// lift_after > 0: a request the tool has not reached after that many cycles is released.
StopRun run_with_stops(const MachineConfig& m, const KernelOptions& ko, const Prog& p,
                       const std::vector<std::uint64_t>& at, int rest,
                       std::uint64_t lift_after = 0) {
  StopRun out;
  Kernel k(m, ko);
  out.r.traj.period_s = m.period_s;
  std::size_t next = 0, req = 0;
  bool waiting = false;
  int standing = -1;
  Sample s;
  for (std::uint64_t c = 0; c < 50'000'000; ++c) {
    while (next < p.blocks.size() && k.wants_block()) k.push(p.blocks[next++]);
    if (next == p.blocks.size()) k.end_of_program();
    if (req < at.size() && at[req] <= c && !waiting && standing < 0) {
      k.request_stop_at_block_end();
      out.requests.push_back({c, 0});
      waiting = true;
      ++req;
    }
    if (waiting && lift_after > 0 && c == out.requests.back().cycle + lift_after) {
      k.release_stop_at_block_end();
      out.requests.back().lifted = true;
      waiting = false;
    }
    if (!k.step(s)) break;
    out.r.samples.push_back(s);
    out.r.traj.add_sample(s);
    if (waiting && k.stopped_at_block_end()) {
      waiting = false;
      out.requests.back().stop_sample = out.r.samples.size() - 1;
      standing = rest;
    }
    if (standing > 0) --standing;
    if (standing == 0) {
      k.release_stop_at_block_end();
      standing = -1;
    }
  }
  return out;
}

double dist(const AxisVec& a, const AxisVec& b) {
  return norm((a - b).xyz());
}

// The path position of a point on the zigzag (X grows along it): the block whose X range holds
// it, plus the distance from that block's start.
double path_mm(const Zigzag& z, const AxisVec& q) {
  const auto it = std::lower_bound(z.vertex.begin(), z.vertex.end(), q[kX],
                                   [](const AxisVec& v, double x) { return v[kX] < x; });
  const auto i = static_cast<std::size_t>(it - z.vertex.begin());
  if (i == 0) return dist(q, AxisVec{});
  if (i >= z.vertex.size()) return z.s_mm.back();
  return z.s_mm[i - 1] + dist(q, z.vertex[i - 1]);
}

// The index of the vertex within 1e-9 mm of q, or −1.
int vertex_at(const Zigzag& z, const AxisVec& q) {
  for (std::size_t i = 0; i < z.vertex.size(); ++i) {
    bool on = true;
    for (std::size_t a = 0; a < kMaxAxes; ++a) on = on && std::abs(z.vertex[i][a] - q[a]) <= 1e-9;
    if (on) return static_cast<int>(i);
  }
  return -1;
}

// How much farther than v²/(2·Amax) from the tool the stop may lie, for speed v (mm/s): what
// each type needs beyond the ideal braking distance. (The test machine's axes allow 5·Amax, so
// every block of the zigzag brakes at Amax itself.)
//  - moving average (and stop mode): the stop is the first block end the *commanded* position
//    has not passed. The tool is the mean of the commanded positions over the filter's window,
//    so the commanded position leads it by at most the sum of the window's commanded steps, T
//    times their mean, the tool's own step: v·(T + T2 − 1)·τ, and the post filter's Tp·vτ
//    (×1.5: the speed is measured by a chord, shorter than the path across a corner). That lead
//    may hold several short blocks: more than "one block more".
//  - acceleration type: the stop's lattice bound with the last step plus 2·A0 (14. in
//    accel_limited_late.cpp): (u² + u·A0)/(2·A0), u = vτ + 2·A0, is v²/(2A) + 2.5·vτ + 3·A0;
//    a jerk stage and the post filter add their lag (T2 + Tp)·vτ between commanded and tool.
//  - search: the greedy brake from the tool's sample, steps v − a, v − 2a, …: v²/(2A) + vτ.
double allowance_mm(const MachineConfig& m, const KernelOptions& ko, double v_mm_s) {
  const double tau = m.period_s, a0 = m.max_accel_mm_s2 * tau * tau, v = v_mm_s * tau;
  const double t2 = m.max_jerk_mm_s3 > 0
                        ? std::ceil(2 * m.max_accel_mm_s2 / (m.max_jerk_mm_s3 * tau) - 1e-9)
                        : 0.0;
  const double tp = m.post_filter_s > 0 ? std::round(m.post_filter_s / tau) : 0.0;
  if (ko.mode == Mode::kStop || ko.accdec == AccDecType::kMovingAverage) {
    const double t = std::ceil(m.max_feed_mm_min / 60 / (m.max_accel_mm_s2 * tau) - 1e-9);
    return 1.5 * v * (t + t2 + tp) + 4 * a0;
  }
  if (ko.accdec == AccDecType::kAcceleration) return 3 * v + 4 * a0 + v * (t2 + tp);
  return 2 * v + 2 * a0;
}

std::string describe(const KernelOptions& ko) {
  if (ko.mode == Mode::kStop) return "stop mode";
  switch (ko.accdec) {
    case AccDecType::kMovingAverage:
      return "moving average";
    case AccDecType::kAcceleration:
      return "acceleration";
    default:
      return "search";
  }
}

// Every request of the run: the tool came to rest on a vertex at or past the braking distance
// and no farther than the first vertex past it with the type's allowance, and stood there; the
// whole run keeps every limit and ends at the program's end point.
void check_stops(const MachineConfig& m, const KernelOptions& ko, const Zigzag& z,
                 const StopRun& run, int rest) {
  const std::string what = describe(ko);
  const auto& smp = run.r.samples;
  ASSERT_FALSE(smp.empty()) << what;
  const double tau = m.period_s;
  for (const Request& q : run.requests) {
    if (q.lifted) continue;  // (the limits and the end point below still hold)
    ASSERT_GT(q.stop_sample, 0U) << what << ": the request at cycle " << q.cycle
                                 << " never stopped the tool";
    ASSERT_GE(q.cycle, 3U);
    // The tool at the request: the last sample before it, its speed by differences: over the
    // last cycle, and the larger of the last two (a chord across a corner is shorter than the
    // path) for the bound from above.
    const AxisVec& p0 = smp[q.cycle - 1].position;
    const double v_last = dist(smp[q.cycle - 1].position, smp[q.cycle - 2].position) / tau;
    const double v =
        std::max(v_last, dist(smp[q.cycle - 2].position, smp[q.cycle - 3].position) / tau);
    const double s_req = path_mm(z, p0);
    const AxisVec& stop = smp[q.stop_sample].position;
    const int k = vertex_at(z, stop);
    ASSERT_GE(k, 0) << what << ": the tool rests at X " << stop[kX] << " Y " << stop[kY]
                    << ", not on a vertex (request at cycle " << q.cycle << ")";
    // At rest there for the cycles it was held, and moving towards it before.
    for (std::size_t i = q.stop_sample;
         i < q.stop_sample + static_cast<std::size_t>(rest) && i < smp.size(); ++i) {
      EXPECT_EQ(smp[i].position, stop) << what << ": moved at sample " << i;
    }
    const double need = v * v / (2 * m.max_accel_mm_s2);
    const double s_stop = z.s_mm[static_cast<std::size_t>(k)];
    // Not before the braking distance from the last cycle's speed (steps v − Aτ, v − 2Aτ, …
    // land v²/(2A) − vτ/2 on; less one cycle's rounding of the measured speed).
    const double least =
        v_last * v_last / (2 * m.max_accel_mm_s2) - v_last * tau - m.max_accel_mm_s2 * tau * tau;
    EXPECT_GE(s_stop - s_req, least - 1e-9) << what << ": stopped " << s_stop - s_req
                                            << " mm after the request at " << v_last << " mm/s";
    // At the first vertex past it, with the type's allowance.
    const double reach = s_req + need + allowance_mm(m, ko, v);
    const auto first = static_cast<int>(
        std::lower_bound(z.s_mm.begin(), z.s_mm.end(), reach - 1e-9) - z.s_mm.begin());
    EXPECT_LE(k, first) << what << ": request at cycle " << q.cycle << " at " << v << " mm/s, path "
                        << s_req << " mm; stopped at vertex " << k << " (" << s_stop
                        << " mm), the first past " << reach << " mm is " << first;
  }
  testing::Limits lim = testing::limits_from_config(m);
  const auto rep = testing::check_trajectory(run.r.traj, z.p.blocks, lim);
  EXPECT_TRUE(rep.ok()) << what << ": " << rep.summary();
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(smp.back().position[i], z.p.pos[i], 1e-9) << what << ": not at the end point";
  }
}

KernelOptions options(AccDecType type, Mode mode = Mode::kLookahead) {
  KernelOptions ko;
  ko.accdec = type;
  ko.mode = mode;
  return ko;
}

// 2 000 blocks behind a 10 000-block buffer (the kernel holds all of them): requests at
// cycles spread over the run (a fixed seed), each stop held 25 cycles.
void stops_on_long_zigzag(const MachineConfig& m, const KernelOptions& ko) {
  const Zigzag z = zigzag(7, 2000, 10000);
  std::mt19937 rng(11);
  std::vector<std::uint64_t> at;
  std::uint64_t c = 200;
  for (int i = 0; i < 12; ++i) {
    c += 500 + rng() % 3000;
    at.push_back(c);
  }
  constexpr int kRest = 25;
  const StopRun run = run_with_stops(m, ko, z.p, at, kRest);
  EXPECT_EQ(run.requests.size(), at.size()) << describe(ko) << ": the program ended first";
  check_stops(m, ko, z, run, kRest);
}

TEST(BlockStop, AccelerationTypeStopsOnTheFirstVertexItCanReach) {
  stops_on_long_zigzag(test_machine(), options(AccDecType::kAcceleration));
}

TEST(BlockStop, MovingAverageStopsOnTheFirstVertexTheCommandedPositionHasNotPassed) {
  stops_on_long_zigzag(test_machine(), options(AccDecType::kMovingAverage));
}

TEST(BlockStop, SearchTypeStopsOnTheFirstVertexBeyondItsBrake) {
  stops_on_long_zigzag(test_machine(), options(AccDecType::kSearch));
}

TEST(BlockStop, StopModeStopsOnTheFirstVertexTheCommandedPositionHasNotPassed) {
  stops_on_long_zigzag(test_machine(), options(AccDecType::kMovingAverage, Mode::kStop));
}

TEST(BlockStop, WithAJerkStageAndThePostFilter) {
  MachineConfig m = test_machine();
  m.max_jerk_mm_s3 = 100000;  // T2 = 40 cycles
  m.post_filter_s = 0.016;
  stops_on_long_zigzag(m, options(AccDecType::kAcceleration));
  stops_on_long_zigzag(m, options(AccDecType::kMovingAverage));
}

// From rest on a vertex a request stops at the next one: the operator's single block after a
// cycle start.
TEST(BlockStop, FromRestEachRequestRunsOneBlock) {
  const MachineConfig m = test_machine();
  for (const KernelOptions& ko :
       {options(AccDecType::kAcceleration), options(AccDecType::kMovingAverage),
        options(AccDecType::kSearch)}) {
    const Zigzag z = zigzag(3, 40, 10000);
    Kernel k(m, ko);
    for (const Block& b : z.p.blocks) k.push(b);
    k.end_of_program();
    Sample s;
    k.request_stop_at_block_end();  // before the first cycle: at the start point
    std::vector<int> stops;
    for (int c = 0; c < 2'000'000 && k.step(s); ++c) {
      if (!k.stopped_at_block_end()) continue;
      stops.push_back(vertex_at(z, s.position));
      k.release_stop_at_block_end();
      if (stops.size() < 5) k.request_stop_at_block_end();
    }
    ASSERT_EQ(stops.size(), 5U) << describe(ko);
    for (int i = 0; i < 5; ++i) EXPECT_EQ(stops[static_cast<std::size_t>(i)], i) << describe(ko);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(s.position[i], z.p.pos[i], 1e-9);
  }
}

// Random zigzags, buffer sizes and request cycles (one or two requests).
RC_GTEST_PROP(BlockStop, AnyRequestStopsOnAReachableVertex, ()) {
  MachineConfig m = test_machine();
  m.lookahead_blocks = *rc::gen::element(16U, 10000U);
  const KernelOptions ko = *rc::gen::element(
      options(AccDecType::kAcceleration), options(AccDecType::kMovingAverage),
      options(AccDecType::kSearch), options(AccDecType::kMovingAverage, Mode::kStop));
  const auto seed = *rc::gen::inRange<std::uint32_t>(0, 1'000'000);
  const int blocks = *rc::gen::inRange(20, 120);
  const double feed = *rc::gen::element(3000.0, 10000.0);
  const Zigzag z = zigzag(seed, blocks, feed);
  std::vector<std::uint64_t> at{*rc::gen::inRange<std::uint64_t>(3, 3000)};
  if (*rc::gen::arbitrary<bool>()) at.push_back(at[0] + *rc::gen::inRange<std::uint64_t>(1, 3000));
  // Some requests are lifted before the tool gets there (single block switched off again).
  const auto lift = *rc::gen::element<std::uint64_t>(0, 0, 1, 5, 40);
  RC_LOG() << describe(ko) << ", seed " << seed << ", " << blocks << " blocks at F" << feed
           << ", window " << m.lookahead_blocks << ", requests at " << at[0]
           << (at.size() > 1 ? " and " + std::to_string(at[1]) : "") << ", lifted after " << lift;
  const StopRun run = run_with_stops(m, ko, z.p, at, 10, lift);
  check_stops(m, ko, z, run, 10);
  RC_ASSERT(!::testing::Test::HasFailure());
}

}  // namespace
}  // namespace cncore::motion::test
