// Collinear pieces merged into one line before the look-ahead (the stage between the direction
// correction and the motion kernel; LinuxCNC calls its counterpart the "naive CAM detector").
//
// CAM output and refined programs cut straight lines into many short G1 pieces whose rounded
// coordinates wobble: a 4.5 µm piece written with 6 decimals turns by up to 2·10⁻⁴ rad at each
// joint. Each joint is a corner to the look-ahead (its cap, its zone, the chain of corners
// within one step), and each piece an item of the window. Merged, the tool runs the straight
// line the pieces describe.
//
// Pieces of one kind (G0 or G1) with the same feed (within 0.1 %: the direction correction's C
// differs by rounding between pieces; the line runs at the lowest) and G64 tolerance, moving no
// axis but X Y Z, merge while every vertex between them lies within tolerance_mm of the chord
// from the first start to the last end, in order along it (projections strictly increasing,
// inside the chord), and while each joint turns by at most max_turn_rad: a corner the look-ahead
// would pass at the machine's top speed anyway (Amax·τ / (2·sin(θ/2)) ≥ V_top, spec 01), so
// that no programmed corner's speed limit is lost, only the rounding wobble of a line. The tool
// then stays within tolerance_mm of the programmed path (spec 01 P1: ≤ 1 µm; 0.5 µm is a
// good setting), and passes no vertex the pieces did not program. A piece
// whose end must be held (G61 exact path, G61.1 / G9 exact stop) ends the merge: the vertex
// stays exact. The test costs O(1) per piece (a cone of allowed directions, line_merge.cpp);
// at most kMaxPieces per line (more while it is shorter than kShortLineMm). The line keeps its
// first piece's source line (Block::line; what the samples on it carry) and names its last piece's
// in Block::last_line (the reports' "lines A-B"), and it carries its first and last pieces'
// directions: the corners at its ends are the pieces' corners, which may turn more than the chord's
// (planner::joint_speed_pc keeps both).
//
// The pieces themselves follow their merged line out of the stage (Block::pieces on the line,
// Block::piece on each piece, in program order): the planner plans the line only, while the
// kernel names the piece under the tool in each sample's line and the observers measure the
// samples against the path as programmed. A line's pieces are held here until it is complete
// (at most kMaxPiecesShort, a few MB at most, independent of the program's length).
//
// On by default ([motion] merge_tolerance_mm = 0.0005; 0 turns it off; off in stop mode): the
// random 2 000-segment program cut into 100× pieces runs in the time of the original (85.89 s
// against 89.12 s unmerged; original 85.90 s), and every corpus program keeps P1–P4.

#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/block.hpp"

namespace cncore::planner {

class LineMerger {
 public:
  // tolerance_mm ≤ 0: every block passes unchanged.
  LineMerger(double tolerance_mm, double max_turn_rad)
      : tolerance_mm_(tolerance_mm), min_cos_(std::cos(max_turn_rad)) {}

  // The largest turn a joint passed at top_speed_mm_s needs no slowing for: 2·sin(θ/2) =
  // accel_mm_s2·period_s / top_speed_mm_s.
  static double max_turn_rad(double accel_mm_s2, double period_s, double top_speed_mm_s) {
    const double x = 0.5 * accel_mm_s2 * period_s / top_speed_mm_s;
    return x >= 1 ? 3.14159265358979 : 2 * std::asin(x);
  }

  // The next block in program order. Then call next() until it returns false.
  void put(const Block& block);
  // The program ends (or stops on an error): the line being merged goes out.
  void finish();
  // The blocks ready, in program order: a merged line (Block::pieces > 0) is followed by its
  // pieces (Block::piece), which the planner skips.
  bool next(Block& out);

  // A line takes at most kMaxPieces pieces, or kMaxPiecesShort while it is shorter than
  // kShortLineMm: sub-µm pieces (a refined program) then still make lines of up to 1 mm instead
  // of 0.1 mm ones, whose straight joints each cost the cycle a segment (stress_test refined
  // 100×: 1 230 lines instead of the original's 149).
  static constexpr std::size_t kMaxPieces = 1024;
  static constexpr std::size_t kMaxPiecesShort = 65536;
  static constexpr double kShortLineMm = 1.0;

 private:
  // An angle as its cosine and sine (the cone test needs no trigonometric call, line_merge.cpp).
  struct Angle {
    double c = 1, s = 0;
    static Angle from_sin(double sn) { return {std::sqrt(1 - sn * sn), sn}; }  // in [0, π/2]
    // x/2 for x in [0, π]: (1 + cos x, sin x) and (sin x, 1 − cos x) both point at x/2; of the
    // two, the one without cancellation (near x = π, 1 + cos x keeps no digits).
    Angle half() const {
      const double hc = c >= 0 ? 1 + c : s;
      const double hs = c >= 0 ? s : 1 - c;
      const double n = std::sqrt(hc * hc + hs * hs);
      return {hc / n, hs / n};
    }
    friend Angle operator+(const Angle& x, const Angle& y) {
      return {x.c * y.c - x.s * y.s, x.s * y.c + x.c * y.s};
    }
    friend Angle operator-(const Angle& x, const Angle& y) {
      return {x.c * y.c + x.s * y.s, x.s * y.c - x.c * y.s};
    }
  };
  // The directions from the line's start that pass within the tolerance of every inner vertex
  // (a cone inside their intersection; the whole sphere before the first), and the distance
  // of the last inner vertex from the start.
  struct Cone {
    Vec3 axis{1, 0, 0};
    Angle half{-1, 0};  // π: every direction
    double r_mm = 0;
  };
  static bool within(const Angle& x, const Angle& y);  // x ≤ y (see line_merge.cpp)
  bool extends(const Block& b, Cone& cone) const;
  void emit(const Block& b);
  // What a piece adds to its line: the rest is the line's (kind, G64 tolerance, override mode).
  struct Piece {
    std::uint32_t line, col;
    Vec3 end;
    double feed_mm_min, correction;
    PathMode path_mode;
    static Piece of(const Block& b) {
      return {b.line, b.col, b.end.xyz(), b.feed_mm_min, b.correction, b.path_mode};
    }
  };

  double tolerance_mm_;
  double min_cos_;  // cos of the largest turn at a merged joint
  bool pending_ = false;
  Vec3 last_dir_;  // unit direction of the last piece merged
  Block line_;     // the merged line so far
  Cone cone_;
  std::size_t pieces_ = 0;      // pieces in it
  double feed_hi_mm_min_ = 0;   // the highest feed of its pieces (line_ has the lowest)
  std::array<Block, 2> out_{};  // ready: at most the line and the block after
  std::size_t out_head_ = 0, out_size_ = 0;
  std::vector<Piece> pieces_of_line_;  // the pieces of line_
  // The pieces of the last merged line handed out, handed out after it (next()).
  std::vector<Piece> out_pieces_;
  std::size_t out_piece_ = 0;  // the next of out_pieces_ to hand out
  Block out_line_;             // the line they belong to
};

}  // namespace cncore::planner
