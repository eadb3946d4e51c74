// The driver: every sample reaches every observer in order, blocks are announced before they
// move, override steps act at the first cycle with t >= T, and an error in the program stops
// the machine at the end of the last good block before the error is rethrown.
#include "simulation/run.hpp"

#include <gtest/gtest.h>
#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "io/summary.hpp"
#include "io/trajectory_csv.hpp"
#include "recorder.hpp"

// Under AddressSanitizer malloc is ASan's own allocator and glibc's mallinfo2 sees none of it:
// the heap in use is then read from the sanitizer's allocator statistics.
#if defined(__SANITIZE_ADDRESS__)
#define CNCORE_RUN_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CNCORE_RUN_TEST_ASAN 1
#endif
#endif
#ifdef CNCORE_RUN_TEST_ASAN
// From the sanitizer runtime (gcc ships no <sanitizer/allocator_interface.h>).
extern "C" std::size_t __sanitizer_get_current_allocated_bytes();
#endif

namespace cncore::sim {
namespace {

using test::Recorder;

std::string program_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

TEST(RunProgram, DeliversEverySampleToEveryObserver) {
  const std::string p =
      program_file("square.ngc", "G21 G90\nG1 X10 F3000\nG1 Y10\nG1 X0\nG1 Y0\nM30\n");
  Recorder a, b;
  const RunCounts n = run_program(p, default_machine_config(), {}, {&a, &b});
  EXPECT_TRUE(a.finished && b.finished);
  EXPECT_EQ(n.blocks, 4u);
  EXPECT_EQ(n.cycles, a.samples.size());
  ASSERT_EQ(a.samples.size(), b.samples.size());
  ASSERT_GT(a.samples.size(), 10u);
  EXPECT_EQ(a.samples.front().t_s, 0.0);
  for (std::size_t i = 1; i < a.samples.size(); ++i) {
    ASSERT_NEAR(a.samples[i].t_s - a.samples[i - 1].t_s, 0.001, 1e-9);
    ASSERT_EQ(a.samples[i].position, b.samples[i].position);
  }
  // Every motion block is announced before any sample executes its line.
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const std::uint32_t line = a.blocks[k].line;
    for (std::size_t i = 0; i < a.samples_at_block[k]; ++i) {
      ASSERT_NE(a.samples[i].line, line) << "block of line " << line << " announced late";
    }
  }
  EXPECT_NEAR(a.samples.back().position[kX], 0, 1e-9);
  EXPECT_NEAR(a.samples.back().position[kY], 0, 1e-9);
}

TEST(RunProgram, OverrideStepsActAtTheFirstCycleAtOrAfterTheirTime) {
  const std::string p = program_file("long.ngc", "G21 G90\nG1 X200 F6000\nM30\n");
  RunOptions o;
  o.override_steps = {{0.5, 40}, {0.25, 150}};  // unsorted on purpose
  Recorder r;
  run_program(p, default_machine_config(), o, {&r});
  ASSERT_GT(r.samples.size(), 600u);
  for (const auto& s : r.samples) {
    const double expected = s.t_s < 0.25 - 1e-9 ? 100 : (s.t_s < 0.5 - 1e-9 ? 150 : 40);
    ASSERT_NEAR(s.override_pct, expected, 1e-9) << "t = " << s.t_s;
  }
}

TEST(RunProgram, AnErrorStopsAtTheEndOfTheLastGoodBlockThenThrows) {
  const std::string p =
      program_file("error.ngc", "G21 G90\nG1 X10 F3000\nG1 X10 Y10\nG2 X20 Y20\nG1 X0\nM30\n");
  Recorder r;
  try {
    run_program(p, default_machine_config(), {}, {&r});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 4u) << e.formatted();
  }
  EXPECT_FALSE(r.finished);
  ASSERT_FALSE(r.samples.empty());
  // The machine came to rest at X10 Y10, the end of line 3.
  const auto& last = r.samples.back();
  EXPECT_NEAR(last.position[kX], 10, 1e-9);
  EXPECT_NEAR(last.position[kY], 10, 1e-9);
  if (r.samples.size() >= 2) {
    const auto& before = r.samples[r.samples.size() - 2];
    // Arriving at rest: the last cycle moves less than Amax·τ² = 2000·1e-6 = 0.002 mm.
    EXPECT_LT(std::hypot(last.position[kX] - before.position[kX],
                         last.position[kY] - before.position[kY]),
              0.002 + 1e-9);
  }
}

// Streaming: with the trajectory and summary observers attached, the heap in use stops growing
// once the execution-data buffer is full. 60 000 chords of 0.5 mm on a circle (about 300 000
// cycles): the heap late in the run is the heap after 10 000 cycles (glibc mallinfo2), within
// 64 KiB.
struct HeapProbe : SampleObserver {
  std::uint64_t cycles = 0;
  std::size_t early = 0, late_max = 0;
  void on_sample(const motion::Sample&) override {
    if (++cycles % 1000 != 0) return;
#ifdef CNCORE_RUN_TEST_ASAN
    const std::size_t in_use = __sanitizer_get_current_allocated_bytes();
#else
    const std::size_t in_use = mallinfo2().uordblks;
#endif
    if (cycles == 10000) early = in_use;
    if (cycles > 10000) late_max = std::max(late_max, in_use);
  }
};

// Path speed of sample k (mm/s) from the positions: |p_k − p_{k−1}| / τ.
double speed_mm_s(const std::vector<motion::Sample>& s, std::size_t k) {
  return norm(s[k].position.xyz() - s[k - 1].position.xyz()) / 0.001;
}

TEST(RunProgram, DryRunMovesFeedBlocksAtTheDryRunFeedAndRapidsAtTheRapidRate) {
  // A long G1 at F600 (10 mm/s), an arc and a rapid back: dry run at 6000 mm/min (100 mm/s).
  const std::string p =
      program_file("dry.ngc", "G21 G90 G17\nG1 X100 F600\nG2 X120 Y0 I10 J0\nG0 X0 Y0\nM30\n");
  auto top_speed_on_line = [&](const RunOptions& o, std::uint32_t line) {
    Recorder r;
    run_program(p, default_machine_config(), o, {&r});
    double top = 0;
    for (std::size_t k = 1; k < r.samples.size(); ++k)
      if (r.samples[k].line == line) top = std::max(top, speed_mm_s(r.samples, k));
    return top;
  };
  RunOptions dry;
  dry.operator_modes.dry_run_feed_mm_min = 6000;
  EXPECT_NEAR(top_speed_on_line({}, 2), 10, 0.05);
  EXPECT_NEAR(top_speed_on_line(dry, 2), 100, 0.5);
  // The arc (radius 10 mm, √(R·A) = 141 mm/s) runs at the dry-run feed too.
  EXPECT_NEAR(top_speed_on_line(dry, 3), 100, 0.5);
  EXPECT_LT(top_speed_on_line({}, 3), 10.05);
  // The rapid keeps the rapid rate (15 000 mm/min) either way.
  EXPECT_NEAR(top_speed_on_line(dry, 4), 250, 1.5);
  EXPECT_NEAR(top_speed_on_line({}, 4), 250, 1.5);
}

TEST(RunProgram, SingleBlockStopsAtEveryBlockEndAndWaits) {
  // Three collinear G1 blocks: without single block they are one line (merged, no stop).
  const std::string p = program_file("single.ngc", "G21 G90\nG1 X10 F3000\nG1 X20\nG1 X30\nM30\n");
  auto run = [&](const RunOptions& o) {
    Recorder r;
    run_program(p, default_machine_config(), o, {&r});
    return r.samples;
  };
  const auto plain = run({});
  for (const double wait_s : {0.0, 0.2}) {
    RunOptions o;
    o.operator_modes.single_block = true;
    o.operator_modes.single_block_wait_s = wait_s;
    const auto s = run(o);
    for (const double x : {10.0, 20.0}) {
      // The first sample at the block's end, the speed into it, and how long it stays.
      std::size_t k = 1;
      while (k < s.size() && std::abs(s[k].position[kX] - x) > 1e-9) ++k;
      ASSERT_LT(k, s.size()) << "no sample at X" << x << " (wait " << wait_s << " s)";
      EXPECT_LE(speed_mm_s(s, k), 2000 * 0.001 * 1.005) << "X" << x;  // ≤ Amax·τ: at rest
      std::size_t at_rest = 0;
      while (k + at_rest + 1 < s.size() && std::abs(s[k + at_rest + 1].position[kX] - x) <= 1e-9)
        ++at_rest;
      EXPECT_GE(static_cast<double>(at_rest) * 0.001, wait_s - 1e-9) << "X" << x;
      EXPECT_LE(static_cast<double>(at_rest) * 0.001, wait_s + 0.0025) << "X" << x;
    }
    // Two more stops and the waits cost time; the end is the same.
    EXPECT_GT(s.back().t_s, plain.back().t_s + 3 * wait_s);
    EXPECT_NEAR(s.back().position[kX], 30, 1e-9);
  }
  // Without single block the tool passes X10 and X20 at speed.
  std::size_t k = 1;
  while (k < plain.size() && plain[k].position[kX] < 10) ++k;
  EXPECT_GT(speed_mm_s(plain, k), 40);
}

TEST(RunProgram, HeapDoesNotGrowWithProgramLength) {
  std::string text = "G21 G90 G17 F6000\nG1 X100 Y0\n";
  constexpr int kChords = 60000;
  const double r = 100, step = 0.5 / r;  // chord angle for 0.5 mm
  char line[96];
  for (int k = 1; k <= kChords; ++k) {
    std::snprintf(line, sizeof line, "G1 X%.5f Y%.5f\n", r * std::cos(k * step),
                  r * std::sin(k * step));
    text += line;
  }
  text += "M30\n";
  const std::string p = program_file("heap.ngc", text);
  text = std::string();
  text.shrink_to_fit();
  const MachineConfig m = default_machine_config();
  const std::string csv = (std::filesystem::path(CNCORE_TEST_TMP_DIR) / "heap.csv").string();
  io::TrajectoryCsvWriter writer(csv, m, {});
  io::SummaryObserver summary(m, "lookahead");
  HeapProbe probe;
  const RunCounts n = run_program(p, m, {}, {&writer, &summary, &probe});
  ASSERT_EQ(n.blocks, static_cast<std::uint64_t>(kChords + 1));
  ASSERT_GT(probe.cycles, 100000u);
  ASSERT_GT(probe.early, 0u);
  EXPECT_LE(probe.late_max, probe.early + std::size_t{64} * 1024)
      << "heap grew from " << probe.early << " to " << probe.late_max << " bytes";
}

TEST(RunProgram, MissingFileIsAnInputError) {
  Recorder r;
  EXPECT_THROW(run_program("/nonexistent/p.ngc", default_machine_config(), {}, {&r}), InputError);
  EXPECT_TRUE(r.samples.empty());
}

// [motion] merge_tolerance_mm: a program of straight lines cut into 100 pieces each (3–10 µm),
// written with 6 decimals, runs as the lines it describes: the same samples as the original
// within 1 µm (the pieces' wobble is 1 nm).
TEST(RunProgram, MergedPiecesRunAsTheLinesTheyDescribe) {
  const double corners[][2] = {{0, 0}, {1, 0.3}, {1.2, 0.9}, {0.4, 0.95}, {0.3, 0.1}};
  std::string lines = "G21 G90 F6000\n", pieces = lines;
  char buf[96];
  for (std::size_t i = 1; i < std::size(corners); ++i) {
    std::snprintf(buf, sizeof buf, "G1 X%.6f Y%.6f\n", corners[i][0], corners[i][1]);
    lines += buf;
    for (int k = 1; k <= 100; ++k) {
      const double f = k / 100.0;
      std::snprintf(buf, sizeof buf, "G1 X%.6f Y%.6f\n",
                    corners[i - 1][0] + f * (corners[i][0] - corners[i - 1][0]),
                    corners[i - 1][1] + f * (corners[i][1] - corners[i - 1][1]));
      pieces += buf;
    }
  }
  MachineConfig m = default_machine_config();
  m.merge_tolerance_mm = 0.0005;
  Recorder whole, merged, unmerged;
  run_program(program_file("lines.ngc", lines + "M2\n"), m, {}, {&whole});
  const RunCounts n = run_program(program_file("pieces.ngc", pieces + "M2\n"), m, {}, {&merged});
  EXPECT_EQ(n.blocks, 400u);  // the program's blocks, not the kernel's
  // 4 lines of 100 pieces, and M2 (each merged line is followed by its programmed pieces, which
  // observers see for the lines they name).
  const auto ran = std::count_if(merged.blocks.begin(), merged.blocks.end(),
                                 [](const Block& b) { return !b.piece; });
  EXPECT_EQ(ran, 4 + 1);
  EXPECT_EQ(merged.blocks.size(), 4 + 1 + 400u);
  ASSERT_EQ(merged.samples.size(), whole.samples.size());
  for (std::size_t i = 0; i < merged.samples.size(); ++i) {
    ASSERT_LE(norm(merged.samples[i].position.xyz() - whole.samples[i].position.xyz()), 1e-6)
        << "sample " << i;
  }
  m.merge_tolerance_mm = 0;
  run_program(program_file("pieces.ngc", pieces + "M2\n"), m, {}, {&unmerged});
  EXPECT_EQ(unmerged.blocks.size(), 401u);
  EXPECT_GE(unmerged.samples.size(), merged.samples.size());
  std::printf("4 lines in 400 pieces: %zu cycles merged, %zu unmerged, %zu as 4 lines\n",
              merged.samples.size(), unmerged.samples.size(), whole.samples.size());
}

}  // namespace
}  // namespace cncore::sim
