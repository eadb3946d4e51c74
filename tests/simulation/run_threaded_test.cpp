// run_program with the program interpreted on a producer thread gives exactly the
// single-thread run: the same samples bit for bit, the same blocks announced after the same
// number of samples, the same counts, the same error at the same point. Small rings and small
// look-ahead buffers make both sides wait on each other often.
#include <gtest/gtest.h>
#include <malloc.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "program_gen.hpp"
#include "recorder.hpp"
#include "simulation/run.hpp"

namespace cncore::sim {
namespace {

namespace gen = testing::gen;

using test::Recorder;

struct Outcome {
  Recorder rec;
  RunCounts counts;
  std::optional<std::string> error;  // InputError::formatted(), or another exception's what()
};

Outcome run(const std::string& path, const MachineConfig& m, RunOptions o, bool threaded) {
  o.producer_thread = threaded;
  Outcome out;
  try {
    out.counts = run_program(path, m, o, {&out.rec});
  } catch (const InputError& e) {
    out.error = e.formatted();
  } catch (const std::exception& e) {
    out.error = std::string("other: ") + e.what();
  }
  return out;
}

// Bit-exact comparison of every field a sample carries (NaN channels compare by bits too).
bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

void expect_same_sample(const motion::Sample& a, const motion::Sample& b, std::size_t i) {
  ASSERT_TRUE(same_bits(a.t_s, b.t_s)) << "cycle " << i;
  ASSERT_EQ(a.line, b.line) << "cycle " << i;
  for (std::size_t k = 0; k < kMaxAxes; ++k) {
    ASSERT_TRUE(same_bits(a.position[k], b.position[k])) << "cycle " << i << " axis " << k;
    ASSERT_TRUE(same_bits(a.path_position[k], b.path_position[k])) << "cycle " << i;
  }
  ASSERT_TRUE(same_bits(a.feed_mm_min, b.feed_mm_min)) << "cycle " << i;
  ASSERT_TRUE(same_bits(a.override_pct, b.override_pct)) << "cycle " << i;
  ASSERT_TRUE(same_bits(a.correction, b.correction)) << "cycle " << i;
  ASSERT_TRUE(same_bits(a.load_pct, b.load_pct)) << "cycle " << i;
  ASSERT_TRUE(same_bits(a.load_target_pct, b.load_target_pct)) << "cycle " << i;
  ASSERT_EQ(a.aux_letter, b.aux_letter) << "cycle " << i;
  ASSERT_TRUE(same_bits(a.aux_value, b.aux_value)) << "cycle " << i;
  ASSERT_TRUE(same_bits(a.aux_p, b.aux_p)) << "cycle " << i;
}

// Runs both paths and compares everything. Returns the single-thread outcome for further checks.
Outcome expect_identical(const std::string& path, const MachineConfig& m, const RunOptions& o) {
  Outcome single = run(path, m, o, false);
  const Outcome threaded = run(path, m, o, true);
  EXPECT_EQ(single.error, threaded.error) << path;
  EXPECT_EQ(single.rec.finished, threaded.rec.finished) << path;
  EXPECT_EQ(single.counts.blocks, threaded.counts.blocks) << path;
  EXPECT_EQ(single.counts.cycles, threaded.counts.cycles) << path;
  EXPECT_EQ(single.rec.samples_at_block, threaded.rec.samples_at_block) << path;
  EXPECT_EQ(single.rec.blocks.size(), threaded.rec.blocks.size()) << path;
  for (std::size_t i = 0; i < std::min(single.rec.blocks.size(), threaded.rec.blocks.size()); ++i) {
    const Block& a = single.rec.blocks[i];
    const Block& b = threaded.rec.blocks[i];
    if (a.line != b.line || a.kind != b.kind || !(a.end == b.end) ||
        !same_bits(a.feed_mm_min, b.feed_mm_min)) {
      ADD_FAILURE() << path << ": block " << i << " differs (line " << a.line << " vs " << b.line
                    << ")";
      break;
    }
  }
  EXPECT_EQ(single.rec.samples.size(), threaded.rec.samples.size()) << path;
  const std::size_t n = std::min(single.rec.samples.size(), threaded.rec.samples.size());
  for (std::size_t i = 0; i < n; ++i) {
    expect_same_sample(single.rec.samples[i], threaded.rec.samples[i], i);
    if (::testing::Test::HasFatalFailure()) {
      ADD_FAILURE() << path;
      break;
    }
  }
  return single;
}

std::string program_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

// A kernel buffer larger and smaller than the ring, and rings from the smallest (2) up.
struct Variant {
  std::uint32_t lookahead_blocks;
  std::size_t ring_blocks;
};
const Variant kVariants[] = {{10000, 4096}, {10000, 2}, {16, 8}, {5, 64}};

void expect_identical_variants(const std::string& path, MachineConfig m, RunOptions o) {
  for (const Variant& v : kVariants) {
    SCOPED_TRACE("lookahead_blocks " + std::to_string(v.lookahead_blocks) + ", ring " +
                 std::to_string(v.ring_blocks));
    m.lookahead_blocks = v.lookahead_blocks;
    o.ring_blocks = v.ring_blocks;
    expect_identical(path, m, o);
  }
}

TEST(RunThreaded, ExamplesGiveBitIdenticalSamples) {
  int n = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(
           std::string(CNCORE_SOURCE_DIR) + "/examples")) {
    if (e.path().extension() != ".ngc") continue;
    SCOPED_TRACE(e.path().string());
    for (int type = 0; type < 2; ++type) {
      RunOptions o;
      o.kernel.accdec = static_cast<motion::AccDecType>(type);
      expect_identical(e.path().string(), default_machine_config(), o);
    }
    ++n;
  }
  EXPECT_GE(n, 5) << "examples/*.ngc not found";
}

TEST(RunThreaded, GeneratedProgramsGiveBitIdenticalSamples) {
  const std::vector<std::pair<std::string, std::string>> programs = {
      {"zigzag.ngc", gen::zigzag(40, 20, 0.5)},
      {"circle.ngc", gen::circle_chords(2000, 30)},
      {"random.ngc", gen::random_path(7, 1500, 0.05, 1.0, 120)},
      {"random_fine.ngc", gen::random_path(3, 200, 0.2, 2.0, 90, 20)},
      {"raster.ngc", gen::raster_3d(20, 10, 1, 0.2)},
  };
  for (const auto& [name, text] : programs) {
    SCOPED_TRACE(name);
    const std::string p = program_file(name, text);
    for (int type = 0; type < 2; ++type) {
      RunOptions o;
      o.kernel.accdec = static_cast<motion::AccDecType>(type);
      expect_identical_variants(p, default_machine_config(), o);
    }
  }
  std::ostringstream cam;
  gen::cam_like(cam, 5000, 5);
  expect_identical_variants(program_file("cam.ngc", cam.str()), default_machine_config(), {});
}

TEST(RunThreaded, DwellsAuxEventsExactStopsAndOverrideStepsGiveBitIdenticalSamples) {
  const std::string p =
      program_file("events.ngc",
                   "G21 G90 G17\nG1 X10 F3000\nG4 P0.05\nM3 S12000\nG1 X20 Y5\nG9 G1 X25\nM0\n"
                   "G61.1\nG1 X30\nG1 Y10\nG64\nG2 X40 Y20 I5 J5\nT2 M6\nG1 X0 Y0\nM5\nM30\n");
  RunOptions o;
  o.override_steps = {{0.02, 50}, {0.1, 0}, {0.15, 180}, {0.3, 100}};
  expect_identical_variants(p, default_machine_config(), o);
  o.kernel.mode = motion::Mode::kStop;
  expect_identical_variants(p, default_machine_config(), o);
}

TEST(RunThreaded, DirectionCorrectionSplittingArcsGivesBitIdenticalSamples) {
  // Helices whose direction ratio varies along the arc: split into sub-arcs by the producer.
  const std::string p =
      program_file("helix.ngc",
                   "G21 G90 G17\nG1 X10 F2000\nG18 G2 X30 Z0 I10 K0\nG19 G3 X35 Y20 Z0 J10 K0\n"
                   "G17 G2 X15 Y20 Z-10 I-10 J0 P3\nM30\n");
  MachineConfig m = default_machine_config();
  m.direction_correction.enabled = true;
  m.direction_correction.arc_step_deg = 2;
  const Outcome single = expect_identical(p, m, {});
  // The stage really split the arcs (more kernel blocks than source motion blocks).
  EXPECT_GT(single.rec.blocks.size(), 3 * single.counts.blocks);
  EXPECT_FALSE(single.error.has_value()) << *single.error;
}

TEST(RunThreaded, AnErrorMidProgramStopsAtTheSamePointOnBothPaths) {
  // 3000 good blocks, then an arc without a centre: the producer has long read the error
  // when the cycle reaches it.
  std::string text = gen::random_path(11, 3000, 0.2, 2.0, 60);
  text.insert(text.rfind("M30"), "G2 X20 Y20\n");
  const std::string p = program_file("error_mid.ngc", text);
  for (const Variant& v : kVariants) {
    MachineConfig m = default_machine_config();
    m.lookahead_blocks = v.lookahead_blocks;
    RunOptions o;
    o.ring_blocks = v.ring_blocks;
    const Outcome single = expect_identical(p, m, o);
    ASSERT_TRUE(single.error.has_value());
    EXPECT_NE(single.error->find("error"), std::string::npos) << *single.error;
    EXPECT_FALSE(single.rec.finished);
    EXPECT_GT(single.rec.samples.size(), 1000u);
  }
}

// A deterministic controller that changes the override from what the cycle measured (the
// adaptive controller's interface): the feedback runs on the cycle's thread on both paths.
struct SpeedFeedback : CycleController {
  double on_cycle(motion::Sample& s, double operator_override_pct) noexcept override {
    s.load_pct = s.feed_mm_min / 100;
    return std::fmod(s.feed_mm_min, 97.0) < 40 ? 0.5 * operator_override_pct
                                               : operator_override_pct;
  }
};

TEST(RunThreaded, CycleControllerGivesBitIdenticalSamples) {
  const std::string p = program_file("feedback.ngc", gen::random_path(5, 800, 0.2, 3.0, 45));
  SpeedFeedback c;
  RunOptions o;
  o.cycle_controller = &c;
  o.override_steps = {{0.5, 120}};
  expect_identical_variants(p, default_machine_config(), o);
}

// An observer that throws mid-run: the producer thread, blocked on a full ring, is stopped and
// joined (the test would hang otherwise) and the exception reaches the caller.
struct Throwing : SampleObserver {
  std::size_t n = 0;
  void on_sample(const motion::Sample&) override {
    if (++n == 500) throw std::runtime_error("observer failed");
  }
};

TEST(RunThreaded, AnObserverThatThrowsStopsTheProducer) {
  const std::string p = program_file("long.ngc", gen::random_path(9, 20000, 0.2, 2.0, 60));
  for (std::size_t ring : {std::size_t{2}, std::size_t{4096}}) {
    Throwing t;
    RunOptions o;
    o.ring_blocks = ring;
    EXPECT_THROW(run_program(p, default_machine_config(), o, {&t}), std::runtime_error);
    EXPECT_EQ(t.n, 500u);
  }
}

#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
// Memory stays flat with the producer thread: the ring is allocated once, the producer's
// interpreter streams. glibc's mallinfo2 sums every arena (the producer thread allocates in
// its own). 60 000 short segments (~400 000 cycles): the heap late in the run stays within 64 KiB
// of the heap after 10 000 cycles.
struct HeapProbe : SampleObserver {
  std::uint64_t cycles = 0;
  std::size_t early = 0, late_max = 0;
  void on_sample(const motion::Sample&) override {
    if (++cycles % 1000 != 0) return;
    const std::size_t in_use = mallinfo2().uordblks;
    if (cycles == 10000) early = in_use;
    if (cycles > 10000) late_max = std::max(late_max, in_use);
  }
};

TEST(RunThreaded, HeapDoesNotGrowWithProgramLength) {
  const std::string p =
      program_file("heap_threaded.ngc", gen::random_path(13, 60000, 0.2, 2.0, 60));
  HeapProbe probe;
  RunOptions o;
  o.producer_thread = true;
  const RunCounts n = run_program(p, default_machine_config(), o, {&probe});
  ASSERT_GE(n.blocks, 60000u);
  ASSERT_GT(probe.cycles, 100000u);
  ASSERT_GT(probe.early, 0u);
  EXPECT_LE(probe.late_max, probe.early + 64 * 1024)
      << "heap grew from " << probe.early << " to " << probe.late_max << " bytes";
}
#endif

TEST(RunThreaded, RingCapacityMustBeAPowerOfTwo) {
  const std::string p = program_file("short.ngc", "G1 X1 F1000\nM30\n");
  RunOptions o;
  o.producer_thread = true;
  o.ring_blocks = 100;
  EXPECT_THROW(run_program(p, default_machine_config(), o, {}), std::invalid_argument);
}

}  // namespace
}  // namespace cncore::sim
