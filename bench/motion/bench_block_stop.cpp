// bench_block_stop: the cost of the cycle that takes Kernel::request_stop_at_block_end (the
// block ends tried from the stopping distance on, and for the search its greedy brake and a
// new plan), against the plain cycle after it. Built-in machine, 10 000-block look-ahead, a
// zigzag of 2 000 short and long blocks (all in the buffer), the request at a random cycle.
//   build/release/bench/motion/bench_block_stop
// Counters: request_us (mean of the request cycles), request_max_us, next_us (mean of the cycle
// after each). Each iteration constructs and runs its own kernel up to the request (untimed).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "motion/kernel.hpp"

namespace {

using cncore::AxisVec;
using cncore::Block;
using cncore::BlockKind;
using cncore::MachineConfig;
using cncore::Vec3;
using cncore::motion::AccDecType;
using cncore::motion::Kernel;
using cncore::motion::KernelOptions;
using cncore::motion::Sample;

// Blocks of 0.05–1.5 mm (one in ten 8 or 20 mm) turned ±2°…60° off X with alternating sign.
std::vector<Block> zigzag(int blocks) {
  std::mt19937 rng(7);
  const double short_mm[] = {0.05, 0.3, 1.5};
  const double long_mm[] = {8, 20};
  const double angle_deg[] = {2, 5, 30, 60};
  std::vector<Block> out;
  AxisVec at;
  for (int i = 0; i < blocks; ++i) {
    const double len = rng() % 10 == 0 ? long_mm[rng() % 2] : short_mm[rng() % 3];
    const double a = (i % 2 == 0 ? 1 : -1) * angle_deg[rng() % 4] * 3.14159265358979 / 180;
    Block b;
    b.kind = BlockKind::kLine;
    b.line = static_cast<std::uint32_t>(i + 1);
    b.start = at;
    b.end = at;
    b.end.set_xyz(at.xyz() + Vec3{len * std::cos(a), len * std::sin(a), 0});
    b.feed_mm_min = 10000;
    out.push_back(b);
    at = b.end;
  }
  return out;
}

double us_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
}

void request_cycle(benchmark::State& state, AccDecType type) {
  const MachineConfig m = cncore::default_machine_config();
  KernelOptions ko = cncore::motion::kernel_options_for(m);
  ko.accdec = type;
  const std::vector<Block> blocks = zigzag(2000);
  std::mt19937 rng(1);
  double sum_req = 0, max_req = 0, sum_next = 0;
  for (auto _ : state) {
    Kernel k(m, ko);
    std::size_t next = 0;
    Sample s;
    auto feed = [&] {
      while (next < blocks.size() && k.wants_block()) k.push(blocks[next++]);
      if (next == blocks.size()) k.end_of_program();
    };
    const auto cycles = 200 + rng() % 20000;
    for (std::uint64_t c = 0; c < cycles; ++c) {
      feed();
      k.step(s);
    }
    feed();
    k.request_stop_at_block_end();
    auto t0 = std::chrono::steady_clock::now();
    k.step(s);
    const double req = us_since(t0);
    feed();
    t0 = std::chrono::steady_clock::now();
    k.step(s);
    const double nxt = us_since(t0);
    state.SetIterationTime(req * 1e-6);
    sum_req += req;
    max_req = std::max(max_req, req);
    sum_next += nxt;
    benchmark::DoNotOptimize(s);
  }
  const auto n = static_cast<double>(state.iterations());
  state.counters["request_us"] = sum_req / n;
  state.counters["request_max_us"] = max_req;
  state.counters["next_us"] = sum_next / n;
}

BENCHMARK_CAPTURE(request_cycle, moving_average, AccDecType::kMovingAverage)
    ->UseManualTime()
    ->Iterations(40)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(request_cycle, acceleration, AccDecType::kAcceleration)
    ->UseManualTime()
    ->Iterations(40)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(request_cycle, search, AccDecType::kSearch)
    ->UseManualTime()
    ->Iterations(40)
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
