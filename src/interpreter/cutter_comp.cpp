#include "interpreter/cutter_comp.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"

namespace cncore::interp {

namespace {

constexpr double kPlaneEps = 1e-9;  // mm: no motion in the plane
// LinuxCNC's TOLERANCE_CONCAVE_CORNER: a corner turning less than this is tangent.
constexpr double kTangentRad = 0.05;
// An arc cut back at an inside corner may not sweep further than programmed by more than this
// (mm along the arc; LinuxCNC allows 0.001 in).
constexpr double kSweepSlackMm = 0.0254;

// Lines p + t·u and q + s·v (u, v unit): p + t·u with t = ((q − p) × v) / (u × v).
bool line_line(Vec2 p, Vec2 u, Vec2 q, Vec2 v, Vec2& x) {
  const double den = cross(u, v);
  if (std::fabs(den) < 1e-12) return false;
  x = p + (cross(q - p, v) / den) * u;
  return true;
}

// Line p + t·u (u unit) and circle |x − c| = r: with w = p − c,
//   t² + 2(w·u)t + (w·w − r²) = 0,  t = −w·u ± √((w·u)² − w·w + r²);
// the point where the line enters the circle (smaller t) or where it leaves it.
bool line_circle(Vec2 p, Vec2 u, Vec2 c, double r, bool entering, Vec2& x) {
  const Vec2 w = p - c;
  const double b = dot(w, u);
  const double disc = b * b - dot(w, w) + r * r;
  if (disc < 0) return false;
  const double root = std::sqrt(disc);
  x = p + (-b + (entering ? -root : root)) * u;
  return true;
}

// Circles |x − c1| = r1 and |x − c2| = r2, d = |c2 − c1|: along the line of centres at
//   a = (r1² − r2² + d²) / (2d) from c1, ± h = √(r1² − a²) across it; the point to the left
//   of c1 → c2 (+h) or to its right.
bool circle_circle(Vec2 c1, double r1, Vec2 c2, double r2, bool left, Vec2& x) {
  const double d = norm(c2 - c1);
  if (d < kPlaneEps || d > r1 + r2 || d < std::fabs(r1 - r2)) return false;
  const Vec2 u = (1 / d) * (c2 - c1);
  const double a = (r1 * r1 - r2 * r2 + d * d) / (2 * d);
  const double h = std::sqrt(std::max(0.0, r1 * r1 - a * a));
  const Vec2 m = c1 + a * u;
  const Vec2 n{-u.b, u.a};
  x = m + (left ? h : -h) * n;
  return true;
}

}  // namespace

void CutterComp::start(Side side, double radius_mm, Plane plane) {
  sign_ = side == Side::kLeft ? 1.0 : -1.0;
  radius_mm_ = radius_mm;
  plane_ = plane;
  pa_ = plane_axes(plane);
  on_ = radius_mm > 0;
  first_ = on_;
}

void CutterComp::pass(std::vector<Block>& blocks, std::size_t from) {
  failed_ = false;
  if (!engaged() || from >= blocks.size()) return;
  scratch_.assign(blocks.begin() + static_cast<std::ptrdiff_t>(from), blocks.end());
  blocks.resize(from);
  for (Block& b : scratch_) take(b, blocks);
  scratch_.clear();
}

void CutterComp::stop(std::vector<Block>& blocks, std::uint32_t line, std::uint32_t col) {
  line_ = line;
  col_ = col;
  if (pending_) release(blocks);
  on_ = false;
  first_ = false;
}

void CutterComp::finish(std::vector<Block>& blocks, std::uint32_t line, std::uint32_t col) {
  stop(blocks, line, col);
  exit_ = false;
}

void CutterComp::recover() {
  if (!failed_) return;
  failed_ = false;
  pending_ = false;
  held_.clear();
  first_ = on_;
}

void CutterComp::fail(const std::string& message) const {
  failed_ = true;
  throw InputError(*file_, line_, col_, message);
}

void CutterComp::take(Block& b, std::vector<Block>& out) {
  line_ = b.line;
  col_ = b.col;
  const bool in_plane = b.kind == BlockKind::kArc ||
                        (is_motion(b) && norm(plane_of(b.end) - plane_of(b.start)) > kPlaneEps);
  if (on_ && in_plane) {
    if (first_) {
      entry(b);
      return;
    }
    Move next = programmed(b);
    offset(next);
    corner(next, out);
    move_ = next;
    pending_ = true;
    return;
  }
  if (pending_) {
    hold(b);
    return;
  }
  if (exit_ && in_plane) {
    exit_move(b, out);
    return;
  }
  // Before the exit move, a move out of the plane stays at the compensated point.
  if (is_motion(b) && exit_) {
    b.start = tool_;
    set_plane(b.end, plane_of(tool_));
  }
  if (is_motion(b)) tool_ = b.end;
  out.push_back(b);
}

void CutterComp::hold(Block& b) {
  if (held_.size() >= kMaxHeld) {
    fail(
        fmt::format("cutter radius compensation: more than {} blocks without motion in the "
                    "plane after a move",
                    kMaxHeld));
  }
  held_.push_back(b);
}

// The entry move: from the tool to the programmed end point moved one radius sideways,
// perpendicular to the line from the tool to it (LinuxCNC's first move after G41/G42).
void CutterComp::entry(const Block& b) {
  if (b.kind == BlockKind::kArc) {
    fail("the first move with cutter radius compensation must be a straight line (G0 or G1)");
  }
  Move m = programmed(b);
  if (!exit_) tool_ = b.start;
  const Vec2 from = plane_of(tool_);
  const double length = norm(m.pe - from);
  if (length <= radius_mm_) {
    fail("Length of cutter compensation entry move is not greater than the tool radius");
  }
  m.dir = (1 / length) * (m.pe - from);
  m.s = from;
  m.e = offset_point(m.pe, m.dir);
  move_ = m;
  pending_ = true;
  first_ = false;
  exit_ = true;  // from now on the tool is off the programmed path until the exit move
}

// After G40: straight from the compensated point to the programmed end point.
void CutterComp::exit_move(Block& b, std::vector<Block>& out) {
  if (b.kind == BlockKind::kArc) {
    fail("The move just after exiting cutter compensation mode must be straight, not an arc");
  }
  b.start = tool_;
  out.push_back(b);
  tool_ = b.end;
  exit_ = false;
}

CutterComp::Move CutterComp::programmed(const Block& b) const {
  Move m;
  m.block = b;
  m.arc = b.kind == BlockKind::kArc;
  m.ps = plane_of(b.start);
  m.pe = plane_of(b.end);
  if (m.arc) {
    AxisVec c;
    c.set_xyz(b.center);
    m.c = plane_of(c);
    m.ccw = component(b.normal, pa_.normal) > 0;
    m.sweep_rad = arc_sweep(m.ps, m.pe, m.c, m.ccw, b.turns);
  } else {
    m.dir = (1 / norm(m.pe - m.ps)) * (m.pe - m.ps);
  }
  return m;
}

// The unit tangent of the programmed move at p: a line's direction; on an arc about c,
// ±(−(p − c).b, (p − c).a) / |p − c| (+ counter-clockwise).
Vec2 CutterComp::tangent_at(const Move& m, Vec2 p) const {
  if (!m.arc) return m.dir;
  const Vec2 v = p - m.c;
  const double r = norm(v);
  return m.ccw ? Vec2{-v.b / r, v.a / r} : Vec2{v.b / r, -v.a / r};
}

// p moved one radius to the tool's side of the tangent t: p ± r·(−t.b, t.a) (+ for G41).
Vec2 CutterComp::offset_point(Vec2 p, Vec2 t) const {
  return p + (sign_ * radius_mm_) * Vec2{-t.b, t.a};
}

// The compensated move: a line parallel at one radius, an arc concentric with radius R − r
// when the tool is on the centre's side (G41 on a CCW arc, G42 on a CW one), else R + r.
void CutterComp::offset(Move& m) const {
  if (m.arc) {
    const bool tool_inside = m.ccw == (sign_ > 0);
    const double r = std::min(norm(m.ps - m.c), norm(m.pe - m.c));
    if (tool_inside && r <= radius_mm_) fail("Tool radius not less than arc radius with comp");
  }
  m.s = offset_point(m.ps, tangent_at(m, m.ps));
  m.e = offset_point(m.pe, tangent_at(m, m.pe));
}

// The corner between the held move and `next` at the programmed point between them: an inside
// corner cuts both back to their intersection, an outside corner gets an arc about the
// programmed corner (a rapid goes straight to the next move's start instead), a tangent one is
// joined as it is. The held move is handed on.
void CutterComp::corner(Move& next, std::vector<Block>& out) {
  const Vec2 t1 = tangent_at(move_, move_.pe);
  const Vec2 t2 = tangent_at(next, next.ps);
  // The turn at the corner, positive towards the tool's side: an inside corner.
  const double turn = sign_ * std::atan2(cross(t1, t2), dot(t1, t2));
  bool inside = turn > kTangentRad;
  bool outside = turn < -kTangentRad;
  if (std::fabs(turn) > std::numbers::pi - kTangentRad) {
    // The path reverses: the tool goes round the end, except next to an arc it is outside
    // of, where it stays on its side of the arc (LinuxCNC's "h" shape). As in LinuxCNC, the
    // next move decides when it is an arc, else the held one.
    const Move& arc = next.arc ? next : move_;
    inside = arc.arc && arc.ccw != (sign_ > 0);
    outside = !inside;
  }
  if (inside) {
    const Vec2 q = inside_corner(move_, next);
    move_.e = q;
    next.s = q;
    release(out);
  } else if (outside) {
    release(out);
    if (next.block.kind == BlockKind::kRapid) {
      next.s = plane_of(tool_);
    } else {
      corner_arc(next, out);
    }
  } else {
    release(out);
    next.s = plane_of(tool_);
  }
}

Vec2 CutterComp::inside_corner(const Move& prev, const Move& next) const {
  Vec2 q;
  if (!prev.arc && !next.arc) {
    if (!line_line(prev.e, prev.dir, next.s, next.dir, q)) {
      fail("Zero degree inside corner is invalid for cutter compensation");
    }
  } else if (!prev.arc) {
    // The line stops where it enters the arc's offset circle, or, with the tool inside the
    // arc, where it leaves it (LinuxCNC's choice, also when the path nearly reverses).
    const bool outside = next.ccw != (sign_ > 0);
    if (!line_circle(prev.e, prev.dir, next.c, norm(next.e - next.c), outside, q)) {
      fail("Arc move in concave corner cannot be reached by the tool without gouging");
    }
  } else if (!next.arc) {
    // The same corner run backwards.
    const bool outside = prev.ccw != (sign_ > 0);
    if (!line_circle(next.s, next.dir, prev.c, norm(prev.e - prev.c), !outside, q)) {
      fail(
          "Arc to straight motion makes a corner the compensated tool can't fit in without "
          "gouging");
    }
  } else if (!circle_circle(prev.c, norm(prev.e - prev.c), next.c, norm(next.e - next.c),
                            // LinuxCNC's side of the line of centres
                            (prev.ccw == (sign_ > 0)) == next.ccw, q)) {
    fail("Arc to arc motion makes a corner the compensated tool can't fit in without gouging");
  }
  return q;
}

// Hands on the held move, then the blocks held after it. A move cut back at inside corners
// must still run the way it was programmed: a line whose ends crossed, or an arc that would
// now sweep further than programmed, is a corner too tight for the tool.
void CutterComp::release(std::vector<Block>& out) {
  Move& m = move_;
  if (m.arc) {
    const double sweep = arc_sweep(m.s, m.e, m.c, m.ccw, m.block.turns);
    const double r = std::max(norm(m.e - m.c), kPlaneEps);
    if (std::fabs(sweep) > std::fabs(m.sweep_rad) + kSweepSlackMm / r) {
      fail("Arc move in concave corner cannot be reached by the tool without gouging");
    }
  } else if (dot(m.e - m.s, m.dir) < 0) {
    fail(m.block.kind == BlockKind::kRapid
             ? "Straight traverse in concave corner cannot be reached by the tool without gouging"
             : "Straight feed in concave corner cannot be reached by the tool without gouging");
  }
  Block& b = m.block;
  b.start = tool_;
  set_plane(b.end, m.e);
  out.push_back(b);
  tool_ = b.end;
  for (Block& h : held_) {
    if (is_motion(h)) {
      h.start = tool_;
      set_plane(h.end, m.e);
      tool_ = h.end;
    }
    out.push_back(h);
  }
  held_.clear();
  pending_ = false;
}

// The arc round an outside corner: radius r about the programmed corner, from the end of the
// move handed on to the start of `next`, clockwise for G41 and counter-clockwise for G42. It
// moves only the axes of the plane, at the next move's feed.
void CutterComp::corner_arc(const Move& next, std::vector<Block>& out) {
  Block a = next.block;
  a.kind = BlockKind::kArc;
  a.start = tool_;
  a.end = tool_;
  set_plane(a.end, next.s);
  AxisVec c = tool_;
  set_plane(c, move_.pe);
  a.center = c.xyz();
  AxisVec n;
  n[pa_.normal] = sign_ > 0 ? -1.0 : 1.0;
  a.normal = n.xyz();
  a.turns = 0;
  out.push_back(a);
  tool_ = a.end;
}

}  // namespace cncore::interp
