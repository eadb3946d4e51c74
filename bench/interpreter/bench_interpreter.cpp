// bench_interpreter: interpreter throughput in MB/s and blocks/s, and the process's peak RSS
// after each program, so that memory independence from program size is visible (the 1 000 000
// line program must not raise the peak above the 100 000 line one by more than noise).
//
//   bench_interpreter [--benchmark_filter=…]
//
// Programs: the largest files of the shared corpus (CNCORE_SHARED_DIR, skipped when absent)
// and generated CAM-like programs (3-axis finishing: short G1 moves with 3–4 decimals, some
// G2/G3 arcs with I/J, comments, F changes) written to a temporary file; a chain of G5 splines.
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "interpreter/interpreter.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cncore;

MachineConfig bench_machine() {
  MachineConfig m;
  const double lo[3] = {-300, -200, -200};
  const double hi[3] = {300, 200, 100};
  for (std::size_t a = 0; a < 3; ++a) {
    m.axes[a].enabled = true;
    m.axes[a].min_mm = lo[a];
    m.axes[a].max_mm = hi[a];
  }
  return m;
}

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

// A CAM-like finishing program: a raster over a wavy surface.
std::string generate(std::size_t lines) {
  const fs::path path = fs::temp_directory_path() / fmt::format("cncore_bench_{}.ngc", lines);
  if (fs::exists(path) && fs::file_size(path) > 0) return path.string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return {};
  std::fprintf(f, "%%\n(generated CAM-like finishing program, %zu lines)\nG21 G90 G17 G64 P0.01\n",
               lines);
  std::fprintf(f, "T1 M6\nS12000 M3\nG0 X0 Y0 Z5\nG1 Z0 F800\n");
  double x = 0, y = 0;
  for (std::size_t i = 0; i < lines; ++i) {
    const std::size_t k = i % 1000;
    if (k == 999) {
      // End of a raster pass: step over with a half circle in XY.
      std::fprintf(f, "G3 X%.4f Y%.4f I0 J0.25 F1200\n", x - 100, y - 75 + 0.5);
      y += 0.5;
      if (y > 150) y = 0;
      continue;
    }
    if (k % 200 == 0) std::fprintf(f, "(pass %zu)\n", i / 1000);
    x = (i / 1000) % 2 == 0 ? (k * 0.2) : (200 - k * 0.2);
    const double z = -1.0 + 0.5 * std::sin(x * 0.05) * std::cos(y * 0.05);
    if (k % 97 == 0) {
      std::fprintf(f, "G1 X%.4f Y%.4f Z%.4f F%d\n", x - 100, y - 75, z,
                   1500 + static_cast<int>(k % 5) * 100);
    } else {
      std::fprintf(f, "X%.4f Y%.4f Z%.4f\n", x - 100, y - 75, z);
    }
  }
  std::fprintf(f, "G0 Z5\nM5\nM30\n%%\n");
  std::fclose(f);
  return path.string();
}

void run(benchmark::State& state, const std::string& path) {
  if (path.empty() || !fs::exists(path)) {
    state.SkipWithError(("program not found: " + path).c_str());
    return;
  }
  const MachineConfig m = bench_machine();
  const auto bytes = static_cast<std::int64_t>(fs::file_size(path));
  std::int64_t blocks = 0;
  for (auto _ : state) {
    try {
      interp::Interpreter in(path, m, interp::Options{});
      Block b;
      std::int64_t n = 0;
      while (in.next(b)) ++n;
      benchmark::DoNotOptimize(b);
      blocks += n;
    } catch (const InputError& e) {
      state.SkipWithError(e.formatted().c_str());
      return;
    }
  }
  state.SetBytesProcessed(bytes * state.iterations());
  state.SetItemsProcessed(blocks);
  state.counters["blocks_per_s"] =
      benchmark::Counter(static_cast<double>(blocks), benchmark::Counter::kIsRate);
  state.counters["file_MB"] = static_cast<double>(bytes) / 1e6;
  state.counters["peak_rss_MB"] = peak_rss_mb();
}

void BM_Generated(benchmark::State& state) {
  run(state, generate(static_cast<std::size_t>(state.range(0))));
}
// 100 000 lines first, then 1 000 000: compare their peak_rss_MB.
BENCHMARK(BM_Generated)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

// A chain of G5 S curves, 20 mm each, every one after the first leaving along the one before
// (no I J), out along +X and back: the cost of fitting tangent arcs to splines.
std::string generate_splines(std::size_t lines) {
  const fs::path path = fs::temp_directory_path() / fmt::format("cncore_bench_g5_{}.ngc", lines);
  if (fs::exists(path) && fs::file_size(path) > 0) return path.string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return {};
  std::fprintf(f, "G21 G90 G17 G64 P0.01\nG0 X-100 Y0 Z0\nF3000\nG91\nG5 X20 Y0 I5 J10 P-5 Q10\n");
  for (std::size_t i = 1; i < lines; ++i) {
    const bool out = (i / 10) % 2 == 0;
    std::fprintf(f, "G5 X%d Y0 P%d Q%d\n", out ? 20 : -20, out ? -5 : 5, i % 2 == 0 ? 10 : -10);
  }
  std::fprintf(f, "M30\n");
  std::fclose(f);
  return path.string();
}

void BM_Splines(benchmark::State& state) {
  run(state, generate_splines(static_cast<std::size_t>(state.range(0))));
  state.counters["g5_lines_per_s"] = benchmark::Counter(
      static_cast<double>(state.range(0)) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Splines)->Arg(10000)->Unit(benchmark::kMillisecond);

void BM_Corpus(benchmark::State& state, const char* file) {
  run(state, (fs::path(CNCORE_SHARED_DIR) / "testdata" / "gcode" / file).string());
}
BENCHMARK_CAPTURE(BM_Corpus, locket_outside, "camotics/locket_outside.ngc")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Corpus, bear, "camotics/bear.nc")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Corpus, circle_small_segments, "linuxcnc-tp/circle_small_segments_ncd.ngc")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Corpus, stress_test, "ugs/stress_test.gcode")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Corpus, enclosure_arcs, "ugs/enclosure.nc")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Corpus, botomata_arcs, "camotics/botomata_bottom.nc")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Corpus, flowsnake_subroutines, "linuxcnc/flowsnake.ngc")
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
