// A motion block as the program wrote it (a straight line, or an arc or helix as an arc): the
// distance of a point to it and how far along it the nearest point lies. The summary measures
// the contour error and shares out time against these, not against the path the kernel planned
// (merged lines, rounded corners).
#pragma once

#include <cstdint>

#include "core/block.hpp"
#include "core/geometry.hpp"

namespace cncore::io {

class ProgrammedMove {
 public:
  ProgrammedMove() = default;
  // A motion block (G0, G1, G2/G3); its X, Y, Z only (rotary axes are no part of the contour).
  explicit ProgrammedMove(const Block& b);

  double length_mm() const { return length_mm_; }

  // The nearest point of the move to p: its distance from p, and its distance along the move
  // from the start (0 … length_mm()).
  struct Nearest {
    double distance_mm = 0;
    double along_mm = 0;
  };
  Nearest nearest(Vec3 p) const;
  // A lower bound of the distance from p (no point of the move is farther than radius_mm_ from
  // middle_): lets a search skip moves that cannot be the nearest.
  double distance_bound(Vec3 p) const { return norm(p - middle_) - radius_mm_; }

 private:
  bool arc_ = false;
  Vec3 start_, end_;
  Vec3 dir_;  // line: unit direction (zero for a move of no length)
  // Arc: centre (in the start's plane), unit radial direction at the start e1, e2 = n × e1,
  // unit normal n (the motion turns counter-clockwise about it), radius, sweep (rad, with the
  // extra turns) and the rise along n from start to end.
  Vec3 centre_, e1_, e2_, n_;
  double radius_mm_arc_ = 0, sweep_rad_ = 0, rise_mm_ = 0;
  double length_mm_ = 0;
  Vec3 middle_;  // centre of a sphere holding the whole move
  double radius_mm_ = 0;
};

}  // namespace cncore::io
