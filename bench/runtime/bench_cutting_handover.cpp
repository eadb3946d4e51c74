// What the cutting simulation and adaptive feed add to one cycle of `cncore serve`
// (docs/runtime.md, "The cutting simulation"): CuttingThread::on_cycle (the record into the
// ring, the load read back) and AdaptiveFeed::on_cycle (the controller every control_cycles
// cycles), with the simulation's thread taking the records and sweeping a Ø10 tool through
// examples/cutting/mill.toml's stock on the other core.
#include <benchmark/benchmark.h>

#include <cmath>

#include "config/machine_config.hpp"
#include "runtime/adaptive_feed.hpp"
#include "runtime/cutting.hpp"

namespace {

using namespace cncore;

MachineConfig machine() {
  return load_machine_config(std::string(CNCORE_SOURCE_DIR) + "/examples/cutting/mill.toml");
}

// A circle of radius 20 mm at Z −2 at 3 000 mm/min (0.05 mm per cycle): the tool cuts all along.
void step_position(motion::Sample& s, std::uint64_t n) {
  const double a = static_cast<double>(n) * 0.05 / 20;
  s.position[kX] = 20 * std::cos(a);
  s.position[kY] = 20 * std::sin(a);
  s.position[kZ] = -2;
  s.path_position = s.position;
  s.feed_mm_min = 3000;
}

void BM_CuttingHandover(benchmark::State& state) {
  const MachineConfig m = machine();
  runtime::CuttingThread cutting(m);
  runtime::Status status;
  motion::Sample s;
  std::uint64_t n = 0;
  for (auto _ : state) {
    step_position(s, n);
    cutting.on_cycle(n++, s, status);
    benchmark::DoNotOptimize(status.load_pct);
  }
  state.counters["merged"] = static_cast<double>(status.cutting_coalesced);
}
BENCHMARK(BM_CuttingHandover);

void BM_CuttingHandoverAndAdaptiveFeed(benchmark::State& state) {
  MachineConfig m = machine();
  m.adaptive.enabled = true;
  runtime::CuttingThread cutting(m);
  runtime::AdaptiveFeed adaptive(m, cutting);
  runtime::Status status;
  status.job = 1;
  motion::Sample s;
  std::uint64_t n = 0;
  for (auto _ : state) {
    step_position(s, n);
    cutting.on_cycle(n++, s, status);
    benchmark::DoNotOptimize(adaptive.on_cycle(s, status));
  }
  state.counters["merged"] = static_cast<double>(status.cutting_coalesced);
}
BENCHMARK(BM_CuttingHandoverAndAdaptiveFeed);

}  // namespace

BENCHMARK_MAIN();
