// The shared third-party corpus (../shared/testdata/gcode, CNCORE_SHARED_DIR): every program
// either interprets completely or stops with an error that names the unsupported feature (or
// the genuine mistake in the program). The expected outcome of each file is listed here, so a
// change in behaviour fails; docs/gcode.md keeps the same table with the reasons.
#include <gtest/gtest.h>

#include <filesystem>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

namespace fs = std::filesystem;

struct CorpusCase {
  const char* file;
  const char* error;  // nullptr: interprets completely; else a fragment of the error message
  std::size_t min_motion_blocks;
};

const CorpusCase kCorpus[] = {
    {"camotics/bear.nc", nullptr, 15000},
    {"camotics/botomata_bottom.nc", nullptr, 6000},
    {"camotics/compass.ngc", nullptr, 2900},
    {"camotics/genes-encoder.ngc", nullptr, 4000},
    {"camotics/heart.ngc", nullptr, 160},
    {"camotics/locket_outside.ngc", nullptr, 10000},
    {"camotics/slant_test.nc", nullptr, 15},
    {"camotics/tiny_cat_outline.ngc", nullptr, 2800},
    {"camotics/vcarve.ngc", nullptr, 3700},
    {"camotics/wave.gcode", nullptr, 1100},
    // N624 "G3 X21 Y-20 I20 J21": radius 29.000 at the start, 27.586 at the end (LinuxCNC
    // rejects it too).
    {"cncjs/Circle_Diamond_Square_Calibration.gcode",
     "radius to the end of the arc differs from the radius to the start", 0},
    {"cncjs/arc-xz-plane.gcode", nullptr, 1},
    {"cncjs/arc-yz-plane.gcode", nullptr, 1},
    {"cncjs/circle-inch.gcode", nullptr, 8},
    // The "G2 J-1.1" full circles work; N55 "X.75" is then a modal G2 without a centre
    // (LinuxCNC and grbl reject it too).
    {"cncjs/full-circle-without-xyz.gcode", "G2 arc without centre (I J K) or radius (R)", 0},
    {"cncjs/helical-thread-milling.gcode", nullptr, 12},
    {"grbl/HelloWorld_cambam.nc", nullptr, 300},
    {"grbl/SO2_helloworld.nc", nullptr, 750},
    {"grbl/braid_cut2d.nc", nullptr, 2500},
    {"grbl/braid_test.gcode", nullptr, 2300},
    {"linuxcnc-tp/Cereal.ngc", nullptr, 2200},
    {"linuxcnc-tp/arc_time.ngc", nullptr, 8},
    {"linuxcnc-tp/circle_small_segments_ncd.ngc", nullptr, 9990},
    {"linuxcnc-tp/full_xy.ngc", nullptr, 6},  // G10 L2 R60: a rotated G54
    {"linuxcnc-tp/full_xz.ngc", nullptr, 3},  // G18 and G19 arcs turned with G10 L2 R60
    {"linuxcnc-tp/full_yz.ngc", nullptr, 3},
    {"linuxcnc-tp/line-contouring-xz.ngc", nullptr, 1390},
    {"linuxcnc-tp/short_segments_0.001.ngc", nullptr, 2990},
    {"linuxcnc-tp/tight-corner-tolerance.ngc", nullptr, 220},
    {"linuxcnc-tp/zigzag_0.002_0.0005.ngc", nullptr, 2000},
    {"linuxcnc/3dtest.ngc", nullptr, 45},
    {"linuxcnc/arcspiral.ngc", nullptr, 1000},
    {"linuxcnc/cds.ngc", nullptr, 260},
    {"linuxcnc/daisy.ngc", "A axis is not configured on this machine", 0},
    {"linuxcnc/factorial.ngc", nullptr, 0},
    {"linuxcnc/flowsnake.ngc", nullptr, 3000},
    {"linuxcnc/spiral.ngc", "polar coordinates ('@' word) are not supported", 0},
    {"linuxcnc/useful-subroutines.ngc", nullptr, 58},
    {"ugs/ShapeOko_Calibration_Pattern_01b.ngc", nullptr, 4500},
    {"ugs/arc_rword_test.gcode", nullptr, 200},
    {"ugs/enclosure.nc", nullptr, 4300},
    {"ugs/g17-g18-g19.gcode", nullptr, 6},
    {"ugs/spiral.gcode", nullptr, 6},
    {"ugs/stress_test.gcode", nullptr, 11990},
};

fs::path corpus_dir() {
  return fs::path(CNCORE_SHARED_DIR) / "testdata" / "gcode";
}

class Corpus : public testing::TestWithParam<CorpusCase> {};

TEST_P(Corpus, InterpretsOrNamesTheUnsupportedFeature) {
  const CorpusCase& c = GetParam();
  const fs::path path = corpus_dir() / c.file;
  if (!fs::exists(path)) GTEST_SKIP() << "shared corpus not found: " << path;
  const MachineConfig m = test_machine();
  std::size_t motion = 0;
  bool have_prev = false;
  AxisVec prev_end;
  try {
    Interpreter in(path.string(), m, Options{});
    Block b;
    while (in.next(b)) {
      if (b.kind == BlockKind::kRapid || b.kind == BlockKind::kLine || b.kind == BlockKind::kArc) {
        if (have_prev) {
          ASSERT_EQ(b.start, prev_end) << format_block(b, m);
        }
        prev_end = b.end;
        have_prev = true;
        ++motion;
      }
    }
  } catch (const InputError& e) {
    ASSERT_NE(c.error, nullptr) << "unexpected error: " << e.formatted();
    EXPECT_NE(std::string(e.what()).find(c.error), std::string::npos) << e.formatted();
    EXPECT_GT(e.line(), 0u);
    EXPECT_GT(e.col(), 0u);
    return;
  }
  EXPECT_EQ(c.error, nullptr) << "expected the error '" << (c.error ? c.error : "") << "'";
  EXPECT_GE(motion, c.min_motion_blocks);
}

std::string corpus_name(const testing::TestParamInfo<CorpusCase>& info) {
  std::string n = info.param.file;
  for (char& ch : n) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  return n;
}

INSTANTIATE_TEST_SUITE_P(Interpreter, Corpus, testing::ValuesIn(kCorpus), corpus_name);

// Every program of the corpus folder is listed above (a new file needs a decision).
TEST(CorpusList, CoversEveryProgramInTheFolder) {
  if (!fs::exists(corpus_dir())) GTEST_SKIP() << "shared corpus not found: " << corpus_dir();
  for (const auto& e : fs::recursive_directory_iterator(corpus_dir())) {
    const std::string ext = e.path().extension().string();
    if (ext != ".ngc" && ext != ".nc" && ext != ".gcode") continue;
    const std::string rel = fs::relative(e.path(), corpus_dir()).string();
    bool listed = false;
    for (const auto& c : kCorpus) listed = listed || rel == c.file;
    EXPECT_TRUE(listed) << rel << " is not in the corpus list";
  }
}

}  // namespace
}  // namespace cncore::interp::test
