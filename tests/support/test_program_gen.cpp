// The program generators: shapes, travel limits, and that refining a random path keeps its
// geometry. Parsed here with a tiny reader of "G0/G1 X Y Z" words (the generators emit nothing
// else in motion lines except the arcs of cam_like, checked separately).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "program_gen.hpp"

namespace cncore::testing::gen {
namespace {

struct Pt {
  double x, y, z;
};

// End points of every G0/G1 motion line, with modal X Y Z.
std::vector<Pt> points(const std::string& text, int* arcs = nullptr) {
  std::vector<Pt> out;
  std::istringstream in(text);
  std::string line;
  Pt cur{0, 0, 0};
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '(') continue;
    std::istringstream w(line);
    std::string word;
    bool motion = false;
    while (w >> word) {
      const char c = word[0];
      if (c == 'G' && (word == "G0" || word == "G1")) motion = true;
      if (c == 'G' && (word == "G2" || word == "G3")) {
        motion = true;
        if (arcs) ++*arcs;
      }
      if (c == 'X') cur.x = std::stod(word.substr(1));
      if (c == 'Y') cur.y = std::stod(word.substr(1));
      if (c == 'Z') cur.z = std::stod(word.substr(1));
    }
    if (motion) out.push_back(cur);
  }
  return out;
}

bool in_travel(const Pt& p) {
  return std::abs(p.x) <= 300 && std::abs(p.y) <= 200 && p.z >= -200 && p.z <= 100;
}

TEST(ProgramGen, ZigZagHasTheRequestedStrokes) {
  const auto pts = points(zigzag(5, 20, 2));
  // 1 rapid + 5 strokes + 4 steps
  ASSERT_EQ(pts.size(), 10u);
  EXPECT_DOUBLE_EQ(pts[0].x, -10);
  EXPECT_DOUBLE_EQ(pts[1].x, 10);
  EXPECT_DOUBLE_EQ(pts[2].y - pts[1].y, 2);
  EXPECT_DOUBLE_EQ(pts[3].x, -10);
  for (const auto& p : pts) EXPECT_TRUE(in_travel(p));
}

TEST(ProgramGen, CircleChordsCloseTheCircle) {
  const auto pts = points(circle_chords(360, 50));
  ASSERT_EQ(pts.size(), 361u);
  EXPECT_DOUBLE_EQ(pts.back().x, 50);
  EXPECT_DOUBLE_EQ(pts.back().y, 0);
  for (const auto& p : pts) EXPECT_NEAR(std::hypot(p.x, p.y), 50, 1e-6);
}

TEST(ProgramGen, RasterStaysInTravelAndFollowsTheSurface) {
  const auto pts = points(
      raster_3d(40, 20, 1, 0.5, 10000, [](double x, double y) { return -1 - 0.01 * x * y; }));
  ASSERT_EQ(pts.size(), 1u + 21u * 81u + 1u);
  for (std::size_t i = 1; i + 1 < pts.size(); ++i)
    EXPECT_NEAR(pts[i].z, -1 - 0.01 * pts[i].x * pts[i].y, 1e-6);
}

TEST(ProgramGen, RefinedRandomPathIsTheSameGeometry) {
  const auto coarse = points(random_path(42, 300));
  const auto fine = points(random_path(42, 300, 0.2, 2.0, 90, 10));
  ASSERT_EQ(coarse.size(), 301u);
  ASSERT_EQ(fine.size(), 3001u);
  for (std::size_t i = 1; i < coarse.size(); ++i) {
    const Pt& a = coarse[i];
    const Pt& b = fine[10 * i];
    EXPECT_DOUBLE_EQ(a.x, b.x);
    EXPECT_DOUBLE_EQ(a.y, b.y);
    EXPECT_DOUBLE_EQ(a.z, b.z);
    // The intermediate points lie on the coarse segment (within the 1e-6 print rounding).
    const Pt& p0 = coarse[i - 1];
    for (int k = 1; k < 10; ++k) {
      const Pt& m = fine[10 * (i - 1) + static_cast<std::size_t>(k)];
      const double ux = a.x - p0.x, uy = a.y - p0.y;
      const double cr = (m.x - p0.x) * uy - (m.y - p0.y) * ux;
      EXPECT_LE(std::abs(cr) / std::hypot(ux, uy), 2e-6);
    }
  }
  for (const auto& p : fine) EXPECT_TRUE(in_travel(p));
  EXPECT_NE(random_path(1, 50), random_path(2, 50));
  EXPECT_EQ(random_path(7, 50), random_path(7, 50));
}

TEST(ProgramGen, CamLikeHasTheRequestedSizeAndStaysInTravel) {
  std::ostringstream o;
  cam_like(o, 100000);
  const std::string text = o.str();
  const auto lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  EXPECT_GE(lines, 99990u);
  EXPECT_LE(lines, 100003u);
  int arcs = 0;
  const auto pts = points(text, &arcs);
  EXPECT_GT(arcs, 50);
  for (const auto& p : pts) ASSERT_TRUE(in_travel(p)) << p.x << " " << p.y << " " << p.z;
}

}  // namespace
}  // namespace cncore::testing::gen

// ---- RapidCheck generators ----
#include <rapidcheck/gtest.h>

#include "path_geometry.hpp"
#include "program_gen_rc.hpp"

namespace cncore::testing::gen {
namespace {

RC_GTEST_PROP(BlockGenerator, ChainedInsideTravelWithConsistentArcs, ()) {
  const auto bl = *blocks();
  RC_ASSERT(!bl.empty());
  AxisVec pos{};
  for (const auto& b : bl) {
    if (b.kind == BlockKind::kDwell || b.kind == BlockKind::kAux) continue;
    RC_ASSERT(b.start == pos);
    pos = b.end;
    if (b.kind == BlockKind::kArc) {
      // Start and end at the same distance from the centre in the plane (an exact arc).
      const Vec3 n = b.normal;
      auto in_plane = [&](Vec3 p) {
        Vec3 q = p - b.center;
        return q - dot(q, n) * n;
      };
      RC_ASSERT(std::abs(norm(in_plane(b.start.xyz())) - norm(in_plane(b.end.xyz()))) < 1e-9);
      RC_ASSERT(std::abs(dot(b.start.xyz() - b.center, n)) < 1e-9);
    }
  }
  const Path path = build_path(bl);
  for (const auto& sg : path.segments) {
    for (int k = 0; k <= 64; ++k) {
      const AxisVec p = sg.point_at(k / 64.0);
      RC_ASSERT(std::abs(p[kX]) <= 300.0);
      RC_ASSERT(std::abs(p[kY]) <= 200.0);
      RC_ASSERT(p[kZ] >= -200.0);
      RC_ASSERT(p[kZ] <= 100.0);
    }
  }
}

RC_GTEST_PROP(BlockGenerator, OverrideStepsAreSortedAndInRange, ()) {
  const auto steps = *override_steps(2.0);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    RC_ASSERT(steps[i].first >= 0.0);
    RC_ASSERT(steps[i].first <= 2.0);
    RC_ASSERT(steps[i].second >= 10.0);
    RC_ASSERT(steps[i].second <= 200.0);
    if (i > 0) RC_ASSERT(steps[i - 1].first <= steps[i].first);
  }
}

}  // namespace
}  // namespace cncore::testing::gen
