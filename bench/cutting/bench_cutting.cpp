// bench_cutting [PROGRAM] [--tool flat|ball|bull] [--diameter MM] [--cell MM] [--png FILE]
// Runs PROGRAM (default: camotics/bear.nc of the shared corpus, a 80 × 80 mm 3D relief raster)
// on the built-in machine with a 200 × 200 × 30 mm stock (X, Y −60 … 140, top Z 0) at 0.1 mm
// cells, once without and once with the cutting simulation, and prints simulated time, wall
// time and their ratio (the goal is ≥ 20× real time on one core), plus the removed volume and
// the load figures.
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>

#include "simulation/cutting/cutting_sim.hpp"
#include "simulation/run.hpp"

using namespace cncore;

namespace {

struct Clockless : sim::SampleObserver {
  double t_s = 0;
  std::uint64_t n = 0;
  void on_sample(const motion::Sample& s) override {
    t_s = s.t_s;
    ++n;
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::string program = std::string(CNCORE_SHARED_DIR) + "/testdata/gcode/camotics/bear.nc";
  std::string shape = "ball", png;
  double diameter = 6, cell = 0.1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--tool" && i + 1 < argc) {
      shape = argv[++i];
    } else if (a == "--diameter" && i + 1 < argc) {
      diameter = std::stod(argv[++i]);
    } else if (a == "--cell" && i + 1 < argc) {
      cell = std::stod(argv[++i]);
    } else if (a == "--png" && i + 1 < argc) {
      png = argv[++i];
    } else if (!a.empty() && a[0] != '-') {
      program = a;
    } else {
      std::fprintf(stderr,
                   "usage: bench_cutting [PROGRAM] [--tool flat|ball|bull] "
                   "[--diameter MM] [--cell MM] [--png FILE]\n");
      return 2;
    }
  }
  if (!std::filesystem::exists(program)) {
    std::printf("SKIP: %s not found (shared corpus absent)\n", program.c_str());
    return 0;
  }
  const std::string toml = fmt::format(
      "[stock]\nmin_mm = [-60, -60, -30]\nsize_mm = [200, 200, 30]\ncell_mm = {}\n"
      "[cutting]\nmaterial = \"aluminium_6061\"\nspindle_power_kw = 5.5\n"
      "[[tools]]\nnumber = 1\ntype = \"{}\"\ndiameter_mm = {}\n{}",
      cell, shape, diameter, shape == "bull" ? "corner_radius_mm = 1\n" : "");
  const MachineConfig machine = parse_machine_config(toml, "bench.toml");

  using Clock = std::chrono::steady_clock;
  // 1. The run alone (interpreter + kernel).
  Clockless plain;
  const auto cpu = [] { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; };
  double c0 = cpu();
  auto t0 = Clock::now();
  sim::run_program(program, machine, {}, {&plain});
  const double wall_plain = std::chrono::duration<double>(Clock::now() - t0).count();
  const double cpu_plain = cpu() - c0;

  // 2. The same run with the cutting simulation.
  Clockless timed;
  c0 = cpu();
  t0 = Clock::now();
  cut::CuttingSimulator cutting(machine, program);
  const double wall_alloc = std::chrono::duration<double>(Clock::now() - t0).count();
  cut::CuttingStage stage(cutting, {&timed});
  sim::run_program(program, machine, {}, {&stage});
  const double wall_cut = std::chrono::duration<double>(Clock::now() - t0).count();
  const double cpu_cut = cpu() - c0;

  const cut::CuttingStats& s = cutting.stats();
  std::printf("program          %s\n", program.c_str());
  std::printf("stock            200 x 200 mm, cell %.3g mm: %zu x %zu cells (%.1f MB)\n", cell,
              cutting.map().nx(), cutting.map().ny(),
              static_cast<double>(cutting.map().heights().size()) * 4 / 1048576.0);
  std::printf("tool             %s D%.3g\n", shape.c_str(), diameter);
  std::printf("simulated time   %.2f s (%llu cycles)\n", timed.t_s,
              static_cast<unsigned long long>(timed.n));
  std::printf("wall, run alone  %.3f s  -> %.1fx real time\n", wall_plain, plain.t_s / wall_plain);
  std::printf("wall, with cut   %.3f s (map allocation %.3f s) -> %.1fx real time\n", wall_cut,
              wall_alloc, timed.t_s / wall_cut);
  // CPU time: the machine may be shared, so wall time can include waiting for a core.
  std::printf("cpu, run alone   %.3f s  -> %.1fx real time\n", cpu_plain, plain.t_s / cpu_plain);
  std::printf("cpu, with cut    %.3f s  -> %.1fx real time (one core)\n", cpu_cut,
              timed.t_s / cpu_cut);
  std::printf("cutting only     %.3f s -> %.1f us per cycle\n", wall_cut - wall_plain,
              (wall_cut - wall_plain) / static_cast<double>(timed.n) * 1e6);
  std::printf("removed          %.0f mm3, peak MRR %.0f mm3/s\n", s.removed_mm3, s.peak_mrr_mm3_s);
  std::printf("load             peak %.1f %%, mean while cutting %.1f %%\n", s.peak_load_pct,
              s.mean_cutting_load_pct());
  if (!png.empty()) {
    std::ofstream(png, std::ios::binary) << cut::heightmap_png(cutting.map());
    std::printf("png              %s\n", png.c_str());
  }
  return 0;
}
