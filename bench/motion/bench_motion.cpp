// Motion-kernel throughput (issue 3, spec 01 P7): interpolation cycles per second without any
// trajectory output, the worst single cycle with a 10 000-block look-ahead window, and the same
// path cut into 100× finer segments (the cost per cycle must not grow with segment count).
#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "motion/kernel.hpp"

namespace {

using namespace cncore;

MachineConfig machine() {
  MachineConfig m;  // 10 000 mm/min, 2 000 mm/s², 1 ms, look-ahead 10 000 blocks
  for (std::size_t i = 0; i < 3; ++i) {
    m.axes[i].enabled = true;
    m.axes[i].max_speed_mm_min = 20000;
    m.axes[i].max_accel_mm_s2 = 10000;
  }
  return m;
}

// A random path of `segments` segments (0.5–5 mm, turns up to ±20°, so the look-ahead runs at
// speed), each cut into `refine` equal pieces: the same geometry in refine× more blocks.
std::vector<Block> random_path(int segments, int refine) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> len(0.5, 5.0), turn(-0.35, 0.35);
  std::vector<Block> out;
  out.reserve(static_cast<std::size_t>(segments) * static_cast<std::size_t>(refine));
  AxisVec p;
  double heading = 0;
  std::uint32_t line = 1;
  for (int i = 0; i < segments; ++i) {
    heading += turn(rng);
    const double l = len(rng);
    const Vec3 d{l * std::cos(heading), l * std::sin(heading), 0};
    const Vec3 a = p.xyz();
    for (int k = 1; k <= refine; ++k) {
      Block b;
      b.kind = BlockKind::kLine;
      b.line = line++;
      b.start = p;
      b.end.set_xyz(a + (static_cast<double>(k) / refine) * d);
      b.feed_mm_min = 10000;
      out.push_back(b);
      p = b.end;
    }
  }
  return out;
}

struct RunStats {
  std::uint64_t cycles = 0;
  double worst_cycle_s = 0;      // wall time of the slowest step() (includes preemption)
  double p50_s = 0, p999_s = 0;  // median and 99.9th percentile of step()
};

// Runs the whole program; `time_each` measures every step() separately (worst cycle).
RunStats run(const std::vector<Block>& blocks, bool time_each, motion::AccDecType type) {
  const MachineConfig m = machine();
  motion::KernelOptions o;
  o.accdec = type;
  motion::Kernel k(m, o);
  std::size_t next = 0;
  motion::Sample s;
  RunStats st;
  std::vector<double> times;
  if (time_each) times.reserve(1 << 20);
  for (;;) {
    while (next < blocks.size() && k.wants_block()) k.push(blocks[next++]);
    if (next == blocks.size()) k.end_of_program();
    if (time_each) {
      const auto t0 = std::chrono::steady_clock::now();
      const bool more = k.step(s);
      const double dt =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (!more) break;
      times.push_back(dt);
    } else if (!k.step(s)) {
      break;
    }
    benchmark::DoNotOptimize(s);
    ++st.cycles;
  }
  if (!times.empty()) {
    std::sort(times.begin(), times.end());
    st.p50_s = times[times.size() / 2];
    st.p999_s = times[times.size() * 999 / 1000];
    st.worst_cycle_s = times.back();
  }
  return st;
}

// Cycles per second: the run includes pushing the blocks (the interpreter's output), as the
// simulation does. Args: refine factor (1 or 100), acc/dec type (0 moving average, 1 acceleration).
void BM_KernelCycles(benchmark::State& state) {
  const auto blocks = random_path(2000, static_cast<int>(state.range(0)));
  std::uint64_t cycles = 0;
  const auto type = static_cast<motion::AccDecType>(state.range(1));
  for (auto _ : state) cycles += run(blocks, false, type).cycles;
  state.counters["cycles_per_s"] =
      benchmark::Counter(static_cast<double>(cycles), benchmark::Counter::kIsRate);
  state.counters["blocks"] = static_cast<double>(blocks.size());
}
BENCHMARK(BM_KernelCycles)
    ->Args({1, 0})
    ->Args({100, 0})
    ->Args({1, 1})
    ->Args({100, 1})
    ->Unit(benchmark::kMillisecond);

// Worst single step() with a full 10 000-block window (the 100× finer path keeps it full).
void BM_KernelWorstCycle(benchmark::State& state) {
  const auto blocks = random_path(2000, static_cast<int>(state.range(0)));
  RunStats st;
  const auto type = static_cast<motion::AccDecType>(state.range(1));
  for (auto _ : state) st = run(blocks, true, type);
  // Per step() (wall clock, two clock reads included): median, 99.9 %, worst (the worst is
  // dominated by preemption on a shared machine).
  state.counters["step_p50_ns"] = st.p50_s * 1e9;
  state.counters["step_p999_ns"] = st.p999_s * 1e9;
  state.counters["worst_cycle_us"] = st.worst_cycle_s * 1e6;
  state.counters["cycles"] = static_cast<double>(st.cycles);
}
BENCHMARK(BM_KernelWorstCycle)
    ->Args({1, 0})
    ->Args({100, 0})
    ->Args({1, 1})
    ->Args({100, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
