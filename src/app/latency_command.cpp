// `cncore latency`: how punctually this machine runs the cycle thread of `cncore serve`, measured
// like cyclictest (the wake-up lateness after each absolute-time sleep) together with the work
// of each cycle, first with the machine idle, then with a program running.
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "runtime/control.hpp"

namespace cncore::app {

namespace {

// A fine-segment program (a sine of 0.05 mm chords, to and fro) for the loaded phase.
std::string write_default_program() {
  std::string path =
      (std::filesystem::temp_directory_path() / fmt::format("cncore-latency-{}.ngc", ::getpid()))
          .string();
  std::ofstream out(path);
  out << "G21 G90 G64 F6000\nG0 X0 Y0 Z0\n";
  for (int pass = 0; pass < 4; ++pass) {
    for (int i = 0; i <= 4000; ++i) {
      const double x = (pass % 2 == 0 ? i : 4000 - i) * 0.05;
      out << fmt::format("G1 X{:.4f} Y{:.4f}\n", x, 5 * std::sin(x / 7.0));
    }
  }
  out << "M30\n";
  if (!out) throw UsageError("cannot write a temporary program in " + path);
  return path;
}

void print_row(const char* what, const runtime::CycleFigures& f) {
  fmt::print(
      "{:<22} {:>9} {:>8.0f} {:>8.0f} {:>8.0f} {:>8.0f}   {:>8.1f} {:>8.1f} {:>8.1f} {:>8.1f} "
      "{:>8}\n",
      what, f.cycles, f.wake_p50_us, f.wake_p99_us, f.wake_p999_us, f.wake_max_us, f.work_p50_us,
      f.work_p99_us, f.work_p999_us, f.work_max_us, f.overruns);
}

}  // namespace

int command_latency(const LatencyArgs& a) {
  MachineConfig machine = machine_from(a.machine);
  machine.period_s = a.period_us * 1e-6;
  machine.servo.kp_per_s = std::min(machine.servo.kp_per_s, 1 / machine.period_s);
  const std::string program = a.program.empty() ? write_default_program() : a.program;
  if (!a.program.empty()) require_readable(program);
  runtime::ControllerOptions o;
  o.sample_ring = 0;
  const double half_s = a.seconds / 2;
  runtime::CycleFigures idle, loaded;
  {
    runtime::Controller c(machine, o);
    if (auto m = c.take_message()) fmt::print("note: {}\n", *m);
    c.cycle_figures(true);
    std::this_thread::sleep_for(std::chrono::duration<double>(half_s));
    idle = c.cycle_figures(true);
    const runtime::Result r = c.load_program(program);
    if (!r.ok) throw UsageError("--program: " + r.error);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(half_s);
    while (std::chrono::steady_clock::now() < end) {
      if (c.status().state == runtime::MachineState::kIdle) (void)c.cycle_start();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    loaded = c.cycle_figures(false);
  }
  if (a.program.empty()) std::filesystem::remove(program);
  fmt::print("period {} µs, {:.1f} s per phase; wake-up lateness and cycle work in µs\n",
             a.period_us, half_s);
  fmt::print("{:<22} {:>9} {:>8} {:>8} {:>8} {:>8}   {:>8} {:>8} {:>8} {:>8} {:>8}\n", "phase",
             "cycles", "wake p50", "p99", "p99.9", "max", "work p50", "p99", "p99.9", "max",
             "overruns");
  print_row("idle", idle);
  print_row("program running", loaded);
  return 0;
}

}  // namespace cncore::app
