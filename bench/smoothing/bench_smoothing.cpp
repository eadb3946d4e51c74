// Path smoothing (planner/path_smoother.hpp): how fast the stage turns chords into curves, and
// what it buys on whole programs.
//
//   bench_smoothing [Google Benchmark flags]
//       blocks/s smoothed on generated chords (no interpretation in the timing), and the worst
//       time of one put() with the blocks it releases (the stage's longest step: a full run
//       fitted at once).
//   bench_smoothing --table [--tolerance MM] [PROGRAM…]
//       each program (default: examples/*.ngc and the shared corpus) run by sim::run_program with
//       smoothing off and on, on the built-in machine: cycle time of both, the exact-path bound
//       (bench/bound, of the programmed blocks), the largest distance of a sample to the
//       programmed path, the checker's violations against the blocks the kernel ran, and the
//       smoothing ratio (G1 chords taken into runs / blocks out for them).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "bound.hpp"
#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "limits.hpp"
#include "path_geometry.hpp"
#include "planner/path_smoother.hpp"
#include "program_blocks.hpp"
#include "simulation/block_source.hpp"
#include "simulation/run.hpp"
#include "trajectory.hpp"
#include "trajectory_checker.hpp"

namespace {

using cncore::Block;
using cncore::Vec3;
namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;

double rounded(double v, double q) {
  return std::round(v / q) * q;
}

std::vector<Block> chords(const std::vector<Vec3>& pts, double feed_mm_min) {
  std::vector<Block> out;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    Block b;
    b.kind = cncore::BlockKind::kLine;
    b.line = static_cast<std::uint32_t>(i);
    b.start.set_xyz(pts[i - 1]);
    b.end.set_xyz(pts[i]);
    b.feed_mm_min = feed_mm_min;
    out.push_back(b);
  }
  return out;
}

// The CAM circle: R 20 in 36 000 chords, 4 decimals.
std::vector<Block> circle() {
  std::vector<Vec3> p;
  for (int i = 0; i <= 36000; ++i) {
    const double a = 2 * kPi * i / 36000;
    p.push_back({rounded(20 * std::cos(a), 1e-4), rounded(20 * std::sin(a), 1e-4), 0});
  }
  return chords(p, 5000);
}

// z = 2·sin(x/5)·cos(y/7), rows of 60 mm in 0.1 mm chords, 4 decimals, stepover 1.5 mm.
std::vector<Block> sine_raster() {
  std::vector<Vec3> p;
  for (int row = 0; row < 20; ++row) {
    const double y = 1.5 * row;
    for (int i = 0; i <= 600; ++i) {
      const double x = row % 2 == 0 ? 0.1 * i : 60 - 0.1 * i;
      p.push_back({x, y, rounded(2 * std::sin(x / 5) * std::cos(y / 7), 1e-4)});
    }
  }
  return chords(p, 6000);
}

// A 3-D random walk of 10–50 µm steps, 6 decimals.
std::vector<Block> random_walk() {
  std::uint64_t s = 0x9E3779B97F4A7C15ull;
  auto rnd = [&] {
    s ^= s >> 12;
    s ^= s << 25;
    s ^= s >> 27;
    return static_cast<double>((s * 0x2545F4914F6CDD1Dull) >> 11) * 0x1.0p-53;
  };
  std::vector<Vec3> p{{0, 0, 0}};
  Vec3 d{1, 0, 0};
  for (int i = 0; i < 20000; ++i) {
    d = d + 0.6 * Vec3{rnd() - 0.5, rnd() - 0.5, rnd() - 0.5};
    d = (1 / cncore::norm(d)) * d;
    const Vec3 q = p.back() + (0.01 + 0.04 * rnd()) * d;
    p.push_back({rounded(q.x, 1e-6), rounded(q.y, 1e-6), rounded(q.z, 1e-6)});
  }
  return chords(p, 6000);
}

// 2 000 strokes of 5 mm with 1 mm steps: every joint a real corner, nothing to smooth.
std::vector<Block> zigzag() {
  std::vector<Vec3> p{{0, 0, 0}};
  for (int i = 0; i < 2000; ++i) {
    const Vec3 q = p.back();
    p.push_back({i % 2 == 0 ? q.x + 5 : q.x - 5, q.y, 0});
    p.push_back({p.back().x, q.y + 1, 0});
  }
  return chords(p, 6000);
}

cncore::planner::SmoothingSettings settings(double tol_mm) {
  cncore::planner::SmoothingSettings s;
  s.tolerance_mm = tol_mm;
  return s;
}

void smooth(benchmark::State& state, const std::vector<Block>& in) {
  std::uint64_t out_blocks = 0;
  double worst_s = 0;
  for (auto _ : state) {
    cncore::planner::PathSmoother sm(settings(0.01));
    Block b;
    for (const Block& x : in) {
      const auto t0 = std::chrono::steady_clock::now();
      sm.put(x);
      while (sm.next(b)) benchmark::DoNotOptimize(b);
      worst_s = std::max(
          worst_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    sm.finish();
    while (sm.next(b)) benchmark::DoNotOptimize(b);
    out_blocks = sm.blocks_out();
  }
  state.counters["blocks/s"] =
      benchmark::Counter(static_cast<double>(in.size()) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
  state.counters["ratio"] =
      static_cast<double>(in.size()) / static_cast<double>(std::max<std::uint64_t>(out_blocks, 1));
  state.counters["worst_put_us"] = worst_s * 1e6;
}

void BM_Circle36000(benchmark::State& s) {
  static const auto in = circle();
  smooth(s, in);
}
void BM_SineRaster(benchmark::State& s) {
  static const auto in = sine_raster();
  smooth(s, in);
}
void BM_RandomWalk(benchmark::State& s) {
  static const auto in = random_walk();
  smooth(s, in);
}
void BM_ZigZag(benchmark::State& s) {
  static const auto in = zigzag();
  smooth(s, in);
}
BENCHMARK(BM_Circle36000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SineRaster)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RandomWalk)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ZigZag)->Unit(benchmark::kMillisecond);

// ---- --table ----

struct Observer : cncore::sim::SampleObserver {
  std::vector<Block> blocks;
  cncore::testing::Trajectory tr;
  void on_block(const Block& b) override {
    if (!b.piece) blocks.push_back(b);  // the merged line before the pieces is what ran
  }
  void on_sample(const cncore::motion::Sample& s) override { tr.add_sample(s); }
};

struct Row {
  double time_s = 0, error_mm = 0;
  std::size_t violations = 0;
};

// The largest distance of a sample to the programmed path near its source line: the segments
// from 3 source lines before the sample's line to 1 100 after it (a curve replaces at most
// PathSmoother::kMaxChords chords). The checker's walk along the path can lose its place on
// programs that pass over the same points again (multi-pass contours), this cannot.
double polyline_error(const cncore::testing::Trajectory& tr, const std::vector<Block>& programmed) {
  std::vector<cncore::testing::PathSegment> segs;
  for (std::size_t i = 0; i < programmed.size(); ++i) {
    cncore::testing::PathSegment seg;
    if (cncore::testing::make_segment(programmed[i], i, seg)) segs.push_back(seg);
  }
  double worst = 0;
  std::size_t first = 0;  // the first segment with line ≥ the sample's line − 3
  for (std::size_t k = 0; k < tr.size(); ++k) {
    const std::uint32_t lo = tr.line[k] > 3 ? tr.line[k] - 3 : 0;
    while (first < segs.size() && segs[first].line < lo) ++first;
    while (first > 0 && segs[first - 1].line >= lo) --first;
    double best = 1e300;
    for (std::size_t j = first; j < segs.size() && segs[j].line <= tr.line[k] + 1100; ++j) {
      double d = 0;
      segs[j].project(tr.pos[k], 0, d);
      best = std::min(best, d);
      if (best < 1e-9) break;
    }
    if (best < 1e300) worst = std::max(worst, best);
  }
  return worst;
}

Row run(const std::string& program, const cncore::MachineConfig& m,
        const std::vector<Block>& programmed) {
  Observer o;
  cncore::sim::run_program(program, m, {}, {&o});
  Row r;
  r.time_s = static_cast<double>(o.tr.size()) * m.period_s;
  const auto lim = cncore::testing::limits_from_config(m);
  const auto kernel = cncore::testing::check_trajectory(o.tr, o.blocks, lim);
  for (std::size_t i = 0; i < static_cast<std::size_t>(cncore::testing::Property::kCount); ++i) {
    r.violations += kernel.counts[i];
  }
  r.error_mm = polyline_error(o.tr, programmed);
  return r;
}

int table(double tol_mm, std::vector<std::string> programs) {
  const fs::path root = fs::path(CNCORE_SOURCE_DIR);
  if (programs.empty()) {
    for (const auto& e : fs::directory_iterator(root / "examples")) {
      if (e.path().extension() == ".ngc") programs.push_back(e.path().string());
    }
    const fs::path corpus = fs::path(CNCORE_SHARED_DIR) / "testdata" / "gcode";
    if (fs::exists(corpus)) {
      for (const auto& e : fs::recursive_directory_iterator(corpus)) {
        const auto ext = e.path().extension();
        if (ext == ".ngc" || ext == ".nc" || ext == ".gcode") programs.push_back(e.path().string());
      }
    } else {
      std::printf("(no corpus at %s: examples only)\n", corpus.string().c_str());
    }
    std::sort(programs.begin(), programs.end());
  }
  cncore::MachineConfig off = cncore::default_machine_config();
  cncore::MachineConfig on = off;
  on.smooth_tolerance_mm = tol_mm;
  std::printf(
      "| program | chords → blocks | off s | on s | on/off | bound s | on/bound | "
      "error mm | violations |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& p : programs) {
    std::vector<Block> blocks;
    try {
      blocks = cncore::testing::read_blocks(p, off);
    } catch (const std::exception&) {
      continue;  // programs `cncore check` rejects
    }
    cncore::planner::PathSmoother sm(
        cncore::sim::smoothing_settings(on, cncore::motion::kernel_options_for(on)));
    Block b;
    for (const Block& x : blocks) {
      sm.put(x);
      while (sm.next(b)) {
      }
    }
    sm.finish();
    while (sm.next(b)) {
    }
    const Row r0 = run(p, off, blocks);
    const Row r1 = run(p, on, blocks);
    const double bound =
        cncore::bound::optimal_time_s(blocks, cncore::testing::limits_from_config(off));
    std::string name = fs::relative(p, fs::path(CNCORE_SHARED_DIR) / "testdata" / "gcode").string();
    if (name.starts_with("..")) name = fs::relative(p, root).string();
    std::printf("| %s | %llu → %llu | %.3f | %.3f | %.3f | %.3f | %.3f | %.4f | %zu |\n",
                name.c_str(), static_cast<unsigned long long>(sm.chords_in()),
                static_cast<unsigned long long>(sm.blocks_out()), r0.time_s, r1.time_s,
                r1.time_s / r0.time_s, bound, bound > 0 ? r1.time_s / bound : 0.0, r1.error_mm,
                r1.violations);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--table") != 0) continue;
    double tol = 0.01;
    std::vector<std::string> programs;
    for (int j = i + 1; j < argc; ++j) {
      if (std::strcmp(argv[j], "--tolerance") == 0 && j + 1 < argc) {
        tol = std::atof(argv[++j]);
      } else {
        programs.emplace_back(argv[j]);
      }
    }
    return table(tol, programs);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
