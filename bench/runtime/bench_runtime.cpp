// bench_runtime: the controller of `cncore serve` under load. The cycle thread runs paced at the
// machine's period while the planning thread interprets and plans a 1 000 000-block program;
// reported: the cycle thread's wake-up lateness and work per cycle (p50 / p99 / p99.9 / max, µs),
// overruns, cycles the kernel found no block ready, and the process's resident memory at the
// start and the end of the measured time (flat: the program streams).
//
//   bench_runtime [--benchmark_filter=…]   (BENCH_RUNTIME_SECONDS: measured time, default 20)
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "runtime/control.hpp"

namespace {

using namespace cncore;

// A fine-segment surface raster: 1 000 000 G1 blocks of ~0.05 mm.
const std::string& million_block_program() {
  static const std::string path = [] {
    const auto p = std::filesystem::temp_directory_path() / "cncore-bench-1m.ngc";
    if (!std::filesystem::exists(p)) {
      std::ofstream out(p);
      out << "G21 G90 G64 F6000\nG0 X0 Y0 Z1\nG1 Z0\n";
      const int per_row = 2000;
      for (int row = 0; row < 500; ++row) {
        const double y = row * 0.2;
        for (int i = 0; i < per_row; ++i) {
          const int k = row % 2 == 0 ? i : per_row - 1 - i;
          const double x = k * 0.05;
          out << fmt::format("G1 X{:.4f} Y{:.4f} Z{:.4f}\n", x, y,
                             0.5 * std::sin(x / 5.0) * std::cos(y / 7.0));
        }
      }
      out << "M30\n";
    }
    return p.string();
  }();
  return path;
}

double rss_mb() {
  std::ifstream in("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  in >> pages_total >> pages_resident;
  return static_cast<double>(pages_resident) * 4096.0 / 1e6;
}

void BM_CycleWhilePlanningAMillionBlocks(benchmark::State& state) {
  const char* env = std::getenv("BENCH_RUNTIME_SECONDS");
  const double seconds = env != nullptr ? std::atof(env) : 20.0;
  const std::string program = million_block_program();
  for (auto _ : state) {
    runtime::ControllerOptions o;
    o.sample_ring = 0;
    runtime::Controller c(default_machine_config(), o);
    while (auto m = c.take_message()) state.SetLabel(*m);
    const auto t_load = std::chrono::steady_clock::now();
    if (!c.load_program(program).ok) state.SkipWithError("load failed");
    const double load_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_load).count();
    if (!c.cycle_start().ok) state.SkipWithError("start failed");
    std::this_thread::sleep_for(std::chrono::seconds(1));  // the planner fills its ring
    c.cycle_figures(true);
    const double rss0 = rss_mb();
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    const runtime::CycleFigures f = c.cycle_figures(false);
    const runtime::Status s = c.status();
    state.counters["wake_p50_us"] = f.wake_p50_us;
    state.counters["wake_p99_us"] = f.wake_p99_us;
    state.counters["wake_p999_us"] = f.wake_p999_us;
    state.counters["wake_max_us"] = f.wake_max_us;
    state.counters["work_p50_us"] = f.work_p50_us;
    state.counters["work_p99_us"] = f.work_p99_us;
    state.counters["work_p999_us"] = f.work_p999_us;
    state.counters["work_max_us"] = f.work_max_us;
    state.counters["cycles"] = static_cast<double>(f.cycles);
    state.counters["overruns"] = static_cast<double>(f.overruns);
    state.counters["starved"] = static_cast<double>(s.starved_cycles);
    state.counters["line_reached"] = s.line;
    state.counters["load_check_s"] = load_s;
    state.counters["rss_start_mb"] = rss0;
    state.counters["rss_end_mb"] = rss_mb();
  }
}
BENCHMARK(BM_CycleWhilePlanningAMillionBlocks)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
