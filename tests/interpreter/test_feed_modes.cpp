// What F means (G93 inverse time, G94 per minute, G95 per revolution) and the local offset G52,
// measured on the blocks: a G93 move's feed is its length times F, so it lasts 1/F minutes; a
// G95 feed is F times the last S; G52 shifts the active system like LinuxCNC's G92 registers.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

std::vector<Block> moves(const std::string& text) {
  return motion_blocks(text, "feed.ngc");
}

std::string error_of(const std::string& text) {
  return error_of_text(text, "feed.ngc");
}

double length_mm(const Block& b) {
  double d2 = 0;
  for (std::size_t a = 0; a < 3; ++a) d2 += (b.end[a] - b.start[a]) * (b.end[a] - b.start[a]);
  return std::sqrt(d2);
}

TEST(FeedModes, InverseTimeMovesLastOneOverFMinutes) {
  const auto b = moves(
      "G21 G90 G0 X0 Y0 Z0\nG93 G1 X30 Y40 F2\nG1 X30 Y40 Z-10 F0.5\n"
      "G2 X50 Y40 I10 J0 F4\nG94 G1 X0 F600\n");
  ASSERT_EQ(b.size(), 4U);  // (the first G0 is to where the tool is: no move)
  // Time of a move = length / feed; G93 asks 1/F minutes.
  EXPECT_NEAR(length_mm(b[0]) / b[0].feed_mm_min, 1.0 / 2, 1e-12);  // 50 mm in 0.5 min
  EXPECT_NEAR(length_mm(b[1]) / b[1].feed_mm_min, 1.0 / 0.5, 1e-12);
  // The half circle of radius 10: 10π mm in 1/4 min.
  EXPECT_NEAR(b[2].feed_mm_min, 10 * std::numbers::pi * 4, 1e-9);
  EXPECT_DOUBLE_EQ(b[3].feed_mm_min, 600);
}

TEST(FeedModes, PerRevolutionFeedIsFTimesTheSpindleSpeed) {
  const auto b = moves("G21 G90 S1200 M3\nG95 G1 X10 F0.05\nS2000\nG1 X20\nG20 G1 X1 F0.002\n");
  ASSERT_EQ(b.size(), 3U);
  EXPECT_DOUBLE_EQ(b[0].feed_mm_min, 0.05 * 1200);
  EXPECT_DOUBLE_EQ(b[1].feed_mm_min, 0.05 * 2000);
  EXPECT_NEAR(b[2].feed_mm_min, 0.002 * 25.4 * 2000, 1e-9);
}

TEST(FeedModes, ErrorsNameTheMissingWord) {
  EXPECT_EQ(error_of("G93 G1 X1 F1\nG1 X2\n"),
            "feed.ngc:2:1: error: G93 inverse time: every G1/G2/G3 line needs its F word");
  EXPECT_EQ(error_of("G95 G1 X1 F0.1\n"),
            "feed.ngc:1:5: error: G95 feed per revolution without a spindle speed S");
  // A new mode asks for a new F: its meaning changed.
  EXPECT_EQ(error_of("G1 X1 F100\nS1000 G95 G1 X2\n"),
            "feed.ngc:2:11: error: no feed rate: program F (per revolution) after G95");
  EXPECT_EQ(error_of("G93 G81 X1 Y1 Z-1 R1 F1\n"),
            "feed.ngc:1:5: error: canned cycles cannot run in G93 inverse time mode: program "
            "G94 first");
}

TEST(LocalOffset, G52ShiftsTheActiveSystemUntilCleared) {
  const auto b = moves(
      "G21 G90 G10 L2 P1 X5\nG54 G0 X0 Y0\nG52 X10 Y-2\nG0 X0 Y0\nG91 G52 X1\nG90 G0 X0\n"
      "G52 X0 Y0\nG0 X0 Y0\n");
  ASSERT_EQ(b.size(), 4U);
  EXPECT_DOUBLE_EQ(b[0].end[kX], 5);
  EXPECT_DOUBLE_EQ(b[1].end[kX], 15);  // G54 + G52
  EXPECT_DOUBLE_EQ(b[1].end[kY], -2);
  EXPECT_DOUBLE_EQ(b[2].end[kX], 6);  // G52 values are the offset itself, in G91 too
  EXPECT_DOUBLE_EQ(b[3].end[kX], 5);
  EXPECT_DOUBLE_EQ(b[3].end[kY], 0);
}

}  // namespace
}  // namespace cncore::interp::test
