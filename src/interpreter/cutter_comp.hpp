// Cutter radius compensation (G41/G42, G41.1/G42.1, G40) as LinuxCNC's interpreter makes it,
// as a streaming stage on the interpreter's blocks: the programmed moves go in, the path of
// the tool centre comes out, one tool radius to the left (G41) or right (G42) of the contour in
// the plane of compensation.
//
// - Entry: the first move with motion in the plane after G41/G42 must be a straight line
//   longer than the radius; it runs from where the tool is to the programmed end point moved
//   one radius sideways, perpendicular to the line.
// - Each later move is offset by the radius (lines parallel, arcs concentric with radius
//   R ∓ r). At an outside corner an arc of radius r about the programmed corner joins the two
//   offset moves; at an inside corner both are cut back to where they intersect (line-line,
//   line-arc, arc-arc). Corners within 0.01 rad of tangent are joined as they are.
// - Exit: after G40 the next move runs straight from the compensated point to the programmed
//   end point (an arc there is an error).
//
// To place the end of a move the next one must be known, so the stage holds back one move
// (and the blocks without motion in the plane that follow it, at most kMaxHeld): memory does
// not grow with program length. Errors (gouging) are InputError at the line that finds them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/block.hpp"
#include "interpreter/arcs.hpp"

namespace cncore::interp {

class CutterComp {
 public:
  enum class Side : std::uint8_t { kLeft, kRight };
  static constexpr std::size_t kMaxHeld = 256;

  explicit CutterComp(const std::string* file) : file_(file) {}

  // G41/G42: compensation on in `plane`. A radius of 0 compensates nothing (LinuxCNC).
  void start(Side side, double radius_mm, Plane plane);
  bool on() const { return on_; }
  Plane plane() const { return plane_; }

  // blocks[from…] (in program order) through the compensation: they are replaced by what can
  // be handed on now; a move that needs the next one is held back.
  void pass(std::vector<Block>& blocks, std::size_t from);
  // G40: hands on what is held back; the next move with motion in the plane is the exit move.
  // `line`, `col`: where errors found now are reported.
  void stop(std::vector<Block>& blocks, std::uint32_t line, std::uint32_t col);
  // Program end: hands on what is held back; compensation off.
  void finish(std::vector<Block>& blocks, std::uint32_t line, std::uint32_t col);
  // After an error of its own (Interpreter::recover): the move it could not place and what
  // waited behind it are dropped; the next move enters again from where the tool is.
  void recover();

 private:
  // One programmed move and its compensated path in the plane (plane coordinates, mm).
  struct Move {
    Block block;
    bool arc = false;
    Vec2 ps, pe;  // programmed start and end
    Vec2 s, e;    // compensated start and end
    Vec2 c;       // arc centre
    bool ccw = false;
    Vec2 dir;              // lines: unit direction of the programmed line
    double sweep_rad = 0;  // arcs: the programmed sweep (signed, CCW positive)
  };

  bool engaged() const { return on_ || exit_ || pending_; }
  void take(Block& b, std::vector<Block>& out);
  void hold(Block& b);
  void entry(const Block& b);
  void exit_move(Block& b, std::vector<Block>& out);
  Move programmed(const Block& b) const;
  void offset(Move& m) const;
  Vec2 tangent_at(const Move& m, Vec2 p) const;
  Vec2 offset_point(Vec2 p, Vec2 tangent) const;
  void corner(Move& next, std::vector<Block>& out);
  Vec2 inside_corner(const Move& prev, const Move& next) const;
  void release(std::vector<Block>& out);
  void corner_arc(const Move& next, std::vector<Block>& out);
  [[noreturn]] void fail(const std::string& message) const;

  Vec2 plane_of(const AxisVec& p) const { return {p[pa_.first], p[pa_.second]}; }
  void set_plane(AxisVec& p, Vec2 v) const {
    p[pa_.first] = v.a;
    p[pa_.second] = v.b;
  }

  const std::string* file_;
  Plane plane_ = Plane::kXY;
  PlaneAxes pa_ = plane_axes(Plane::kXY);
  double sign_ = 1;  // +1 G41 (tool on the left of the contour), −1 G42
  double radius_mm_ = 0;
  bool on_ = false;
  bool first_ = false;  // the entry move is still to come
  // The tool is off the programmed path (from the entry move until the exit move after G40).
  bool exit_ = false;
  bool pending_ = false;         // move_ is held back
  mutable bool failed_ = false;  // the last error was found here
  AxisVec tool_;                 // where the tool is: the end of the last block handed on
  Move move_;
  std::vector<Block> held_;           // blocks after move_ without motion in the plane
  std::vector<Block> scratch_;        // the blocks being passed
  std::uint32_t line_ = 0, col_ = 0;  // the block being passed, for errors
};

}  // namespace cncore::interp
