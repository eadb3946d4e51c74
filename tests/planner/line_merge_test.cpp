// The collinear-piece stage: what comes out is measured against what went in (vertices kept,
// distances of every dropped vertex to the output polyline, order of the other blocks).
#include "planner/line_merge.hpp"

#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "planner/segment.hpp"

namespace cncore::planner {
namespace {

constexpr double kTol = 0.0005;
constexpr double kTurn = 0.008;  // the built-in machine's: 2·asin(2 mm/s / (2·250 mm/s))

Block line(Vec3 from, Vec3 to, double feed = 6000, BlockKind kind = BlockKind::kLine) {
  Block b;
  b.kind = kind;
  b.start.set_xyz(from);
  b.end.set_xyz(to);
  b.feed_mm_min = kind == BlockKind::kRapid ? 0 : feed;
  return b;
}

Vec3 rounded(Vec3 p, double q) {
  return {std::round(p.x / q) * q, std::round(p.y / q) * q, std::round(p.z / q) * q};
}

// What the planner takes (the pieces that follow a merged line are left out); `pieces`, if
// given, gets those.
std::vector<Block> run(LineMerger& m, const std::vector<Block>& in,
                       std::vector<Block>* pieces = nullptr) {
  std::vector<Block> out;
  Block b;
  auto take = [&] {
    while (m.next(b)) {
      if (!b.piece) {
        out.push_back(b);
      } else if (pieces != nullptr) {
        pieces->push_back(b);
      }
    }
  };
  for (const Block& x : in) {
    m.put(x);
    take();
  }
  m.finish();
  take();
  return out;
}

// Distance from p to the segment [a, b].
double distance(Vec3 p, Vec3 a, Vec3 b) {
  const Vec3 d = b - a;
  const double l2 = dot(d, d);
  const double t = l2 > 0 ? std::clamp(dot(p - a, d) / l2, 0.0, 1.0) : 0.0;
  return norm(p - (a + t * d));
}

// Every input vertex lies within `tol` of the output block that covers it, output vertices are
// input vertices, and both polylines start and end at the same points.
void expect_covers(const std::vector<Block>& in, const std::vector<Block>& out, double tol) {
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.front().start, in.front().start);
  EXPECT_EQ(out.back().end, in.back().end);
  std::size_t k = 0;
  for (const Block& o : out) {
    ASSERT_LT(k, in.size());
    ASSERT_EQ(o.start, in[k].start) << "output block starts at no input vertex";
    while (k < in.size() && in[k].end != o.end) {
      // (+1e-9 mm: the rounding of a distance computed from coordinates of metres.)
      EXPECT_LE(distance(in[k].end.xyz(), o.start.xyz(), o.end.xyz()), tol + 1e-9);
      ++k;
    }
    ASSERT_LT(k, in.size()) << "output block ends at no input vertex";
    ++k;
  }
  EXPECT_EQ(k, in.size());
}

TEST(LineMerge, RoundedPiecesOfALineBecomeTheLine) {
  // 1 mm along a skew direction, cut into 200 pieces of 5 µm written with 6 decimals.
  const Vec3 a{0.1, -0.2, 3}, dir{0.6, -0.64, 0.48};
  std::vector<Block> in;
  Vec3 p = a;
  for (int i = 1; i <= 200; ++i) {
    const Vec3 q = rounded(a + (0.005 * i) * dir, 1e-6);
    in.push_back(line(p, q));
    p = q;
  }
  LineMerger m(kTol, kTurn);
  const auto out = run(m, in);
  EXPECT_EQ(out.size(), 1u);
  expect_covers(in, out, kTol);
}

// A line takes at most 1 024 pieces once it is 1 mm long, but up to 65 536 while it is shorter:
// pieces of 0.1 µm (a refined program) make one line of 0.8 mm, not 8 of 0.1 mm, and pieces of
// 1 µm still split a 3 mm line every 1 024.
TEST(LineMerge, PieceLimitCountsOnlyOnceTheLineIsAMillimetreLong) {
  const Vec3 a{0.1, -0.2, 3}, dir{0.6, -0.64, 0.48};
  auto pieces = [&](int n, double len_mm) {
    std::vector<Block> in;
    Vec3 p = a;
    for (int i = 1; i <= n; ++i) {
      const Vec3 q = rounded(a + (len_mm * i) * dir, 1e-9);
      in.push_back(line(p, q));
      p = q;
    }
    return in;
  };
  const auto fine = pieces(8000, 0.0001);
  LineMerger m1(kTol, kTurn);
  const auto out1 = run(m1, fine);
  EXPECT_EQ(out1.size(), 1u);
  expect_covers(fine, out1, kTol);
  const auto coarse = pieces(3000, 0.001);
  LineMerger m2(kTol, kTurn);
  const auto out2 = run(m2, coarse);
  ASSERT_EQ(out2.size(), 3u);
  EXPECT_EQ(out2[0].end, coarse[LineMerger::kMaxPieces - 1].end);
  expect_covers(coarse, out2, kTol);
}

TEST(LineMerge, KeepsCornersFeedsStopsAndEvents) {
  LineMerger m(kTol, kTurn);
  std::vector<Block> in;
  in.push_back(line({0, 0, 0}, {1, 0, 0}));
  in.push_back(line({1, 0, 0}, {2, 0.02, 0}));  // 1.15°: a corner with a speed limit
  in.push_back(line({2, 0.02, 0}, {3, 0.04, 0}));
  in.push_back(line({3, 0.04, 0}, {4, 0.06, 0}, 3000));  // another feed
  in.push_back(line({4, 0.06, 0}, {5, 0.08, 0}, 3000, BlockKind::kRapid));
  Block dwell;
  dwell.kind = BlockKind::kDwell;
  dwell.dwell_s = 1;
  in.push_back(dwell);
  in.push_back(line({5, 0.08, 0}, {6, 0.1, 0}, 3000, BlockKind::kRapid));
  in.back().path_mode = PathMode::kExactStop;
  in.push_back(line({6, 0.1, 0}, {7, 0.12, 0}, 3000, BlockKind::kRapid));
  in.push_back(line({7, 0.12, 0}, {6.5, 0.11, 0}, 3000, BlockKind::kRapid));  // back
  const auto out = run(m, in);
  // Merged: only pieces 2 + 3 (the same direction and feed). Everything else stays, in order.
  ASSERT_EQ(out.size(), in.size() - 1);
  EXPECT_EQ(out[1].start, in[1].start);
  EXPECT_EQ(out[1].end, in[2].end);
  for (std::size_t i = 2; i < out.size(); ++i) {
    EXPECT_EQ(out[i].kind, in[i + 1].kind);
    EXPECT_EQ(out[i].end, in[i + 1].end);
    EXPECT_EQ(out[i].path_mode, in[i + 1].path_mode);
  }
}

TEST(LineMerge, AMergedLineCarriesTheSourceLinesOfItsFirstAndLastPiece) {
  LineMerger m(kTol, kTurn);
  std::vector<Block> in;
  for (int i = 0; i < 5; ++i) {
    in.push_back(line({1.0 * i, 0, 0}, {1.0 * i + 1, 0, 0}));
    in.back().line = 10 + static_cast<std::uint32_t>(i);
  }
  in.push_back(line({5, 0, 0}, {5, 1, 0}));  // a corner: a block of its own
  in.back().line = 20;
  const auto out = run(m, in);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].line, 10u);
  EXPECT_EQ(out[0].last_line, 14u);
  EXPECT_EQ(out[1].line, 20u);
  EXPECT_EQ(out[1].last_line, 0u);  // one source block
}

// A merged line runs along its chord, whose direction differs from its first and last pieces'
// by up to the tolerance over its length: the corner it makes with the block after it can turn
// less than the programmed corner of the pieces (found: 3.46° instead of 3.48° on
// line-contouring-xz, a crossing at 33.12 mm/s where that corner allows 32.94). The planner's
// passing speed there is the lower of both corners'.
TEST(LineMerge, CornersAtAMergedLinesEndsKeepThePiecesPassingSpeed) {
  LineMerger m(kTol, kTurn);
  std::vector<Block> in;
  in.push_back(line({0, 0.05, 0}, {1, 0, 0}));  // 2.86° to the chord, 2.88° to the piece
  in.push_back(line({1, 0, 0}, {2, 0.0004, 0}));
  in.push_back(line({2, 0.0004, 0}, {3, 0.0004, 0}));
  in.push_back(line({3, 0.0004, 0}, {4, 0, 0}));
  in.push_back(line({4, 0, 0}, {5, 0.05, 0}));  // 2.86° from the chord, 2.88° from the piece
  const auto out = run(m, in);
  ASSERT_EQ(out.size(), 3u);
  ASSERT_EQ(out[1].start, in[1].start);
  ASSERT_EQ(out[1].end, in[3].end);
  MachineConfig mc;
  const Limits lim = make_limits(mc, false);
  std::vector<Segment> seg;
  seg.reserve(out.size());
  for (const Block& b : out) seg.push_back(make_motion_segment(b, lim));
  auto unit = [](const Block& b) {
    const Vec3 d = b.end.xyz() - b.start.xyz();
    return (1 / norm(d)) * d;
  };
  // Amax·τ / (2·sin(θ/2)) = Amax·τ / |S − E| of the pieces' corner (per cycle: Amax·τ²).
  auto pieces_vg = [&](const Block& x, const Block& y) {
    return lim.amax_pc2 / norm(unit(y) - unit(x));
  };
  const double vg_start = pieces_vg(in[0], in[1]), vg_end = pieces_vg(in[3], in[4]);
  // The chord's own corners are gentler here: without the pieces' directions both ends would
  // be passed faster than their corners allow.
  EXPECT_GT(lim.amax_pc2 / norm(unit(out[1]) - unit(in[0])), 1.005 * vg_start);
  EXPECT_GT(lim.amax_pc2 / norm(unit(out[2]) - unit(out[1])), 1.005 * vg_end);
  EXPECT_LE(joint_speed_pc(seg[0], seg[1], lim, false), vg_start * (1 + 1e-12));
  EXPECT_LE(joint_speed_pc(seg[1], seg[2], lim, false), vg_end * (1 + 1e-12));
  // A line of one piece is the piece: no directions of its own.
  EXPECT_EQ(out[0].first_piece_dir, Vec3{});
  EXPECT_EQ(out[2].last_piece_dir, Vec3{});
}

TEST(LineMerge, FeedsThatDifferByRoundingMergeAtTheLowest) {
  // The direction correction's C of two pieces of one line differs in the last digits.
  LineMerger m(kTol, kTurn);
  std::vector<Block> in;
  in.push_back(line({0, 0, 0}, {1, 0, 0}, 6000 * (1 + 3e-7)));
  in.push_back(line({1, 0, 0}, {2, 0, 0}, 6000));
  in.push_back(line({2, 0, 0}, {3, 0, 0}, 6000 * (1 + 5e-7)));
  in.push_back(line({3, 0, 0}, {4, 0, 0}, 6000 * 1.01));  // another feed: its own line
  const auto out = run(m, in);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].end, in[2].end);
  EXPECT_EQ(out[0].feed_mm_min, 6000.0);  // never faster than any piece's feed
  EXPECT_EQ(out[1].feed_mm_min, 6000 * 1.01);
}

TEST(LineMerge, ExactStopEndsTheLineItClosesAndExactPathKeepsItsVertices) {
  LineMerger m(kTol, kTurn);
  std::vector<Block> in;
  in.reserve(4);
  for (int i = 0; i < 4; ++i) in.push_back(line({1.0 * i, 0, 0}, {1.0 * i + 1, 0, 0}));
  in[1].path_mode = PathMode::kExactStop;  // G9: the line ends there, stopping
  in[2].path_mode = PathMode::kExactPath;  // G61: its end stays a vertex
  const auto out = run(m, in);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].end, in[1].end);
  EXPECT_EQ(out[0].path_mode, PathMode::kExactStop);
  EXPECT_EQ(out[1].end, in[2].end);
  EXPECT_EQ(out[2].end, in[3].end);
}

TEST(LineMerge, OffPassesEveryBlock) {
  LineMerger m(0, kTurn);
  std::vector<Block> in;
  in.reserve(10);
  for (int i = 0; i < 10; ++i) in.push_back(line({1.0 * i, 0, 0}, {1.0 * i + 1, 0, 0}));
  EXPECT_EQ(run(m, in).size(), in.size());
}

TEST(LineMerge, TurnLimitFollowsTheMachine) {
  // Amax·τ / (2·sin(θ/2)) = V_top at the limit.
  const double th = LineMerger::max_turn_rad(2000, 0.001, 250);
  EXPECT_NEAR(2000 * 0.001 / (2 * std::sin(th / 2)), 250, 1e-9);
  EXPECT_NEAR(LineMerger::max_turn_rad(1e9, 1, 1), std::numbers::pi, 1e-9);
}

// Random polylines: straight runs with rounded coordinates, gentle and sharp corners, feed
// changes. Whatever merges, the output covers the input within the tolerance, keeps its
// vertices' order, and no joint it keeps hides a turn above the limit.
RC_GTEST_PROP(LineMerge, RandomPolylinesStayWithinTheTolerance, ()) {
  std::vector<Block> in;
  Vec3 p{0, 0, 0};
  const auto runs = *rc::gen::inRange(1, 8);
  for (int r = 0; r < runs; ++r) {
    const double az = *rc::gen::inRange(0, 3600) / 10.0 * std::numbers::pi / 180;
    const double el = *rc::gen::inRange(-900, 900) / 10.0 * std::numbers::pi / 180;
    const Vec3 dir{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
    const double piece = *rc::gen::element(1e-4, 0.001, 0.005, 0.05, 1.0);
    const double q = *rc::gen::element(1e-6, 1e-5, 1e-4);
    const double feed = *rc::gen::element(3000.0, 6000.0);
    const auto n = *rc::gen::inRange(1, 1500);  // past kMaxPieces too
    const Vec3 a = p;
    for (int i = 1; i <= n; ++i) {
      const Vec3 e = rounded(a + (piece * i) * dir, q);
      if (e == p) continue;
      in.push_back(line(p, e, feed));
      p = e;
    }
  }
  RC_PRE(!in.empty());
  LineMerger m(kTol, kTurn);
  const auto out = run(m, in);
  RC_ASSERT(out.size() <= in.size());
  expect_covers(in, out, kTol);
  // Merged joints turned by ≤ kTurn each: the pieces inside every output line.
  std::size_t k = 0;
  for (const Block& o : out) {
    std::size_t first = k;
    while (in[k].end != o.end) ++k;
    for (std::size_t i = first + 1; i <= k; ++i) {
      const Vec3 u = in[i - 1].end.xyz() - in[i - 1].start.xyz();
      const Vec3 v = in[i].end.xyz() - in[i].start.xyz();
      RC_ASSERT(dot(u, v) >= std::cos(kTurn) * norm(u) * norm(v) * (1 - 1e-12));
      RC_ASSERT(in[i].feed_mm_min >= o.feed_mm_min);
    }
    ++k;
  }
}

}  // namespace
}  // namespace cncore::planner
