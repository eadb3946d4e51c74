// Moves: the target of a block from its axis words, travel limits, G0/G1 lines and G2/G3 arcs
// (helices, spirals) in the active plane.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

void Interpreter::Impl::check_travel(const AxisVec& lo, const AxisVec& hi, const AxisVec& target,
                                     std::uint32_t col) {
  constexpr double kSlack = 1e-9;
  if (beyond_travel_) {
    bool inside = true;
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      const AxisConfig& ax = machine_.axes[a];
      if (!ax.enabled || ax.max_mm <= ax.min_mm) continue;
      inside = inside && hi[a] <= ax.max_mm + kSlack && lo[a] >= ax.min_mm - kSlack;
    }
    if (!inside) return;  // still out there, as a consequence of the first error
    beyond_travel_ = false;
  }
  travel_target_ = target;
  travel_failed_ = true;  // cleared below when the move stays inside
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    const AxisConfig& ax = machine_.axes[a];
    if (!ax.enabled || ax.max_mm <= ax.min_mm) continue;  // rotary without limits
    const auto& word = words_[kAxisWords[a]];
    const std::uint32_t c = word.present ? word.col : col;
    if (hi[a] > ax.max_mm + kSlack) {
      fail(c, fmt::format("{} {:.3f} is beyond the travel limit {:.3f}", kAxisLetters[a], hi[a],
                          ax.max_mm));
    }
    if (lo[a] < ax.min_mm - kSlack) {
      fail(c, fmt::format("{} {:.3f} is beyond the travel limit {:.3f}", kAxisLetters[a], lo[a],
                          ax.min_mm));
    }
  }
  travel_failed_ = false;
}

// G9 makes this block's end an exact stop; else the modal G61/G61.1/G64 (with G64's P).
PathMode Interpreter::Impl::block_path_mode() const {
  return words_.group(GGroup::kExactStopOnce) != nullptr ? PathMode::kExactStop : modal_.path_mode;
}

void Interpreter::Impl::set_path_mode(Block& b) const {
  b.path_mode = block_path_mode();
  b.tolerance_mm = b.path_mode == PathMode::kBlend ? modal_.tolerance_mm : -1;
}

void Interpreter::Impl::emit_motion(BlockKind kind, const AxisVec& target, std::uint32_t col) {
  in_sync_ = false;
  Block b = base_block(kind);
  b.end = target;
  b.col = col;
  b.feed_mm_min = kind == BlockKind::kRapid ? 0 : move_feed_mm_min_;
  set_path_mode(b);
  b.smooth_tolerance_mm = modal_.smooth_tolerance_mm;
  out_.push_back(b);
}

// G0/G1 to `target` (machine coordinates). In G96 a G1 follows the speed along it
// (threading.cpp) and after a G0 the speed is the new radius's.
void Interpreter::Impl::line_motion(const AxisVec& target, std::uint32_t col) {
  if (!modal_.css) {
    plain_line_motion(target, col);
  } else if (modal_.motion == Motion::kLine) {
    css_line(target, col);
  } else {
    plain_line_motion(target, col);
    css_update(target, col);
  }
}

void Interpreter::Impl::plain_line_motion(const AxisVec& target, std::uint32_t col) {
  const bool rapid = modal_.motion == Motion::kRapid;
  // G93's length: over X Y Z, or over the rotary axes for a rotary-only move (LinuxCNC's rule).
  double linear2 = 0, rotary2 = 0;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    const double d2 = (target[a] - pos_[a]) * (target[a] - pos_[a]);
    (is_rotary(a) ? rotary2 : linear2) += d2;
  }
  if (!rapid) {
    move_feed_mm_min_ = move_feed_mm_min(std::sqrt(linear2 > 0 ? linear2 : rotary2), col);
  }
  check_travel(target, target, target, col);
  const double len2 = linear2 + rotary2;
  if (len2 > kZeroMoveMm * kZeroMoveMm || zero_length_moves_) {
    emit_motion(rapid ? BlockKind::kRapid : BlockKind::kLine, target, col);
  }
  pos_ = target;
}

// G2/G3. The centre comes from R (centre_from_radius) or from I J K (check_centre); the helix
// axis (plane normal) and any other axes move linearly with the angle.
void Interpreter::Impl::arc(const AxisVec& target, bool ccw, std::uint32_t col) {
  const Words& w = words_;
  const char* g = ccw ? "G3" : "G2";
  move_feed_mm_min(0, col);  // the feed errors first, as for G1
  const PlaneAxes pa = plane_axes(modal_.plane);
  const double unit = modal_.length_unit_mm();
  // In a rotated system (G10 L2 R) a G18/G19 arc lies in a vertical plane turned with the
  // system: it is computed in the frame turned back by R, where that plane is the ZX or YZ
  // plane, and turned to the machine when emitted.
  const double turn = arc_turn_deg();
  const AxisVec from = turned(pos_, -turn), to = turned(target, -turn);
  const Vec2 s{from[pa.first], from[pa.second]};
  const Vec2 e{to[pa.first], to[pa.second]};
  Vec2 c;
  double dr = 0;  // r1 − r0: an I J K arc whose radii differ within the tolerance is a spiral
  if (w.has(pa.normal_word)) {
    const char up = static_cast<char>(pa.normal_word - 'a' + 'A');
    fail(w[pa.normal_word].col,
         fmt::format("{} word given for an arc in the {} plane", up, plane_gcode(modal_.plane)));
  }
  const bool has_first = w.has(pa.first_word), has_second = w.has(pa.second_word);
  if (w.has('r')) {
    if (has_first || has_second) fail(w['r'].col, "arc with both R and I/J/K");
    const double tol = modal_.inch ? kRadiusTolInch * 25.4 : kRadiusTolMm;
    const ArcCheck chk = centre_from_radius(s, e, w['r'].value * unit, ccw, tol, c);
    if (!chk.ok) fail(w['r'].col, chk.message);
  } else {
    if (!has_first && !has_second) {
      fail(col, fmt::format("{} arc without centre (I J K) or radius (R)", g));
    }
    const double i = w[pa.first_word].value * unit;  // absent words are 0
    const double j = w[pa.second_word].value * unit;
    if (modal_.arc_absolute) {
      // G90.1: program coordinates
      AxisVec pc = to_program(pos_, tool_offset_);
      pc[pa.first] = i;
      pc[pa.second] = j;
      const AxisVec mc = turned(from_program(pc), -turn);
      c = {mc[pa.first], mc[pa.second]};
    } else {
      // G91.1: relative to the start point, along the program's (rotated) axes; a G18/G19
      // arc's frame is already turned.
      const Vec2 d = modal_.plane == Plane::kXY ? rotated({i, j}, rotation_deg(modal_.coord_system))
                                                : Vec2{i, j};
      c = {s.a + d.a, s.b + d.b};
    }
    const double abs_tol = modal_.inch ? kArcAbsTolInch * 25.4 : kArcAbsTolMm;
    const double r0 = std::hypot(s.a - c.a, s.b - c.b), r1 = std::hypot(e.a - c.a, e.b - c.b);
    dr = r1 - r0;
    // check_centre would move the centre onto the chord's bisector; like LinuxCNC, the
    // programmed centre stays and the radius blends from r0 to r1 along the sweep (the
    // planner's arcs take r linear in the angle).
    Vec2 moved = c;
    const ArcCheck chk = check_centre(s, e, moved, abs_tol, kArcRelTol);
    if (!chk.ok) {
      fail(col,
           fmt::format("{} ({:.4f} mm at the start, {:.4f} mm at the end)", chk.message, r0, r1));
    }
  }
  std::uint32_t turns = 0;
  if (w.has('p')) {
    const double p = w['p'].value;
    if (p < 1 || p != std::floor(p) || p > 1e6) {
      fail(w['p'].col, "arc turns P must be a positive integer");
    }
    turns = static_cast<std::uint32_t>(p) - 1;
  }
  arc_move(target, c, dr, ccw, turns, col);
}

void Interpreter::Impl::arc_move(const AxisVec& target, Vec2 c, double dr, bool ccw,
                                 std::uint32_t turns, std::uint32_t col) {
  const PlaneAxes pa = plane_axes(modal_.plane);
  const double turn = arc_turn_deg();
  const AxisVec from = turned(pos_, -turn), to = turned(target, -turn);
  const Vec2 s{from[pa.first], from[pa.second]};
  const Vec2 e{to[pa.first], to[pa.second]};
  check_arc_travel(target, c, dr, ccw, turns, col);
  // G93's length: the arc's (the radius at the start, or a spiral's mean) with the helix rise.
  const double sweep_rad = arc_sweep(s, e, c, ccw, turns);
  const double rise_mm = to[pa.normal] - from[pa.normal];
  const double mean_r = 0.5 * (std::hypot(s.a - c.a, s.b - c.b) + std::hypot(e.a - c.a, e.b - c.b));
  move_feed_mm_min_ = move_feed_mm_min(std::hypot(mean_r * sweep_rad, rise_mm), col);

  emit_arc(target, c, ccw, turns, col);
  pos_ = target;
}

// One arc block from pos_ to `target` about `c` (plane coordinates): a circular arc, or a
// spiral when the radii at the two ends differ,
//   p(t) = c + (r0 + (r1 − r0)·t)·(cos(θ0 + φ·t), sin(θ0 + φ·t)),  t ∈ [0, 1],
// with the helix axis and the other axes linear in t (src/planner/segment.cpp).
void Interpreter::Impl::emit_arc(const AxisVec& target, Vec2 c, bool ccw, std::uint32_t turns,
                                 std::uint32_t col) {
  const PlaneAxes pa = plane_axes(modal_.plane);
  in_sync_ = false;
  if (modal_.css) css_update(target, col);  // the speed at the arc's end, for the whole arc
  Block b = base_block(BlockKind::kArc);
  b.col = col;
  b.end = target;
  b.feed_mm_min = move_feed_mm_min_;
  set_path_mode(b);
  const double turn = arc_turn_deg();
  AxisVec centre = turned(pos_, -turn);  // projected into the plane of the start point
  centre[pa.first] = c.a;
  centre[pa.second] = c.b;
  b.center = turned(centre, turn).xyz();
  AxisVec normal;
  normal[pa.normal] = ccw ? 1.0 : -1.0;
  b.normal = turned(normal, turn).xyz();
  b.turns = turns;
  out_.push_back(b);
}

// Travel of an arc from pos_ to `target` about `c` (plane coordinates) whose end radius is
// the start's + dr: the end point, plus the axis-aligned extremes of the circle that the arc
// passes. When the whole circle (c ± r) lies inside the travel, the extremes need not be
// computed.
void Interpreter::Impl::check_arc_travel(const AxisVec& target, Vec2 c, double dr, bool ccw,
                                         std::uint32_t turns, std::uint32_t col) {
  if (arc_turn_deg() != 0) {
    check_turned_arc_travel(target, c, ccw, turns, col);
    return;
  }
  const PlaneAxes pa = plane_axes(modal_.plane);
  const Vec2 s{pos_[pa.first], pos_[pa.second]};
  const Vec2 e{target[pa.first], target[pa.second]};
  AxisVec lo = target, hi = target;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    lo[a] = std::min(pos_[a], target[a]);
    hi[a] = std::max(pos_[a], target[a]);
  }
  // (A spiral's radius differs from the start's by at most |r1 − r0|.)
  const double r = std::hypot(s.a - c.a, s.b - c.b) + std::fabs(dr);
  const AxisConfig& fa = machine_.axes[pa.first];
  const AxisConfig& sa = machine_.axes[pa.second];
  const bool circle_inside =
      c.a - r >= fa.min_mm && c.a + r <= fa.max_mm && c.b - r >= sa.min_mm && c.b + r <= sa.max_mm;
  if (!circle_inside) {
    const double sweep = arc_sweep(s, e, c, ccw, turns);
    Vec2 lo2, hi2;
    arc_bounds(s, e, c, sweep, lo2, hi2);
    // An extreme inside the sweep (not an end point) of a spiral: within |r1 − r0| of the
    // circle's.
    const double wa = std::fabs(dr);
    if (lo2.a < std::min(s.a, e.a)) lo2.a -= wa;
    if (lo2.b < std::min(s.b, e.b)) lo2.b -= wa;
    if (hi2.a > std::max(s.a, e.a)) hi2.a += wa;
    if (hi2.b > std::max(s.b, e.b)) hi2.b += wa;
    lo[pa.first] = lo2.a;
    lo[pa.second] = lo2.b;
    hi[pa.first] = hi2.a;
    hi[pa.second] = hi2.b;
  }
  check_travel(lo, hi, target, col);
}

double Interpreter::Impl::arc_turn_deg() const {
  return modal_.plane == Plane::kXY ? 0.0 : rotation_deg(modal_.coord_system);
}

AxisVec Interpreter::Impl::turned(AxisVec p, double deg) {
  const Vec2 xy = rotated({p[0], p[1]}, deg);
  p[0] = xy.a;
  p[1] = xy.b;
  return p;
}

// A turned arc's travel (its extremes are not those of its plane's axes): the points of its
// sweep every 0.25°, turned to the machine. Between two of them the arc bulges by at most
// r·(1 − cos 0.125°) = 2.4e-6·r beyond their box.
void Interpreter::Impl::check_turned_arc_travel(const AxisVec& target, Vec2 c, bool ccw,
                                                std::uint32_t turns, std::uint32_t col) {
  const PlaneAxes pa = plane_axes(modal_.plane);
  const double turn = arc_turn_deg();
  const AxisVec from = turned(pos_, -turn), to = turned(target, -turn);
  const Vec2 s{from[pa.first], from[pa.second]}, e{to[pa.first], to[pa.second]};
  const double r0 = std::hypot(s.a - c.a, s.b - c.b), r1 = std::hypot(e.a - c.a, e.b - c.b);
  const double a0 = std::atan2(s.b - c.b, s.a - c.a);
  // Extra turns sweep the whole circle: one turn at the larger radius stands for them.
  const double sweep = turns > 0 ? 2 * std::numbers::pi : arc_sweep(s, e, c, ccw, 0);
  const int n = std::max(8, static_cast<int>(std::ceil(sweep / (0.25 * std::numbers::pi / 180))));
  AxisVec lo = target, hi = target;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    lo[a] = std::min(pos_[a], target[a]);
    hi[a] = std::max(pos_[a], target[a]);
  }
  for (int k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / n;
    const double ang = a0 + (ccw ? 1 : -1) * sweep * t;
    const double r = turns > 0 ? std::max(r0, r1) : r0 + (r1 - r0) * t;
    AxisVec p = from;
    p[pa.first] = c.a + r * std::cos(ang);
    p[pa.second] = c.b + r * std::sin(ang);
    p[pa.normal] = from[pa.normal] + (to[pa.normal] - from[pa.normal]) * t;
    const AxisVec m = turned(p, turn);
    for (std::size_t a = 0; a < kLinearAxes; ++a) {
      lo[a] = std::min(lo[a], m[a]);
      hi[a] = std::max(hi[a], m[a]);
    }
  }
  check_travel(lo, hi, target, col);
}

double Interpreter::Impl::move_feed_mm_min(double length_mm, std::uint32_t col) const {
  const Words& w = words_;
  switch (modal_.feed_mode) {
    case FeedMode::kInverseTime:
      // F = 1 / (the move's time in minutes): v = length · F.
      if (!w.has('f')) fail(col, "G93 inverse time: every G1/G2/G3 line needs its F word");
      if (w['f'].value <= 0) fail(w['f'].col, "feed rate F is zero");
      return length_mm * w['f'].value;
    case FeedMode::kPerRevolution:
      // v = F (mm/rev) · S (rev/min).
      if (!modal_.feed_set) fail(col, "no feed rate: program F (per revolution) after G95");
      if (modal_.feed_mm_rev <= 0) fail(col, "feed rate F is zero");
      if (modal_.spindle_rpm <= 0) fail(col, "G95 feed per revolution without a spindle speed S");
      return modal_.feed_mm_rev * modal_.spindle_rpm;
    case FeedMode::kPerMinute:
      break;
  }
  if (!modal_.feed_set) fail(col, "no feed rate: program F before the first G1/G2/G3");
  if (modal_.feed_mm_min <= 0) fail(col, "feed rate F is zero");
  return modal_.feed_mm_min;
}

}  // namespace cncore::interp
