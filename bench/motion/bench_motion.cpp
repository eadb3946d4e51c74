// Motion-kernel speed (spec 01 P7): interpolation cycles per second without any
// trajectory output, per-cycle latency percentiles and the worst single cycle with a
// 10 000-block look-ahead window, on `ugs/stress_test.gcode` and the same path cut into 100×
// finer segments, and the kernel's memory against program length.
//
// Every program is interpreted before the clock starts (the kernel is fed pre-interpreted
// Blocks); what the kernel does with a block (segment construction, joint speed, look-ahead
// points) is part of Kernel::push and is included where a figure says "incl. push".
// Kernel construction (allocating and touching its buffers) is never timed.
//
// Extra flags (before the Google Benchmark ones): --shared DIR (corpus root, default the CMake
// cache's CNCORE_SHARED_DIR), --mlock (mlockall(MCL_CURRENT | MCL_FUTURE) before measuring),
// --runs N (runs per latency benchmark, default 3), --histogram (print the per-cycle latency
// histograms to stderr), --digest (print a hash of
// every program's samples instead of benchmarking), --construct TYPE N (time N kernel
// constructions in a row instead of benchmarking), --evict-kb N (Latency: write N KB of other
// memory, untimed, before every step — the cache traffic of the pushes a finer program makes
// between two cycles, on a coarse one: how much of a fine program's step() is its input's
// traffic rather than its work), --override-every N (Latency: the feed override steps to 70,
// 120 and 100 % in turn every N cycles, set untimed before the step it applies to: what an
// operator's override change costs the cycle that replans for it).
//
// The "_merged" programs are the same blocks handed to the kernel through the collinear-piece
// stage of `cncore run` (planner/line_merge.hpp, [motion] merge_tolerance_mm): the stage's
// work is timed with the pushes, as the interpretation is not. LineMerge/<program> times the
// stage alone on them.
#include <benchmark/benchmark.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <x86intrin.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"
#include "motion/kernel.hpp"
#include "planner/huge_pages.hpp"
#include "planner/line_merge.hpp"
#include "program_gen.hpp"
#include "simulation/stepper.hpp"

// Heap accounting: every operator new in the process is counted, so a run can show that the
// kernel allocates only at construction (and how much) and never while it runs.
namespace {
std::uint64_t g_allocs = 0;
std::uint64_t g_alloc_bytes = 0;
}  // namespace

// These replace the global allocation functions, so new/free pair up by construction; gcc 12
// cannot see that once it inlines the replacement into a caller and warns (mismatched-new-delete).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
  ++g_allocs;
  g_alloc_bytes += n;
  if (void* p = std::malloc(n != 0 ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  return operator new(n);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
#pragma GCC diagnostic pop

namespace {

using namespace cncore;

std::string g_shared_dir = CNCORE_SHARED_DIR;
bool g_histogram = false;

// ---------------------------------------------------------------------------------------------
// Programs

struct Program {
  std::string name;
  std::vector<Block> blocks;
  bool ok = false;
  std::string error;
  bool merge = false;  // through the collinear-piece stage (see the top)
};

// A program's blocks in the order the kernel takes them, direct or through the collinear-piece
// stage (its put/next calls then run inside the timed loops).
class Feed {
 public:
  explicit Feed(const Program& p)
      : blocks_(p.blocks),
        merge_(p.merge),
        merger_(sim::make_line_merger(default_machine_config(), {})) {}
  // The next block, or nullptr at the end of the program.
  const Block* next() {
    if (!merge_) return next_ < blocks_.size() ? &blocks_[next_++] : nullptr;
    while (true) {
      if (merger_.next(out_)) return &out_;
      if (next_ == blocks_.size()) {
        merger_.finish();
        return merger_.next(out_) ? &out_ : nullptr;
      }
      merger_.put(blocks_[next_++]);
    }
  }

 private:
  const std::vector<Block>& blocks_;
  bool merge_;
  planner::LineMerger merger_;
  std::size_t next_ = 0;
  Block out_;
};

// Pushes blocks while the kernel wants them; at the end of the program, tells it so.
inline void feed_kernel(motion::Kernel& k, Feed& feed, bool& ended) {
  while (!ended && k.wants_block()) {
    const Block* b = feed.next();
    if (b == nullptr) {
      ended = true;
      break;
    }
    k.push(*b);
  }
  if (ended) k.end_of_program();
}

// A program is interpreted the first time a selected benchmark needs it (not timed).
struct LazyProgram {
  LazyProgram(std::string n, Program (*l)(int), int f, bool m = false)
      : name(std::move(n)), load(l), factor(f), merge(m) {}
  std::string name;
  Program (*load)(int factor);
  int factor;
  bool merge;
  const Program& get() {
    if (!done) {
      prog = load(factor);
      prog.merge = merge;
      prog.name = name;
      if (!prog.ok)
        std::fprintf(stderr, "bench_motion: %s skipped: %s\n", name.c_str(), prog.error.c_str());
      done = true;
    }
    return prog;
  }
  Program prog;
  bool done = false;
};

std::vector<Block> interpret(interp::Interpreter& in) {
  std::vector<Block> out;
  Block b;
  while (in.next(b)) out.push_back(b);
  return out;
}

// The same path in `factor`× more blocks (lines in equal pieces, arcs in equal angles), through
// the G-code writer that `cncore-gen refine` uses, then the interpreter again.
std::vector<Block> refine(const std::vector<Block>& blocks, int factor, const MachineConfig& m) {
  std::ostringstream text;
  testing::gen::GcodeWriter w(text, factor);
  for (const Block& b : blocks) w.add(b);
  w.finish();
  interp::Interpreter in(interp::Interpreter::FromText{}, text.str(), "refined", m, {});
  return interpret(in);
}

Program load_stress(int factor) {
  Program p;
  p.name = factor == 1 ? "stress_test" : "stress_test_x" + std::to_string(factor);
  const std::string path = g_shared_dir + "/testdata/gcode/ugs/stress_test.gcode";
  try {
    const MachineConfig m = default_machine_config();
    interp::Interpreter in(path, m, {});
    p.blocks = interpret(in);
    if (factor > 1) p.blocks = refine(p.blocks, factor, m);
    p.ok = true;
  } catch (const InputError& e) {
    p.error = e.formatted();
  }
  return p;
}

// A seeded random path of 2000 short segments (0.2–2 mm, turns up to ±90°: real corners), in
// `refine`× more blocks: 2 k and 200 k blocks of the same path for the memory comparison.
Program load_random(int factor) {
  Program p;
  p.name = factor == 1 ? "random_2k" : "random_2k_x" + std::to_string(factor);
  const MachineConfig m = default_machine_config();
  interp::Interpreter in(interp::Interpreter::FromText{},
                         testing::gen::random_path(1, 2000, 0.2, 2.0, 90, factor), p.name, m, {});
  p.blocks = interpret(in);
  p.ok = true;
  return p;
}

std::vector<LazyProgram>& programs() {
  static std::vector<LazyProgram> all;
  return all;
}

// ---------------------------------------------------------------------------------------------
// Timing

// TSC ticks per ns, calibrated against steady_clock (the TSC is constant and non-stop here;
// reading it costs ~10 ns against ~25 ns for clock_gettime under kvm-clock).
double tsc_per_ns() {
  static const double f = [] {
    const auto t0 = std::chrono::steady_clock::now();
    const std::uint64_t c0 = __rdtsc();
    while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(50)) {
    }
    const std::uint64_t c1 = __rdtsc();
    const double ns =
        std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    return static_cast<double>(c1 - c0) / ns;
  }();
  return f;
}

inline std::uint64_t ticks() {
  _mm_lfence();
  const std::uint64_t t = __rdtsc();
  _mm_lfence();
  return t;
}

motion::KernelOptions options(int type) {
  motion::KernelOptions o;
  o.accdec = static_cast<motion::AccDecType>(type);
  return o;
}

const char* type_name(int type) {
  return type == 0 ? "moving_average" : type == 1 ? "acceleration" : "search";
}

// Feeds a program's blocks as the kernel asks for them and steps it to the end; on_sample sees
// every sample. Returns the cycles stepped.
template <class OnSample>
std::uint64_t drive(motion::Kernel& k, const Program& prog, OnSample on_sample) {
  std::uint64_t cycles = 0;
  Feed feed(prog);
  bool ended = false;
  motion::Sample s;
  for (;;) {
    feed_kernel(k, feed, ended);
    if (!k.step(s)) break;
    on_sample(s);
    ++cycles;
  }
  return cycles;
}

// Cycles per second of Kernel::push + Kernel::step on a pre-interpreted program (construction
// and destruction not timed). Also: heap bytes allocated by the kernel's construction and
// allocations while it runs (must be 0: memory flat in program length).
// Mcycles_per_s is Google Benchmark's rate: cycles / the thread's CPU time of the timed part
// (the "CPU" column), not the wall-clock "Time" column: on the shared machine the wall clock
// also counts the time other processes hold the core. Mcycles_per_wall_s: cycles / wall-clock
// time of the timed part alone, measured here (steady_clock, pauses excluded).
void BM_Throughput(benchmark::State& state, LazyProgram* lazy, int type) {
  const Program* prog = &lazy->get();
  if (!prog->ok) {
    state.SkipWithError(prog->error.c_str());
    return;
  }
  const MachineConfig m = default_machine_config();
  const motion::KernelOptions o = options(type);
  std::uint64_t cycles = 0;
  std::uint64_t construct_bytes = 0, run_allocs = 0;
  double wall_s = 0;
  for (auto _ : state) {
    state.PauseTiming();
    // The kernel's large buffers come from planner::huge_alloc, not operator new: both count.
    const std::uint64_t b0 = g_alloc_bytes + planner::huge_alloc_stats().bytes;
    auto k = std::make_unique<motion::Kernel>(m, o);
    construct_bytes = g_alloc_bytes + planner::huge_alloc_stats().bytes - b0;
    const std::uint64_t a0 = g_allocs + planner::huge_alloc_stats().allocations;
    state.ResumeTiming();
    const auto w0 = std::chrono::steady_clock::now();
    cycles += drive(*k, *prog, [](motion::Sample& s) { benchmark::DoNotOptimize(s); });
    wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    state.PauseTiming();
    run_allocs = g_allocs + planner::huge_alloc_stats().allocations - a0;
    k.reset();
    state.ResumeTiming();
  }
  state.counters["Mcycles_per_s"] =
      benchmark::Counter(static_cast<double>(cycles) * 1e-6, benchmark::Counter::kIsRate);
  state.counters["Mcycles_per_wall_s"] =
      wall_s > 0 ? static_cast<double>(cycles) * 1e-6 / wall_s : 0;
  state.counters["blocks"] = static_cast<double>(prog->blocks.size());
  state.counters["kernel_heap_MB"] = static_cast<double>(construct_bytes) / 1e6;
  state.counters["allocs_in_run"] = static_cast<double>(run_allocs);
}

// The collinear-piece stage alone (planner/line_merge.hpp): every block of the program through
// the built-in machine's LineMerger, no kernel. Mpieces_per_s: blocks put per second; lines_out:
// the blocks it hands on.
void BM_LineMerge(benchmark::State& state, LazyProgram* lazy) {
  const Program* prog = &lazy->get();
  if (!prog->ok) {
    state.SkipWithError(prog->error.c_str());
    return;
  }
  std::uint64_t pieces = 0, lines = 0;
  for (auto _ : state) {
    planner::LineMerger merger = sim::make_line_merger(default_machine_config(), {});
    Block out;
    lines = 0;
    for (const Block& b : prog->blocks) {
      merger.put(b);
      while (merger.next(out)) ++lines;
    }
    merger.finish();
    while (merger.next(out)) ++lines;
    benchmark::DoNotOptimize(out);
    pieces += prog->blocks.size();
  }
  state.counters["Mpieces_per_s"] =
      benchmark::Counter(static_cast<double>(pieces) * 1e-6, benchmark::Counter::kIsRate);
  state.counters["lines_out"] = static_cast<double>(lines);
}

struct Percentiles {
  double p50 = 0, p99 = 0, p999 = 0, p9999 = 0, max = 0, sum = 0;
  std::size_t over_10us = 0;
};

Percentiles percentiles(std::vector<double>& ns) {
  Percentiles p;
  if (ns.empty()) return p;
  for (double v : ns) {
    p.sum += v;
    if (v > 10000) ++p.over_10us;
  }
  std::sort(ns.begin(), ns.end());
  auto at = [&](double q) {
    return ns[std::min(ns.size() - 1, static_cast<std::size_t>(q * ns.size()))];
  };
  p.p50 = at(0.5);
  p.p99 = at(0.99);
  p.p999 = at(0.999);
  p.p9999 = at(0.9999);
  p.max = ns.back();
  return p;
}

void print_histogram(const std::string& title, const std::vector<double>& sorted_ns) {
  // Powers-of-two buckets from 32 ns.
  std::array<std::size_t, 24> count{};
  for (double v : sorted_ns) {
    std::size_t b = 0;
    for (double edge = 32; v >= edge && b + 1 < count.size(); edge *= 2) ++b;
    ++count[b];
  }
  std::fprintf(stderr, "%s (%zu cycles)\n", title.c_str(), sorted_ns.size());
  double lo = 0, hi = 32;
  for (std::size_t b = 0; b < count.size(); ++b, lo = hi, hi *= 2) {
    if (count[b] != 0) std::fprintf(stderr, "  [%8.0f, %8.0f) ns  %zu\n", lo, hi, count[b]);
  }
}

// Per-cycle latency: every Kernel::step timed on its own (TSC, fenced), pushes between steps
// untimed; the program is run `g_runs` times. The kernel is deterministic (cycle i does the same
// work in every run) while preemption and interrupts of the shared machine are not, so the
// worst of the per-cycle minimum over the runs is the kernel's own worst cycle ("worst_det");
// the raw worst over all runs is reported next to it. Percentiles pool every run. step()-only
// cycles/s: cycles / Σ step time of the fastest run (the timer's own cost subtracted). A timed
// empty call right after each step shows what the machine does to a 10 ns window (floor_*).
int g_runs = 3;
std::size_t g_override_every = 0;  // --override-every: cycles between override steps (0: none)
std::size_t g_evict_kb = 0;
std::vector<unsigned char> g_evict;  // --evict-kb's scratch memory

void BM_Latency(benchmark::State& state, LazyProgram* lazy, int type) {
  const Program* prog = &lazy->get();
  if (!prog->ok) {
    state.SkipWithError(prog->error.c_str());
    return;
  }
  const MachineConfig m = default_machine_config();
  const motion::KernelOptions o = options(type);
  const double f = tsc_per_ns();
  std::vector<double> step_ns, empty_ns, det_ns;
  std::vector<std::uint64_t> raw, raw_empty, min_ticks;
  Percentiles st, floor, det;
  double overhead_ns = 0, best_sum_ns = 0;
  std::size_t cycles = 0, worst_det_cycle = 0;
  for (auto _ : state) {
    // Timer cost: back-to-back reads (minimum of many).
    std::uint64_t best = UINT64_MAX;
    for (int i = 0; i < 100000; ++i) {
      const std::uint64_t a = ticks();
      const std::uint64_t b = ticks();
      best = std::min(best, b - a);
    }
    overhead_ns = static_cast<double>(best) / f;
    const std::size_t cap = 1u << 22;
    // Touched before the runs: no page fault while timing.
    raw.assign(cap * static_cast<std::size_t>(g_runs), 0);
    raw_empty.assign(raw.size(), 0);
    min_ticks.assign(cap, UINT64_MAX);
    best_sum_ns = 0;
    for (int run = 0; run < g_runs; ++run) {
      motion::Kernel k(m, o);
      std::uint64_t* rt = raw.data() + cap * static_cast<std::size_t>(run);
      std::uint64_t* re = raw_empty.data() + cap * static_cast<std::size_t>(run);
      std::size_t c = 0;
      Feed feed(*prog);
      bool ended = false;
      motion::Sample s;
      for (;;) {
        feed_kernel(k, feed, ended);
        // One byte per 64-byte line, with a running value the compiler cannot drop.
        for (std::size_t i = 0; i < g_evict.size(); i += 64) g_evict[i] += 1;
        if (g_override_every > 0 && c > 0 && c % g_override_every == 0) {
          constexpr std::array<double, 3> kSteps{70, 120, 100};
          k.set_override(kSteps[(c / g_override_every - 1) % kSteps.size()]);
        }
        benchmark::ClobberMemory();
        const std::uint64_t t0 = ticks();
        const bool more = k.step(s);
        const std::uint64_t t1 = ticks();
        benchmark::DoNotOptimize(s);
        const std::uint64_t e0 = ticks();
        benchmark::ClobberMemory();
        const std::uint64_t e1 = ticks();
        if (!more) break;
        if (c < cap) {
          rt[c] = t1 - t0;
          re[c] = e1 - e0;
        }
        ++c;
      }
      cycles = std::min(c, cap);
      double sum = 0;
      for (std::size_t i = 0; i < cycles; ++i) {
        min_ticks[i] = std::min(min_ticks[i], rt[i]);
        sum += std::max(0.0, static_cast<double>(rt[i]) / f - overhead_ns);
      }
      if (run == 0 || sum < best_sum_ns) best_sum_ns = sum;
    }
    step_ns.clear();
    empty_ns.clear();
    for (int run = 0; run < g_runs; ++run) {
      for (std::size_t i = 0; i < cycles; ++i) {
        const std::size_t at = cap * static_cast<std::size_t>(run) + i;
        step_ns.push_back(std::max(0.0, static_cast<double>(raw[at]) / f - overhead_ns));
        empty_ns.push_back(std::max(0.0, static_cast<double>(raw_empty[at]) / f - overhead_ns));
      }
    }
    det_ns.resize(cycles);
    for (std::size_t i = 0; i < cycles; ++i) {
      det_ns[i] = std::max(0.0, static_cast<double>(min_ticks[i]) / f - overhead_ns);
    }
    worst_det_cycle =
        static_cast<std::size_t>(std::max_element(det_ns.begin(), det_ns.end()) - det_ns.begin());
    st = percentiles(step_ns);
    floor = percentiles(empty_ns);
    det = percentiles(det_ns);
  }
  if (g_histogram) {
    print_histogram(prog->name + " " + type_name(type) + ": step(), all runs", step_ns);
    print_histogram(prog->name + " " + type_name(type) + ": step(), per-cycle min of runs", det_ns);
    print_histogram(prog->name + " " + type_name(type) + ": empty timed call", empty_ns);
  }
  state.counters["cycles"] = static_cast<double>(cycles);
  state.counters["runs"] = g_runs;
  state.counters["evict_kb"] = static_cast<double>(g_evict_kb);
  state.counters["override_every"] = static_cast<double>(g_override_every);
  state.counters["step_Mcycles_per_s"] = best_sum_ns > 0 ? 1e3 * cycles / best_sum_ns : 0;
  // The same from the per-cycle minimum over the runs (preemption taken out cycle by cycle):
  // steadier than the fastest run on the loaded machine, for before/after comparisons.
  state.counters["step_det_Mcycles_per_s"] = det.sum > 0 ? 1e3 * cycles / det.sum : 0;
  state.counters["p50_ns"] = st.p50;
  state.counters["p99_ns"] = st.p99;
  state.counters["p999_ns"] = st.p999;
  state.counters["p9999_ns"] = st.p9999;
  state.counters["worst_us"] = st.max / 1e3;
  state.counters["over_10us"] = static_cast<double>(st.over_10us);
  state.counters["worst_det_us"] = det.max / 1e3;
  state.counters["worst_det_cycle"] = static_cast<double>(worst_det_cycle);
  state.counters["over_10us_det"] = static_cast<double>(det.over_10us);
  state.counters["floor_worst_us"] = floor.max / 1e3;
  state.counters["floor_over_10us"] = static_cast<double>(floor.over_10us);
  state.counters["timer_ns"] = overhead_ns;
}

// --digest: one line per program and type with the cycle count and an FNV-1a hash of every
// sample's bytes (positions, speed, line): a bit-exact before/after check of a change that must
// not alter the trajectory.
void print_digests() {
  const MachineConfig m = default_machine_config();
  for (int type = 0; type < 2; ++type) {
    for (LazyProgram& lazy : programs()) {
      const Program& prog = lazy.get();
      if (!prog.ok) continue;
      motion::Kernel k(m, options(type));
      std::uint64_t h = 1469598103934665603ull;
      auto mix = [&h](const void* p, std::size_t n) {
        const auto* c = static_cast<const unsigned char*>(p);
        for (std::size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 1099511628211ull;
      };
      const std::uint64_t cycles = drive(k, prog, [&mix](const motion::Sample& s) {
        mix(&s.t_s, sizeof s.t_s);
        mix(&s.line, sizeof s.line);
        mix(&s.position, sizeof s.position);
        mix(&s.path_position, sizeof s.path_position);
        mix(&s.feed_mm_min, sizeof s.feed_mm_min);
      });
      std::printf("%-18s %-15s cycles %8llu  digest %016llx\n", prog.name.c_str(), type_name(type),
                  static_cast<unsigned long long>(cycles), static_cast<unsigned long long>(h));
    }
  }
}

// --profile NAME TYPE RUNS: runs one program RUNS times (pushes and steps, no timing), for a
// sampling profiler (`perf record -e cpu-clock`): kernel construction, push and step show up as
// separate symbols. TYPE: moving_average or acceleration.
int profile(const std::string& name, const std::string& type, int runs) {
  const MachineConfig m = default_machine_config();
  const int t = type == "moving_average" ? 0 : 1;
  for (LazyProgram& lazy : programs()) {
    if (lazy.name != name) continue;
    const Program& prog = lazy.get();
    if (!prog.ok) return 1;
    std::uint64_t cycles = 0;
    const auto w0 = std::chrono::steady_clock::now();
    for (int run = 0; run < runs; ++run) {
      motion::Kernel k(m, options(t));
      cycles += drive(k, prog, [](motion::Sample& s) { benchmark::DoNotOptimize(s); });
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    std::printf("%s %s: %llu cycles in %.3f s\n", name.c_str(), type_name(t),
                static_cast<unsigned long long>(cycles), s);
    return 0;
  }
  std::fprintf(stderr, "bench_motion: no program %s\n", name.c_str());
  return 1;
}

// --construct TYPE N: constructs N kernels of TYPE in a row (built-in machine, 10 000-block
// window) and prints each one's wall time and the page faults it took (getrusage's minor
// faults): the cost the benchmarks above leave out, which a whole `cncore run` pays once. Run it
// in a fresh process for the first construction's figure: later ones reuse the memory the
// earlier kernels freed (huge_pages.hpp keeps an empty region).
int construct(const std::string& type, int n) {
  const MachineConfig m = default_machine_config();
  const int t = type == "moving_average" ? 0 : 1;
  for (int i = 0; i < n; ++i) {
    rusage r0{}, r1{};
    getrusage(RUSAGE_SELF, &r0);
    const auto w0 = std::chrono::steady_clock::now();
    double ms = 0;
    {
      motion::Kernel k(m, options(t));
      benchmark::DoNotOptimize(&k);
      ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count();
      getrusage(RUSAGE_SELF, &r1);
    }
    std::printf("%s kernel %d: %.3f ms, %ld page faults\n", type_name(t), i + 1, ms,
                r1.ru_minflt - r0.ru_minflt);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  bool lock = false, digest = false;
  std::string prof_name, prof_type;
  int prof_runs = 0;
  std::string construct_type;
  int construct_n = 0;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--mlock") == 0) {
      lock = true;
    } else if (std::strcmp(argv[i], "--digest") == 0) {
      digest = true;
    } else if (std::strcmp(argv[i], "--profile") == 0 && i + 3 < argc) {
      prof_name = argv[++i];
      prof_type = argv[++i];
      prof_runs = std::max(1, std::atoi(argv[++i]));
    } else if (std::strcmp(argv[i], "--construct") == 0 && i + 2 < argc) {
      construct_type = argv[++i];
      construct_n = std::max(1, std::atoi(argv[++i]));
    } else if (std::strcmp(argv[i], "--histogram") == 0) {
      g_histogram = true;
    } else if (std::strcmp(argv[i], "--evict-kb") == 0 && i + 1 < argc) {
      g_evict_kb = static_cast<std::size_t>(std::max(0, std::atoi(argv[++i])));
      g_evict.assign(g_evict_kb * 1024, 0);
    } else if (std::strcmp(argv[i], "--override-every") == 0 && i + 1 < argc) {
      g_override_every = static_cast<std::size_t>(std::max(0, std::atoi(argv[++i])));
    } else if (std::strcmp(argv[i], "--runs") == 0 && i + 1 < argc) {
      g_runs = std::max(1, std::atoi(argv[++i]));
    } else if (std::strcmp(argv[i], "--shared") == 0 && i + 1 < argc) {
      g_shared_dir = argv[++i];
    } else {
      args.push_back(argv[i]);
    }
  }
  if (lock && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    std::fprintf(stderr, "bench_motion: mlockall failed (%s); running unlocked\n",
                 std::strerror(errno));
  }
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;

  auto& progs = programs();
  progs.reserve(7);
  progs.emplace_back("stress_test", load_stress, 1);
  progs.emplace_back("stress_test_x100", load_stress, 100);
  progs.emplace_back("random_2k", load_random, 1);
  progs.emplace_back("random_2k_x100", load_random, 100);
  progs.emplace_back("stress_test_merged", load_stress, 1, true);
  progs.emplace_back("stress_test_x100_merged", load_stress, 100, true);
  progs.emplace_back("random_2k_x100_merged", load_random, 100, true);
  if (digest) {
    print_digests();
    return 0;
  }
  if (prof_runs > 0) return profile(prof_name, prof_type, prof_runs);
  if (construct_n > 0) return construct(construct_type, construct_n);
  for (LazyProgram& p : progs) {
    if (p.merge)
      benchmark::RegisterBenchmark(("LineMerge/" + p.name).c_str(), BM_LineMerge, &p)
          ->Unit(benchmark::kMillisecond);
  }
  // The search type searches ~20–70 µs per cycle: measured on the programs without the
  // 100× refinement only, to keep the run short.
  for (int type = 0; type < 3; ++type) {
    for (LazyProgram& p : progs) {
      if (type == 2 && p.name.find("x100") != std::string::npos) continue;
      const std::string suffix = p.name + "/" + type_name(type);
      benchmark::RegisterBenchmark(("Throughput/" + suffix).c_str(), BM_Throughput, &p, type)
          ->Unit(benchmark::kMillisecond);
    }
    for (LazyProgram& p : progs) {
      if (type == 2 && p.name.find("x100") != std::string::npos) continue;
      const std::string suffix = p.name + "/" + type_name(type);
      benchmark::RegisterBenchmark(("Latency/" + suffix).c_str(), BM_Latency, &p, type)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(1);
    }
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
