// SegmentBuffer::seek (the motion cycle's two cursor moves per cycle, spec 01 P7): a full
// 10 000-item window of fine segments whose lengths vary by ±25 %, the cursor moving by about
// k items per call, with the last call's skip as the hint (as the kernel passes it) and without.
//   bench_seek [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>

#include "planner/buffer.hpp"
#include "planner/segment.hpp"

namespace {

using cncore::planner::Segment;
using cncore::planner::SegmentBuffer;

void BM_Seek(benchmark::State& state) {
  const auto k = static_cast<double>(state.range(0));
  const bool hinted = state.range(1) != 0;
  SegmentBuffer buf(10000);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> len(0.75e-3, 1.25e-3);  // mean 1 µm
  double s = 0;
  while (!buf.full()) {
    Segment seg;
    seg.s0_mm = s;
    seg.length_mm = len(rng);
    s = seg.end_mm();
    buf.push(seg);
  }
  std::uint64_t cur = buf.begin_index(), skip = 1;
  double pos = 0;
  for (auto _ : state) {
    pos += k * 1e-3;
    if (pos >= s) {  // wrap: start over at the window's beginning (untimed in effect: rare)
      pos = 0;
      cur = buf.begin_index();
    }
    const std::uint64_t from = cur;
    cur = hinted ? buf.seek(from, pos, UINT64_MAX, from + skip) : buf.seek(from, pos);
    if (cur > from) skip = cur - from;
    benchmark::DoNotOptimize(cur);
  }
  state.counters["items_per_call"] = k;
}

BENCHMARK(BM_Seek)->ArgNames({"k", "hint"})->ArgsProduct({{1, 8, 69, 500}, {0, 1}});

}  // namespace

BENCHMARK_MAIN();
