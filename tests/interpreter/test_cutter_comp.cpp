// Cutter radius compensation G41/G42/G41.1/G42.1/G40, measured on the emitted blocks: sampled
// densely, the compensated path of every contour move lies one tool radius from the programmed
// contour (computed here from the contour as written, lines and arcs), on the side asked for;
// the exit move ends at the programmed point; the gouging cases are errors at their line.
#include <gtest/gtest.h>

#include <algorithm>

#include "comp_contour.hpp"
#include "config/tool_table.hpp"
#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

constexpr double kRadius = 3.0;  // D6

std::vector<Block> motion_of(const std::string& text, const Options& o = {}) {
  Interpreter in(Interpreter::FromText{}, text, "comp.ngc", test_machine(), o);
  std::vector<Block> out;
  Block b;
  while (in.next(b)) {
    if (is_motion(b)) out.push_back(b);
  }
  return out;
}

std::string error_of(const std::string& text, const Options& o = {}) {
  try {
    motion_of(text, o);
  } catch (const InputError& e) {
    return e.formatted();
  }
  return "no error";
}

Piece line(P2 from, P2 to) {
  return {from, to, false, false, {}};
}
Piece arc(P2 from, P2 to, bool ccw, P2 c) {
  return {from, to, true, ccw, c};
}

// A closed rectangle 40 × 30 run counter-clockwise from the middle of a side, which is run
// again to beyond the start at the end so that the last corner is a corner too.
std::vector<Piece> rectangle() {
  return {line({20, 0}, {40, 0}), line({40, 0}, {40, 30}), line({40, 30}, {0, 30}),
          line({0, 30}, {0, 0}), line({0, 0}, {30, 0})};
}

// Counter-clockwise: a convex quarter arc, a concave quarter arc (a fillet into the corner),
// and sharp corners on both sides of it.
std::vector<Piece> profile_with_arcs() {
  return {line({10, 0}, {30, 0}),   arc({30, 0}, {40, 10}, true, {30, 10}),
          line({40, 10}, {40, 30}), arc({40, 30}, {30, 40}, false, {40, 40}),
          line({30, 40}, {0, 40}),  line({0, 40}, {0, 0}),
          line({0, 0}, {20, 0})};
}

struct Traced {
  std::vector<Block> blocks;
  std::uint32_t first_line = 0, last_line = 0;  // the contour moves
  P2 exit_to;
};

// Lead in from 10 before the contour's start on its first line, compensate, run the contour,
// G40 and leave 10 away from it on the tool's side.
Traced run_contour(const std::vector<Piece>& pieces, int plane, bool left, const std::string& comp,
                   const Options& o = {}) {
  const PlaneWords pw = plane_words(plane);
  const Piece& first = pieces.front();
  const double len = std::hypot(first.to.a - first.from.a, first.to.b - first.from.b);
  const P2 u{(first.to.a - first.from.a) / len, (first.to.b - first.from.b) / len};
  const Piece& last = pieces.back();
  const double last_len = std::hypot(last.to.a - last.from.a, last.to.b - last.from.b);
  const P2 v{(last.to.a - last.from.a) / last_len, (last.to.b - last.from.b) / last_len};
  const double side = left ? 1 : -1;
  Traced r;
  r.exit_to = {last.to.a - side * 10 * v.b, last.to.b + side * 10 * v.a};
  std::string text = fmt::format("G21 G90 G94 F1000 {}\n", pw.gcode);
  text += fmt::format("G0 {}{} {}{}\n", pw.first_word, first.from.a - 10 * u.a, pw.second_word,
                      first.from.b - 10 * u.b);
  text += comp + "\n";
  text += fmt::format("G1 {}{} {}{}\n", pw.first_word, first.from.a, pw.second_word, first.from.b);
  r.first_line = 5 + static_cast<std::uint32_t>(std::count(comp.begin(), comp.end(), '\n'));
  text += contour_gcode(pieces, pw);
  r.last_line = r.first_line + static_cast<std::uint32_t>(pieces.size()) - 1;
  text += "G40\n";
  text +=
      fmt::format("G1 {}{} {}{}\nM2\n", pw.first_word, r.exit_to.a, pw.second_word, r.exit_to.b);
  r.blocks = motion_of(text, o);
  return r;
}

struct Measured {
  std::size_t samples = 0;
  double worst_radius_error = 0;  // max |distance to the contour − r|
  std::size_t wrong_side = 0;
  std::size_t corner_arcs = 0;  // arcs about a corner of the contour (not programmed arcs)
  double worst_gap = 0;         // max distance from a block's start to the previous end
};

Measured measure(const Traced& r, const std::vector<Piece>& pieces, int plane, bool left,
                 double radius = kRadius) {
  const PlaneWords pw = plane_words(plane);
  Measured m;
  for (std::size_t i = 1; i < r.blocks.size(); ++i) {
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      m.worst_gap = std::max(m.worst_gap, std::fabs(r.blocks[i].start[a] - r.blocks[i - 1].end[a]));
    }
  }
  for (const Block& b : r.blocks) {
    if (b.line < r.first_line || b.line > r.last_line) continue;
    if (b.kind == BlockKind::kArc) {
      AxisVec c;
      c.set_xyz(b.center);
      for (const Piece& p : pieces) {
        if (std::hypot(c[pw.first] - p.from.a, c[pw.second] - p.from.b) < 1e-9) {
          ++m.corner_arcs;
          break;
        }
      }
    }
    for (const P2& q : sample_block(b, pw)) {
      const Foot f = nearest(pieces, q);
      ++m.samples;
      m.worst_radius_error = std::max(m.worst_radius_error, std::fabs(f.distance - radius));
      if (f.at_end) continue;
      const double cross = f.tangent.a * (q.b - f.at.b) - f.tangent.b * (q.a - f.at.a);
      if ((cross > 0) != left) ++m.wrong_side;
    }
  }
  return m;
}

void expect_compensated(const std::vector<Piece>& pieces, int plane, bool left,
                        std::size_t corner_arcs) {
  SCOPED_TRACE(fmt::format("G{} {}", plane, left ? "G41.1" : "G42.1"));
  const Traced r = run_contour(pieces, plane, left, left ? "G41.1 D6" : "G42.1 D6");
  const Measured m = measure(r, pieces, plane, left);
  EXPECT_GT(m.samples, 1000u);
  EXPECT_LT(m.worst_radius_error, 1e-6) << "distance from the programmed contour − radius (mm)";
  EXPECT_EQ(m.wrong_side, 0u);
  EXPECT_EQ(m.corner_arcs, corner_arcs);
  EXPECT_LT(m.worst_gap, 1e-9) << "each block starts where the previous ended";
  const PlaneWords pw = plane_words(plane);
  ASSERT_FALSE(r.blocks.empty());
  const Block& exit = r.blocks.back();
  EXPECT_NEAR(exit.end[pw.first], r.exit_to.a, 1e-9);
  EXPECT_NEAR(exit.end[pw.second], r.exit_to.b, 1e-9);
  EXPECT_NEAR(exit.end[pw.normal], 0.0, 1e-9);
}

// G41 on a counter-clockwise contour keeps the tool inside: every corner is an inside corner
// (no corner arcs); G42 keeps it outside: an arc round each of the four sharp corners.
TEST(CutterComp, RectangleInsideAndOutsideInEachPlane) {
  for (int plane : {17, 18, 19}) {
    expect_compensated(rectangle(), plane, true, 0);
    expect_compensated(rectangle(), plane, false, 4);
  }
}

// Convex and concave arcs with tangent and sharp joins: line-arc and arc-line intersections at
// the inside corners, corner arcs at the outside ones.
TEST(CutterComp, ProfileWithArcsInsideAndOutside) {
  for (int plane : {17, 18}) {
    expect_compensated(profile_with_arcs(), plane, true, 0);
    expect_compensated(profile_with_arcs(), plane, false, 4);
  }
}

TEST(CutterComp, EntryMoveEndsOneRadiusSidewaysOfItsEndPoint) {
  const auto blocks = motion_of("G21 F1000\nG0 X-10 Y0\nG41.1 D6\nG1 X0 Y0\nX40\nG40\nX50\n");
  ASSERT_GE(blocks.size(), 3u);
  // The entry runs from (−10, 0) to (0, 3): perpendicular to its own direction at its end.
  EXPECT_NEAR(blocks[1].start[kX], -10, 1e-12);
  EXPECT_NEAR(blocks[1].end[kX], 0, 1e-12);
  EXPECT_NEAR(blocks[1].end[kY], 3, 1e-12);
  EXPECT_NEAR(blocks[2].end[kY], 3, 1e-12);  // the next line, held parallel
  EXPECT_NEAR(blocks.back().end[kX], 50, 1e-12);
  EXPECT_NEAR(blocks.back().end[kY], 0, 1e-12);
}

TEST(CutterComp, DiameterFromTheToolTableOrTheWord) {
  Options o;
  o.tools = parse_tool_table("T1 D6\nT2 D10\n", "t.tbl");
  const Traced word = run_contour(rectangle(), 17, false, "G42.1 D6");
  const Traced table = run_contour(rectangle(), 17, false, "G42 D1", o);
  const Traced spindle = run_contour(rectangle(), 17, false, "T1 M6 G42", o);
  // A negative diameter puts the tool on the other side.
  const Traced negative = run_contour(rectangle(), 17, false, "G41.1 D-6");
  ASSERT_EQ(word.blocks.size(), table.blocks.size());
  ASSERT_EQ(word.blocks.size(), spindle.blocks.size());
  ASSERT_EQ(word.blocks.size(), negative.blocks.size());
  for (std::size_t i = 0; i < word.blocks.size(); ++i) {
    for (std::size_t a = 0; a < 3; ++a) {
      EXPECT_NEAR(word.blocks[i].end[a], table.blocks[i].end[a], 1e-12);
      EXPECT_NEAR(word.blocks[i].end[a], spindle.blocks[i].end[a], 1e-12);
      EXPECT_NEAR(word.blocks[i].end[a], negative.blocks[i].end[a], 1e-12);
    }
  }
  const Traced d2 = run_contour(rectangle(), 17, false, "G42 D2", o);
  EXPECT_LT(measure(d2, rectangle(), 17, false, 5.0).worst_radius_error, 1e-6);
  // G41.1 D in inch: 0.25 in is a radius of 3.175 mm.
  const Traced inch = run_contour(rectangle(), 17, true, "G20 G41.1 D0.25\nG21");
  EXPECT_LT(measure(inch, rectangle(), 17, true, 3.175).worst_radius_error, 1e-6);
}

TEST(CutterComp, ToolNotInTheTableIsAnError) {
  Options o;
  o.tools = parse_tool_table("T1 D6\n", "t.tbl");
  EXPECT_NE(error_of("G21 F100\nG0 X-10\nG41 D7\nG1 X0\n", o)
                .find("comp.ngc:3:5: error: tool 7 is not in the tool table"),
            std::string::npos)
      << error_of("G21 F100\nG0 X-10\nG41 D7\nG1 X0\n", o);
}

// The gouging checks, each at the line where the program shows it.
TEST(CutterComp, GougingIsAnErrorAtItsLine) {
  struct Case {
    const char* program;
    const char* error;
  };
  const Case cases[] = {
      {"G21 F100\nG0 X0 Y0\nG41.1 D6\nG1 X2 Y0\n",
       "comp.ngc:4:1: error: Length of cutter compensation entry move is not greater than the "
       "tool radius"},
      // An inside corner after a move shorter than the tool's diameter: the 2 mm step cannot
      // be followed.
      {"G21 F100\nG0 X-10 Y0\nG41.1 D6\nG1 X0\nX40\nY2\nX0\n",
       "comp.ngc:7:1: error: Straight feed in concave corner cannot be reached by the tool "
       "without gouging"},
      // An arc of radius 2 with the tool (radius 3) on its inside.
      {"G21 F100\nG0 X-10 Y0\nG41.1 D6\nG1 X0\nX20\nG3 X22 Y2 I0 J2\n",
       "comp.ngc:6:1: error: Tool radius not less than arc radius with comp"},
      // An inside corner into an arc (radius 4, the tool inside it) whose offset circle
      // (radius 1) the offset line does not reach.
      {"G21 F100\nG0 X-10 Y0\nG41.1 D6\nG1 X0\nX20\nG3 X12 Y0 I-4 J0\n",
       "comp.ngc:6:1: error: Arc move in concave corner cannot be reached by the tool without "
       "gouging"},
      {"G21 F100\nG0 X-10\nG41.1 D6\nG1 X0\nX20\nG40\nG2 X30 I5\n",
       "comp.ngc:7:1: error: The move just after exiting cutter compensation mode must be "
       "straight, not an arc"},
      {"G21 F100\nG0 X-10\nG41.1 D6\nG1 X0\nG42.1 D6\n",
       "comp.ngc:5:1: error: cutter radius compensation is already on"},
      {"G21 F100\nG0 X-10\nG41.1 D6\nG1 X0\nG18\n",
       "comp.ngc:5:1: error: change of plane with cutter radius compensation on"},
      {"G21 F100\nG0 X-10\nG41.1 D6\nG3 X0 Y0 I5\n",
       "comp.ngc:4:1: error: the first move with cutter radius compensation must be a straight "
       "line"},
      {"G21 F100\nG0 X-10\nG41.1\n", "comp.ngc:3:1: error: G41.1 without D"},
      {"G21 F100\nG1 X1 D3\n",
       "comp.ngc:2:7: error: D word without G41, G42, G41.1, G42.1, G96, G33 or G76"},
  };
  for (const Case& c : cases) {
    EXPECT_NE(error_of(c.program).find(c.error), std::string::npos)
        << c.program << "\n-> " << error_of(c.program);
  }
}

// A move without motion in the plane (a plunge) between two moves waits with them: the corner
// is still placed, and the plunge happens at the compensated corner point.
TEST(CutterComp, PlungeBetweenMovesStaysAtTheCorner) {
  const auto blocks = motion_of("G21 F100\nG0 X-10 Y0\nG42.1 D6\nG1 X0\nX40\nZ-1\nY30\nG40\nX50\n");
  // entry, X40 (to (40, −3)), Z-1 at (40, −3), the corner arc to (43, 0), Y30 …
  ASSERT_GE(blocks.size(), 6u);
  EXPECT_EQ(blocks[3].line, 6u);
  EXPECT_NEAR(blocks[3].end[kX], 40, 1e-12);
  EXPECT_NEAR(blocks[3].end[kY], -3, 1e-12);
  EXPECT_NEAR(blocks[3].end[kZ], -1, 1e-12);
  EXPECT_EQ(blocks[4].kind, BlockKind::kArc);
  EXPECT_NEAR(blocks[4].end[kX], 43, 1e-12);
  EXPECT_NEAR(blocks[4].end[kY], 0, 1e-12);
}

// `cncore check` goes on after a gouge: the move that could not be placed is dropped, the next
// one enters again, and a later error is still found at its own line.
TEST(CutterComp, CheckingContinuesAfterAGouge) {
  Interpreter in(Interpreter::FromText{},
                 "G21 F100\nG0 X-10 Y0\nG41.1 D6\nG1 X0\nX40\nY2\nX0\nY20\nX-20\nG40\n"
                 "G1 X#<nope>\nM2\n",
                 "comp.ngc", test_machine(), Options{});
  std::vector<std::uint32_t> error_lines;
  std::vector<Block> moves;
  for (;;) {
    try {
      Block b;
      if (!in.next(b)) break;
      if (is_motion(b)) moves.push_back(b);
    } catch (const InputError& e) {
      error_lines.push_back(e.line());
      if (!in.recover()) break;
    }
  }
  EXPECT_EQ(error_lines, (std::vector<std::uint32_t>{7, 11}));
  ASSERT_FALSE(moves.empty());
  // After line 7 the tool enters again towards (0, 20), and X-20 runs on its left at y = 17.
  EXPECT_NEAR(moves.back().end[kX], -20, 1e-9);
  EXPECT_NEAR(moves.back().end[kY], 17, 1e-9);
}

// Where the path turns back on itself the tool goes round the end on an arc about the
// programmed point (here up a line, back down round a G2 half circle the tool is inside of, and
// up and back down again), every sample still one radius from the contour.
TEST(CutterComp, ReversalsGoRoundTheEnd) {
  const std::vector<Piece> contour = {line({20, -5}, {20, 0}), arc({20, 0}, {0, 0}, false, {10, 0}),
                                      line({0, 0}, {0, -10})};
  const Traced r = run_contour(contour, 17, false, "G42.1 D6");
  const Measured m = measure(r, contour, 17, false);
  EXPECT_LT(m.worst_radius_error, 1e-6);
  EXPECT_EQ(m.wrong_side, 0u);
  EXPECT_EQ(m.corner_arcs, 2u);
}

// A line that turns back 178° into a G2 half circle (LinuxCNC's crazy-paths case). With the
// tool outside the arc (G41) the corner is inside: the line stops where it meets the arc's
// offset and every sample stays one radius from the contour. With the tool inside the arc
// (G42) LinuxCNC's 0.05 rad tolerance makes it a reversal: the tool goes round the corner on an
// arc, and where that arc meets the half circle's offset it comes a little nearer the contour.
TEST(CutterComp, NearReversalIntoAnArcFollowsLinuxCnc) {
  const std::vector<Piece> contour = {line({116.7, -94.2}, {0, 0}),
                                      arc({0, 0}, {-36, -48}, false, {-18, -24})};
  for (const bool left : {true, false}) {
    SCOPED_TRACE(left ? "G41.1" : "G42.1");
    const Traced r = run_contour(contour, 17, left, left ? "G41.1 D5" : "G42.1 D5");
    const Measured m = measure(r, contour, 17, left, 2.5);
    EXPECT_GT(m.samples, 100u);
    EXPECT_EQ(m.corner_arcs, left ? 0u : 1u);
    EXPECT_LT(m.worst_radius_error, left ? 1e-6 : 0.01 * 2.5);
    if (left) {
      EXPECT_EQ(m.wrong_side, 0u);
    }
  }
}

// LinuxCNC's own bad/ccomp-arcexit.ngc (CNCORE_SHARED_DIR) fails with the message its first
// line names: an arc right after G40.
TEST(CutterComp, LinuxCncArcExitFailsForItsReason) {
  const std::string path =
      std::string(CNCORE_SHARED_DIR) + "/testdata/linuxcnc-interp/bad/ccomp-arcexit.ngc";
  const std::string text = read_text(path);
  if (text.empty()) GTEST_SKIP() << path << " not found (shared test data absent)";
  const std::string expected = text.substr(1, text.find('\n') - 1);
  EXPECT_NE(error_of(text).find("comp.ngc:7:1: error: " + expected), std::string::npos)
      << error_of(text);
}

}  // namespace
}  // namespace cncore::interp::test
