// The lathe cycles G70, G71 and G72 measured on the emitted blocks against the profile the test
// writes: the roughing never comes closer to the part than the allowance D, leaves no more
// than D on any point of it, cuts at depths of I and retracts at 45° by R; the finishing pass
// runs on the profile (or at its offsets); A and C round and chamfer corners; and the errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>

#include "comp_contour.hpp"
#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

const PlaneWords kZX = plane_words(18);  // a = Z, b = X

std::vector<Block> blocks(const std::string& text) {
  return motion_blocks(text, "lathe.ngc");
}

std::string error_of(const std::string& text) {
  return error_of_text(text, "lathe.ngc");
}

bool rapid(const Block& b) {
  return b.kind == BlockKind::kRapid;
}

P2 zx(const AxisVec& v) {
  return {v[kZX.first], v[kZX.second]};
}

Piece line(P2 from, P2 to) {
  Piece p;
  p.from = from;
  p.to = to;
  return p;
}

Piece arc(P2 from, P2 to, bool ccw, P2 c) {
  Piece p = line(from, to);
  p.arc = true;
  p.ccw = ccw;
  p.c = c;
  return p;
}

Piece piece_of(const Block& b) {
  Piece p = line(zx(b.start), zx(b.end));
  if (b.kind == BlockKind::kArc) {
    AxisVec c;
    c.set_xyz(b.center);
    AxisVec n;
    n.set_xyz(b.normal);
    p.arc = true;
    p.c = zx(c);
    p.ccw = n[kZX.normal] > 0;
  }
  return p;
}

// Points along the profile, each at least `margin` from its piece's ends.
std::vector<P2> profile_points(const std::vector<Piece>& profile, double margin) {
  std::vector<P2> out;
  for (const Piece& p : profile) {
    Block b;
    b.kind = p.arc ? BlockKind::kArc : BlockKind::kLine;
    b.start[kZX.first] = p.from.a;
    b.start[kZX.second] = p.from.b;
    b.end[kZX.first] = p.to.a;
    b.end[kZX.second] = p.to.b;
    if (p.arc) {
      AxisVec c, n;
      c[kZX.first] = p.c.a;
      c[kZX.second] = p.c.b;
      n[kZX.normal] = p.ccw ? 1 : -1;
      b.center = c.xyz();
      b.normal = n.xyz();
    }
    for (const P2& q : sample_block(b, kZX)) {
      if (std::hypot(q.a - p.from.a, q.b - p.from.b) >= margin &&
          std::hypot(q.a - p.to.a, q.b - p.to.b) >= margin) {
        out.push_back(q);
      }
    }
  }
  return out;
}

struct Measured {
  double closest = 1e300;     // of any move to the profile
  bool entered_part = false;  // a sample inside the part (by more than 1e-6)
  // The most stock left: over the profile (away from its corners, where an inside corner
  // keeps up to D·√2), the distance to the nearest cut.
  double most_left = 0;
};

Measured measure(const std::vector<Block>& moves, const std::vector<Piece>& profile, double d,
                 const std::function<bool(P2)>& inside_part) {
  Measured m;
  std::vector<Piece> feeds;
  for (const Block& b : moves) {
    for (const P2& q : sample_block(b, kZX)) {
      const double far = nearest(profile, q).distance;
      m.closest = std::min(m.closest, far);
      if (inside_part(q) && far > 1e-6) m.entered_part = true;
    }
    if (!rapid(b)) feeds.push_back(piece_of(b));
  }
  for (const P2& p : profile_points(profile, 2 * d)) {
    m.most_left = std::max(m.most_left, nearest(feeds, p).distance);
  }
  return m;
}

// A shaft: Ø10 for 10 mm, a concave R3 shoulder to Ø16, a face to Ø20, Ø20 to Z-25 (radii).
const std::vector<Piece> kShaft = {
    line({0, 5}, {-10, 5}),
    arc({-10, 5}, {-13, 8}, false, {-10, 8}),
    line({-13, 8}, {-13, 10}),
    line({-13, 10}, {-25, 10}),
};
// The same, closed by the wall at Z-25 the cycle adds up to the start's X (stock Ø22).
const std::vector<Piece> kShaftClosed = {
    kShaft[0], kShaft[1], kShaft[2], kShaft[3], line({-25, 10}, {-25, 11}),
};
constexpr const char* kShaftSub =
    "o10 sub\nG1 X5 Z0\nZ-10\nG2 X8 Z-13 I3 K0\nG1 X10\nZ-25\no10 endsub\n";

double shaft_x(double z) {
  if (z > -10) return 5;
  if (z > -13) return 8 - std::sqrt(std::max(0.0, 9 - (z + 10) * (z + 10)));
  return 10;
}
bool inside_shaft(P2 q) {
  return q.a < -1e-9 && q.a > -25 + 1e-9 && q.b < shaft_x(q.a) - 1e-9;
}

TEST(LatheCycles, G71RoughsToTheAllowanceInPassesOfIAndRetractsAt45Degrees) {
  const auto moves = blocks(std::string(kShaftSub) +
                            "G18 G21 G90 G8 F200\nG0 X15 Z5\nG71 Q10 X12 Z2 D0.2 I1 R0.5\n");
  const Measured m = measure(moves, kShaftClosed, 0.2, inside_shaft);
  EXPECT_FALSE(m.entered_part);
  EXPECT_GE(m.closest, 0.2 - 1e-6) << "no move comes closer to the part than D";
  EXPECT_LE(m.most_left, 0.2 + 1e-6) << "every point of the part is cut to D";
  // The passes along −Z: at 12, 11, … (one I apart), the last one on the offset contour.
  std::set<double, std::greater<>> levels;
  std::size_t retracts = 0;
  for (std::size_t i = 0; i < moves.size(); ++i) {
    const Block& b = moves[i];
    const P2 s = zx(b.start), e = zx(b.end);
    if (!rapid(b) && b.kind == BlockKind::kLine && std::fabs(e.b - s.b) < 1e-9 &&
        e.a < s.a - 1e-9) {
      levels.insert(std::round(s.b * 1e6) / 1e6);
    }
    if (rapid(b) && std::fabs(std::fabs(e.a - s.a) - 0.5) < 1e-9 &&
        std::fabs(e.b - s.b - 0.5) < 1e-9) {
      ++retracts;
    }
  }
  // 12 … 6: the roughing passes; 10.2 and 5.2: the contour on Ø20 and Ø10, D from them.
  const std::set<double, std::greater<>> expected = {12, 11, 10.2, 10, 9, 8, 7, 6, 5.2};
  EXPECT_EQ(levels, expected);
  EXPECT_GE(retracts, 7U) << "each roughing pass leaves by R at 45°";
}

TEST(LatheCycles, G70FinishesOnTheProfileAndAtItsOffsets) {
  const std::string head = std::string(kShaftSub) + "G18 G21 G90 G8 F100\nG0 X15 Z5\n";
  {
    const auto moves = blocks(head + "G70 Q10 X12 Z2\n");
    std::vector<Block> cut;
    for (const Block& b : moves) {
      if (!rapid(b) && zx(b.start).a <= 1e-9) cut.push_back(b);
    }
    const Measured m = measure(cut, kShaft, 0, inside_shaft);
    EXPECT_LE(m.closest, 1e-9);
    EXPECT_LE(m.most_left, 1e-6) << "the finishing pass runs over the whole profile";
    double worst = 0;
    for (const Block& b : cut) {
      for (const P2& q : sample_block(b, kZX)) worst = std::max(worst, nearest(kShaft, q).distance);
    }
    EXPECT_LE(worst, 1e-6) << "and on it";
  }
  // P2 D1 E0: passes at (P − p)·(D − E)/P + E, p = 1 … P: 0.5 mm, then on the profile.
  const auto moves = blocks(head + "G70 Q10 X12 Z2 P2 D1 E0\n");
  std::vector<Block> first;  // the feed moves up to the rapid back to the start
  for (const Block& b : moves) {
    if (!rapid(b)) {
      first.push_back(b);
    } else if (!first.empty()) {
      break;
    }
  }
  const Measured m = measure(first, kShaft, 0.5, inside_shaft);
  EXPECT_FALSE(m.entered_part);
  EXPECT_NEAR(m.closest, 0.5, 1e-6);
  EXPECT_LE(m.most_left, 0.5 + 1e-6);
  std::size_t on_profile = 0;
  for (const Block& b : moves) {
    const double far = nearest(kShaft, zx(b.end)).distance;
    if (!rapid(b) && far < 1e-6) ++on_profile;
  }
  EXPECT_GE(on_profile, kShaft.size());
}

// A profile line before any G0–G3 is a straight segment, as LinuxCNC reads it: the same
// profile with and without its first G1 gives the same cycle.
TEST(LatheCycles, AProfileLineWithoutAMotionCodeIsStraight) {
  const std::string tail = "G18 G21 G90 G8 F200\nG0 X15 Z5\nG71 Q10 X12 Z2 D0.2 I1 R0.5\n";
  std::string bare = kShaftSub;
  bare.replace(bare.find("G1 X5"), 2, "");
  const auto with = blocks(std::string(kShaftSub) + tail);
  const auto without = blocks(bare + tail);
  ASSERT_EQ(with.size(), without.size());
  ASSERT_GT(with.size(), 10u);
  for (std::size_t i = 0; i < with.size(); ++i) {
    for (std::size_t a = 0; a < 3; ++a) EXPECT_NEAR(with[i].end[a], without[i].end[a], 1e-12);
  }
}

// A face stepped from Z-6 at the centre to Z-3 at radius 10, roughed by passes along X.
TEST(LatheCycles, G72FacesInPassesAlongX) {
  const std::vector<Piece> face = {
      line({-6, 0}, {-6, 10}), line({-6, 10}, {-3, 10}), line({-3, 10}, {-3, 20}),
      line({-3, 20}, {0, 20}),  // the stock's diameter (G72 closes the profile up to Z1)
  };
  auto inside = [](P2 q) {
    const double surface = q.b < 10 ? -6 : -3;
    return q.b > 1e-9 && q.b < 20 - 1e-9 && q.a < surface - 1e-9;
  };
  const auto moves = blocks(
      "o20 sub\nG1 X0 Z-6\nX10\nZ-3\nX20\no20 endsub\nG18 G21 G90 G8 F150\nG0 X25 Z4\n"
      "G72 Q20 X22 Z1 D0.3 I1.5 R0.4\n");
  const Measured m = measure(moves, face, 0.3, inside);
  EXPECT_FALSE(m.entered_part);
  EXPECT_GE(m.closest, 0.3 - 1e-6);
  EXPECT_LE(m.most_left, 0.3 + 1e-6);
  std::set<double, std::greater<>> levels;  // Z of the passes along X
  for (const Block& b : moves) {
    const P2 s = zx(b.start), e = zx(b.end);
    if (!rapid(b) && std::fabs(e.a - s.a) < 1e-9 && std::fabs(e.b - s.b) > 1e-9) {
      levels.insert(std::round(s.a * 1e6) / 1e6);
    }
  }
  // 1 … −5 one I apart from the start; −2.7 and −5.7: the contour, D above the two faces.
  const std::set<double, std::greater<>> expected = {1, -0.5, -2, -2.7, -3.5, -5, -5.7};
  EXPECT_EQ(levels, expected);
}

// C1 chamfers the inside corner at X10 Z-5 (the path meets its two edges 1 mm from it); A2
// rounds the one at X12 Z-10 with a radius of 2.
TEST(LatheCycles, CornersAreChamferedAndRounded) {
  const auto moves = blocks(
      "o30 sub\nG1 X10 Z0\nZ-5 C1\nX12\nZ-10 A2\nX16\nZ-20\no30 endsub\n"
      "G18 G21 G90 G8 F100\nG0 X20 Z3\nG70 Q30 X20 Z2\n");
  std::vector<P2> ends;
  std::size_t arcs = 0;
  for (const Block& b : moves) {
    ends.push_back(zx(b.end));
    if (b.kind == BlockKind::kArc) {
      ++arcs;
      AxisVec c;
      c.set_xyz(b.center);
      EXPECT_NEAR(zx(c).a, -8, 1e-6);
      EXPECT_NEAR(zx(c).b, 14, 1e-6);
    }
  }
  auto reached = [&](P2 p) {
    return std::ranges::any_of(ends, [&](P2 q) { return std::hypot(q.a - p.a, q.b - p.b) < 1e-6; });
  };
  EXPECT_TRUE(reached({-4, 10})) << "chamfer start on the diameter";
  EXPECT_TRUE(reached({-5, 11})) << "chamfer end on the face";
  EXPECT_FALSE(reached({-5, 10}));
  EXPECT_EQ(arcs, 1U);
  EXPECT_TRUE(reached({-8, 12})) << "the rounding starts on the diameter";
  EXPECT_TRUE(reached({-10, 14})) << "and ends on the face";
}

TEST(LatheCycles, Errors) {
  const std::string sub = "o10 sub\nG1 X5 Z0\nZ-10\nX10\no10 endsub\n";
  EXPECT_NE(
      error_of(sub + "G18 G0 X12 Z2\nG71 X12 Z2 I1\n").find("lathe.ngc:7:1: error: G71 without Q"),
      std::string::npos);
  EXPECT_NE(error_of(sub + "G17 G0 X12 Z2\nG71 Q10 X12 Z2\n")
                .find("lathe.ngc:7:1: error: G71 works in the ZX plane only"),
            std::string::npos);
  EXPECT_NE(error_of(sub + "G18 G0 X12 Z2\nG71 Q11 X12 Z2\n").find("lathe.ngc:7:"),
            std::string::npos);
  EXPECT_NE(
      error_of(sub + "G18 G0 X12 Z2\nG71 Q10 X12 Z2 I0\n").find("I (depth of cut) must be > 0"),
      std::string::npos);
  EXPECT_NE(
      error_of("o10 sub\nG1 X5 Z0\nZ-10\nZ-5\nX10\no10 endsub\nG18 G0 X12 Z2\nG71 Q10 X12 Z2\n")
          .find("lathe.ngc:8:1: error: G71: the profile is not monotonic"),
      std::string::npos);
  EXPECT_NE(error_of("o10 sub\nG1 X5 Z0\nG81 Z-1 R1\no10 endsub\nG18 G0 X12 Z2\nG71 Q10 X12 Z2\n")
                .find("lathe.ngc:3:1: error: G81 in a lathe cycle's profile"),
            std::string::npos);
  EXPECT_NE(error_of(sub + "G18 G0 X12 Z2\nG41.1 D1\nG71 Q10 X12 Z2\n")
                .find("with cutter radius compensation on"),
            std::string::npos);
  EXPECT_NE(error_of("G18 G0 U1\n").find("U axis is not supported"), std::string::npos);
  EXPECT_NE(
      error_of("o10 sub\nG1 X5 Z0\nZ-0.0005\no10 endsub\nG18 G0 X12 Z2 F100\nG70 Q10 X12 Z2\n")
          .find("lathe.ngc:6:1: error: G70: the profile has no segment longer than 0.001"),
      std::string::npos);
}

}  // namespace
}  // namespace cncore::interp::test
