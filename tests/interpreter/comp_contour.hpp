// A programmed contour in the plane of compensation, written by the tests themselves (lines and
// arcs in plane coordinates (a, b)), the G-code for it in G17, G18 or G19, and the distance of
// a point to it: what cutter radius compensation is measured against.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/block.hpp"

namespace cncore::interp::test {

struct P2 {
  double a = 0, b = 0;
};

// One piece of the contour: a line from `from` to `to`, or an arc about `c` (ccw or not).
struct Piece {
  P2 from, to;
  bool arc = false;
  bool ccw = false;
  P2 c;
};

// The plane's axes as (first, second) with their axis and centre words.
struct PlaneWords {
  const char* gcode;
  std::size_t first, second, normal;
  char first_word, second_word, first_centre, second_centre;
};
inline PlaneWords plane_words(int g) {
  if (g == 18) return {"G18", 2, 0, 1, 'Z', 'X', 'K', 'I'};
  if (g == 19) return {"G19", 1, 2, 0, 'Y', 'Z', 'J', 'K'};
  return {"G17", 0, 1, 2, 'X', 'Y', 'I', 'J'};
}

// G-code for the pieces, one per line (G1 / G2 / G3 with the centre offset from the start).
inline std::string contour_gcode(const std::vector<Piece>& pieces, const PlaneWords& pw) {
  std::string out;
  for (const Piece& p : pieces) {
    if (!p.arc) {
      out += fmt::format("G1 {}{} {}{}\n", pw.first_word, p.to.a, pw.second_word, p.to.b);
    } else {
      out += fmt::format("{} {}{} {}{} {}{} {}{}\n", p.ccw ? "G3" : "G2", pw.first_word, p.to.a,
                         pw.second_word, p.to.b, pw.first_centre, p.c.a - p.from.a,
                         pw.second_centre, p.c.b - p.from.b);
    }
  }
  return out;
}

// The nearest point of a piece to q, and whether it is an end of the piece.
struct Foot {
  P2 at;
  double distance = 0;
  bool at_end = false;
  P2 tangent;  // unit direction of travel at `at`
};

inline Foot foot_on(const Piece& p, P2 q) {
  Foot f;
  auto end_foot = [&](P2 e) {
    Foot g;
    g.at = e;
    g.distance = std::hypot(q.a - e.a, q.b - e.b);
    g.at_end = true;
    return g;
  };
  if (!p.arc) {
    const double da = p.to.a - p.from.a, db = p.to.b - p.from.b;
    const double len2 = da * da + db * db;
    const double t = ((q.a - p.from.a) * da + (q.b - p.from.b) * db) / len2;
    if (t <= 0) return end_foot(p.from);
    if (t >= 1) return end_foot(p.to);
    f.at = {p.from.a + t * da, p.from.b + t * db};
    f.distance = std::hypot(q.a - f.at.a, q.b - f.at.b);
    const double len = std::sqrt(len2);
    f.tangent = {da / len, db / len};
    return f;
  }
  const double r = std::hypot(p.from.a - p.c.a, p.from.b - p.c.b);
  const double a0 = std::atan2(p.from.b - p.c.b, p.from.a - p.c.a);
  const double a1 = std::atan2(p.to.b - p.c.b, p.to.a - p.c.a);
  const double aq = std::atan2(q.b - p.c.b, q.a - p.c.a);
  const double two_pi = 2 * std::numbers::pi;
  auto wrap = [&](double x) {
    x = std::fmod(x, two_pi);
    return x < 0 ? x + two_pi : x;
  };
  const double sweep = p.ccw ? wrap(a1 - a0) : wrap(a0 - a1);
  const double along = p.ccw ? wrap(aq - a0) : wrap(a0 - aq);
  if (along > sweep) {
    const Foot s = end_foot(p.from), e = end_foot(p.to);
    return s.distance <= e.distance ? s : e;
  }
  f.at = {p.c.a + r * std::cos(aq), p.c.b + r * std::sin(aq)};
  f.distance = std::fabs(std::hypot(q.a - p.c.a, q.b - p.c.b) - r);
  f.tangent = p.ccw ? P2{-std::sin(aq), std::cos(aq)} : P2{std::sin(aq), -std::cos(aq)};
  f.at_end = along < 1e-9 || along > sweep - 1e-9;  // the side is not defined there
  return f;
}

// The nearest point of the whole contour.
inline Foot nearest(const std::vector<Piece>& pieces, P2 q) {
  Foot best;
  best.distance = 1e300;
  for (const Piece& p : pieces) {
    const Foot f = foot_on(p, q);
    if (f.distance < best.distance) best = f;
  }
  return best;
}

// Points along a motion block in plane coordinates (a line, or an arc/spiral about its centre).
inline std::vector<P2> sample_block(const Block& b, const PlaneWords& pw, int n = 200) {
  const P2 s{b.start[pw.first], b.start[pw.second]};
  const P2 e{b.end[pw.first], b.end[pw.second]};
  std::vector<P2> out;
  if (b.kind != BlockKind::kArc) {
    for (int i = 0; i <= n; ++i) {
      const double t = static_cast<double>(i) / n;
      out.push_back({s.a + t * (e.a - s.a), s.b + t * (e.b - s.b)});
    }
    return out;
  }
  AxisVec cv;
  cv.set_xyz(b.center);
  const P2 c{cv[pw.first], cv[pw.second]};
  AxisVec nv;
  nv.set_xyz(b.normal);
  const bool ccw = nv[pw.normal] > 0;
  const double r0 = std::hypot(s.a - c.a, s.b - c.b), r1 = std::hypot(e.a - c.a, e.b - c.b);
  const double a0 = std::atan2(s.b - c.b, s.a - c.a), a1 = std::atan2(e.b - c.b, e.a - c.a);
  const double two_pi = 2 * std::numbers::pi;
  double sweep = ccw ? a1 - a0 : a0 - a1;
  while (sweep <= 1e-12) sweep += two_pi;
  while (sweep > two_pi) sweep -= two_pi;
  sweep += two_pi * b.turns;
  for (int i = 0; i <= n; ++i) {
    const double t = static_cast<double>(i) / n;
    const double ang = a0 + (ccw ? 1 : -1) * sweep * t;
    const double r = r0 + (r1 - r0) * t;
    out.push_back({c.a + r * std::cos(ang), c.b + r * std::sin(ang)});
  }
  return out;
}

}  // namespace cncore::interp::test
