// Pipeline speed: interpolation cycles per second of the whole `sim::run_program`
// (interpreter → direction correction → Kernel::push → Kernel::step, no observer: no
// trajectory output), with the program interpreted on a producer thread that hands the blocks
// to the cycle through the SPSC ring (RunOptions::producer_thread), against the single-thread
// run. The programs of bench_motion: `ugs/stress_test.gcode`, a seeded random path of 2 000
// short segments, and both cut into 100× finer segments with the same refine writer
// (tests/support GcodeWriter), written to files before any clock starts. Both acc/dec types,
// built-in machine (10 000-block look-ahead).
//
// Pinning: the calling thread (the cycle) runs on --cycle-cpu (default 0), the producer on
// --producer-cpu (default 1); -1 leaves either to the scheduler.
//
// Each benchmark runs the program --runs times (default 3) and reports the best run:
//   Mcycles_per_s  cycles / wall time of the whole run_program call (kernel construction,
//                  ~7-19 MB of buffers, included: it is part of a run)
//   wall_ms        that run's wall time
//   waits, wait_ms (threaded) how often and how long the cycle waited for a late block
//   cycle_cpu_ms   CPU time of the cycle's thread in the best run (CLOCK_THREAD_CPUTIME_ID:
//                  time the shared machine preempted it is not counted; spin-waiting is)
//   busy_Mcycles_per_s  cycles / (wall time − wait time), best run: the cycle's own rate in the
//                  pipeline (Kernel::push + Kernel::step + ring hand-over), what it would run
//                  at were the producer never late
// Producer/PROGRAM: the producer's side alone (interpreter + direction correction into a
// discarded Block), blocks/s and the cycle rate it can feed at most
// (blocks/s × cycles/block of the program).
//
// Extra flags (before the Google Benchmark ones): --shared DIR, --runs N, --cycle-cpu N,
// --producer-cpu N, --tmp DIR (where the generated programs go; default the system temp dir).
#include <benchmark/benchmark.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"
#include "program_gen.hpp"
#include "simulation/run.hpp"

namespace {

using namespace cncore;

std::string g_shared_dir = CNCORE_SHARED_DIR;
std::string g_tmp_dir;
int g_runs = 3;
int g_cycle_cpu = 0;
int g_producer_cpu = 1;

struct Program {
  std::string name;
  std::string path;   // the file run_program reads
  std::string error;  // not available (e.g. the corpus is absent)
  std::uint64_t blocks = 0;
  std::uint64_t cycles = 0;  // of a moving-average run (for the producer's cycle bound)
};

// The same path in `factor`× more blocks, through the writer `cncore-gen refine` uses.
void write_refined(const std::string& in_path, const std::string& out_path, int factor) {
  const MachineConfig m = default_machine_config();
  interp::Interpreter in(in_path, m, {});
  std::ofstream out(out_path);
  testing::gen::GcodeWriter w(out, factor);
  Block b;
  while (in.next(b)) w.add(b);
  w.finish();
}

Program make_program(const std::string& name) {
  Program p;
  p.name = name;
  const std::string dir = g_tmp_dir;
  const std::string stress = g_shared_dir + "/testdata/gcode/ugs/stress_test.gcode";
  try {
    if (name == "stress_test") {
      if (!std::filesystem::exists(stress)) throw std::runtime_error(stress + " not found");
      p.path = stress;
    } else if (name == "stress_test_x100") {
      if (!std::filesystem::exists(stress)) throw std::runtime_error(stress + " not found");
      p.path = dir + "/bench_pipeline_stress_test_x100.ngc";
      write_refined(stress, p.path, 100);
    } else {
      const int factor = name == "random_2k" ? 1 : 100;
      p.path = dir + "/bench_pipeline_" + name + ".ngc";
      std::ofstream(p.path) << testing::gen::random_path(1, 2000, 0.2, 2.0, 90, factor);
    }
  } catch (const std::exception& e) {
    p.error = e.what();
  }
  return p;
}

std::vector<Program>& programs() {
  static std::vector<Program> all;
  return all;
}

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void pin_self(int cpu) {
  if (cpu < 0) return;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(static_cast<unsigned>(cpu), &set);
  sched_setaffinity(0, sizeof set, &set);
}

void unpin_self() {
  cpu_set_t set;
  CPU_ZERO(&set);
  for (int c = 0; c < CPU_SETSIZE; ++c) CPU_SET(static_cast<unsigned>(c), &set);
  sched_setaffinity(0, sizeof set, &set);
}

void BM_Run(benchmark::State& state, Program* prog, int type, bool threaded) {
  if (!prog->error.empty()) {
    state.SkipWithError(prog->error.c_str());
    return;
  }
  const MachineConfig m = default_machine_config();
  sim::RunOptions o;
  o.kernel.accdec = static_cast<motion::AccDecType>(type);
  o.producer_thread = threaded;
  o.producer_cpu = g_producer_cpu;
  pin_self(g_cycle_cpu);
  double best_s = 0, best_busy_s = 0, best_cpu_s = 0;
  sim::RunCounts counts, best_counts;
  for (auto _ : state) {
    for (int run = 0; run < g_runs; ++run) {
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = thread_cpu_s();
      counts = sim::run_program(prog->path, m, o, {});
      const double cpu = thread_cpu_s() - c0;
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (run == 0 || s < best_s) {
        best_s = s;
        best_counts = counts;
        best_cpu_s = cpu;
      }
      const double busy = s - counts.producer_wait_s;
      if (run == 0 || busy < best_busy_s) best_busy_s = busy;
    }
    state.SetIterationTime(best_s);
  }
  unpin_self();
  if (type == 0) {
    prog->blocks = counts.blocks;
    prog->cycles = counts.cycles;
  }
  state.counters["Mcycles_per_s"] = static_cast<double>(counts.cycles) / best_s * 1e-6;
  state.counters["wall_ms"] = best_s * 1e3;
  state.counters["cycle_cpu_ms"] = best_cpu_s * 1e3;
  if (threaded) {
    state.counters["waits"] = static_cast<double>(best_counts.producer_waits);
    state.counters["wait_ms"] = best_counts.producer_wait_s * 1e3;
  }
  state.counters["busy_Mcycles_per_s"] = static_cast<double>(counts.cycles) / best_busy_s * 1e-6;
  state.counters["cycles"] = static_cast<double>(counts.cycles);
  state.counters["blocks"] = static_cast<double>(counts.blocks);
  state.counters["blocks_per_cycle"] =
      static_cast<double>(counts.blocks) / static_cast<double>(counts.cycles);
}

// The producer's work alone: interpretation of every block (the direction correction is off on
// the built-in machine: it passes blocks through).
void BM_Producer(benchmark::State& state, Program* prog) {
  if (!prog->error.empty()) {
    state.SkipWithError(prog->error.c_str());
    return;
  }
  const MachineConfig m = default_machine_config();
  pin_self(g_producer_cpu);
  double best_s = 0;
  std::uint64_t blocks = 0;
  for (auto _ : state) {
    for (int run = 0; run < g_runs; ++run) {
      const auto t0 = std::chrono::steady_clock::now();
      interp::Interpreter in(prog->path, m, {});
      Block b;
      blocks = 0;
      while (in.next(b)) {
        benchmark::DoNotOptimize(b);
        ++blocks;
      }
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (run == 0 || s < best_s) best_s = s;
    }
    state.SetIterationTime(best_s);
  }
  unpin_self();
  const double blocks_per_s = static_cast<double>(blocks) / best_s;
  state.counters["Mblocks_per_s"] = blocks_per_s * 1e-6;
  state.counters["wall_ms"] = best_s * 1e3;
  if (prog->cycles > 0 && prog->blocks > 0) {
    // Cycles per block of the moving-average run (set by its Run benchmark, registered first).
    const double cycles_per_block =
        static_cast<double>(prog->cycles) / static_cast<double>(prog->blocks);
    state.counters["feeds_max_Mcycles_per_s"] = blocks_per_s * cycles_per_block * 1e-6;
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  g_tmp_dir = std::filesystem::temp_directory_path().string();
  for (int i = 0; i < argc; ++i) {
    auto flag = [&](const char* f) { return std::strcmp(argv[i], f) == 0 && i + 1 < argc; };
    if (flag("--shared")) {
      g_shared_dir = argv[++i];
    } else if (flag("--runs")) {
      g_runs = std::max(1, std::atoi(argv[++i]));
    } else if (flag("--cycle-cpu")) {
      g_cycle_cpu = std::atoi(argv[++i]);
    } else if (flag("--producer-cpu")) {
      g_producer_cpu = std::atoi(argv[++i]);
    } else if (flag("--tmp")) {
      g_tmp_dir = argv[++i];
    } else {
      args.push_back(argv[i]);
    }
  }
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;

  auto& progs = programs();
  progs.reserve(4);
  for (const char* name : {"stress_test", "stress_test_x100", "random_2k", "random_2k_x100"}) {
    progs.push_back(make_program(name));
    if (!progs.back().error.empty()) {
      std::fprintf(stderr, "bench_pipeline: %s skipped: %s\n", name, progs.back().error.c_str());
    }
  }
  for (int type = 0; type < 2; ++type) {
    for (Program& p : progs) {
      for (const bool threaded : {false, true}) {
        const std::string name = "Run/" + p.name + "/" +
                                 (type == 0 ? "moving_average" : "acceleration") + "/" +
                                 (threaded ? "threaded" : "single");
        benchmark::RegisterBenchmark(name.c_str(), BM_Run, &p, type, threaded)
            ->Unit(benchmark::kMillisecond)
            ->UseManualTime()
            ->Iterations(1);
      }
    }
  }
  for (Program& p : progs) {
    benchmark::RegisterBenchmark(("Producer/" + p.name).c_str(), BM_Producer, &p)
        ->Unit(benchmark::kMillisecond)
        ->UseManualTime()
        ->Iterations(1);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  for (const Program& p : progs) {
    if (p.path.rfind(g_tmp_dir, 0) == 0) std::filesystem::remove(p.path);
  }
  return 0;
}
