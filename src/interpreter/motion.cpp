// Moves: the target of a block from its axis words, travel limits, G0/G1 lines and G2/G3 arcs
// (helices, spirals) in the active plane.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

AxisVec Interpreter::Impl::target_from_words(bool machine_coords) const {
  AxisVec target = pos_;
  const double unit = modal_.length_unit_mm();
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    const auto& v = words_[kAxisWords[a]];
    if (!v.present) continue;
    const double value = v.value * (is_rotary(a) ? 1.0 : unit);
    if (machine_coords) {
      target[a] = value + tool_offset_[a];  // G53: machine coordinates; the tool offset stays
    } else if (modal_.absolute) {
      target[a] = value + offset(a);  // G90: program coordinate + work offset (+ G92)
    } else {
      target[a] = pos_[a] + value;  // G91
    }
  }
  return target;
}

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

void Interpreter::Impl::emit_motion(BlockKind kind, const AxisVec& target, std::uint32_t col) {
  Block b = base_block(kind);
  b.end = target;
  b.col = col;
  b.feed_mm_min = kind == BlockKind::kRapid ? 0 : move_feed_mm_min_;
  b.path_mode =
      words_.group(GGroup::kExactStopOnce) != nullptr ? PathMode::kExactStop : modal_.path_mode;
  b.tolerance_mm = b.path_mode == PathMode::kBlend ? modal_.tolerance_mm : -1;
  b.smooth_tolerance_mm = modal_.smooth_tolerance_mm;
  out_.push_back(b);
}

// G0/G1 to `target` (machine coordinates).
void Interpreter::Impl::line_motion(const AxisVec& target, std::uint32_t col) {
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
  if (len2 > kZeroMoveMm * kZeroMoveMm) {
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
  const Vec2 s{pos_[pa.first], pos_[pa.second]};
  const Vec2 e{target[pa.first], target[pa.second]};
  Vec2 c;
  Vec2 programmed;  // the I J K centre as written (check_centre moves c onto the bisector)
  bool spiral = false;
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
      c = {i + offset(pa.first), j + offset(pa.second)};  // G90.1: program coordinates
    } else {
      c = {s.a + i, s.b + j};  // G91.1: relative to the start point
    }
    const double abs_tol = modal_.inch ? kArcAbsTolInch * 25.4 : kArcAbsTolMm;
    programmed = c;
    const double dr =
        std::hypot(e.a - c.a, e.b - c.b) - std::hypot(s.a - c.a, s.b - c.b);  // r1 − r0
    spiral = std::fabs(dr) > kSpiralMinMm;
    const ArcCheck chk = check_centre(s, e, c, abs_tol, kArcRelTol);
    if (!chk.ok) {
      const double r0 = std::hypot(s.a - c.a, s.b - c.b), r1 = std::hypot(e.a - c.a, e.b - c.b);
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
  // Travel: the end point, plus the axis-aligned extremes of the circle that the arc passes.
  // When the whole circle (c ± r) lies inside the travel, the extremes need not be computed.
  AxisVec lo = target, hi = target;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    lo[a] = std::min(pos_[a], target[a]);
    hi[a] = std::max(pos_[a], target[a]);
  }
  // (A spiral's radius differs from this one by at most the radius tolerance.)
  const double r = std::sqrt((s.a - c.a) * (s.a - c.a) + (s.b - c.b) * (s.b - c.b)) +
                   (spiral ? std::fabs(std::hypot(e.a - programmed.a, e.b - programmed.b) -
                                       std::hypot(s.a - programmed.a, s.b - programmed.b))
                           : 0.0);
  const AxisConfig& fa = machine_.axes[pa.first];
  const AxisConfig& sa = machine_.axes[pa.second];
  const bool circle_inside =
      c.a - r >= fa.min_mm && c.a + r <= fa.max_mm && c.b - r >= sa.min_mm && c.b + r <= sa.max_mm;
  if (!circle_inside) {
    const double sweep = arc_sweep(s, e, c, ccw, turns);
    Vec2 lo2, hi2;
    arc_bounds(s, e, c, sweep, lo2, hi2);
    lo[pa.first] = lo2.a;
    lo[pa.second] = lo2.b;
    hi[pa.first] = hi2.a;
    hi[pa.second] = hi2.b;
  }
  check_travel(lo, hi, target, col);
  // G93's length: the arc's (the radius at the start, or a spiral's mean) with the helix rise.
  const double sweep_rad = arc_sweep(s, e, c, ccw, turns);
  const double rise_mm = target[pa.normal] - pos_[pa.normal];
  const double mean_r = 0.5 * (std::hypot(s.a - c.a, s.b - c.b) + std::hypot(e.a - c.a, e.b - c.b));
  move_feed_mm_min_ = move_feed_mm_min(std::hypot(mean_r * sweep_rad, rise_mm), col);

  if (spiral) {
    arc_spiral(target, programmed, ccw, turns, col);
  } else {
    emit_arc(target, c, ccw, turns, col);
  }
  pos_ = target;
}

// G10 L2 / L20 (work offsets), G92, G92.1, G92.2, G92.3.

// One arc block from pos_ to `target` about `c` (plane coordinates; equal radii at both ends).
void Interpreter::Impl::emit_arc(const AxisVec& target, Vec2 c, bool ccw, std::uint32_t turns,
                                 std::uint32_t col) {
  const PlaneAxes pa = plane_axes(modal_.plane);
  Block b = base_block(BlockKind::kArc);
  b.col = col;
  b.end = target;
  b.feed_mm_min = move_feed_mm_min_;
  b.path_mode =
      words_.group(GGroup::kExactStopOnce) != nullptr ? PathMode::kExactStop : modal_.path_mode;
  b.tolerance_mm = b.path_mode == PathMode::kBlend ? modal_.tolerance_mm : -1;
  std::array<double, 3> centre{};
  centre[pa.first] = c.a;
  centre[pa.second] = c.b;
  centre[pa.normal] = pos_[pa.normal];  // projected into the plane of the start point
  b.center = {centre[0], centre[1], centre[2]};
  std::array<double, 3> normal{};
  normal[pa.normal] = ccw ? 1.0 : -1.0;
  b.normal = {normal[0], normal[1], normal[2]};
  b.turns = turns;
  out_.push_back(b);
}

// An I J K arc whose end radius r1 differs from its start radius r0 (within the tolerance):
// like LinuxCNC, the programmed centre c stays and the radius blends along the sweep φ,
//   p(t) = c + (r0 + (r1 − r0)·t)·(cos(θ0 + φ·t), sin(θ0 + φ·t)),  t ∈ [0, 1],
// with the helix axis and other axes linear in t. The planner takes circular arcs, so the
// spiral goes as n arcs through the points p(k/n), each with its radius change of at most
// kSpiralPieceMm (each arc then stays within about that of the spiral), and at most a quarter
// turn each.
void Interpreter::Impl::arc_spiral(const AxisVec& target, Vec2 c, bool ccw, std::uint32_t turns,
                                   std::uint32_t col) {
  const PlaneAxes pa = plane_axes(modal_.plane);
  const AxisVec start = pos_;
  const Vec2 s{start[pa.first], start[pa.second]};
  const Vec2 e{target[pa.first], target[pa.second]};
  const double r0 = std::hypot(s.a - c.a, s.b - c.b);
  const double r1 = std::hypot(e.a - c.a, e.b - c.b);
  const double theta0 = std::atan2(s.b - c.b, s.a - c.a);
  const double sweep = arc_sweep(s, e, c, ccw, turns);  // signed, CCW positive
  const double by_radius = std::ceil(std::fabs(r1 - r0) / kSpiralPieceMm);
  const double by_angle = std::ceil(std::fabs(sweep) / (std::numbers::pi / 2));
  const auto n = static_cast<int>(std::clamp(std::max(by_radius, by_angle), 2.0, 4096.0));
  for (int k = 1; k <= n; ++k) {
    const double t = static_cast<double>(k) / n;
    AxisVec p = target;
    if (k < n) {
      for (std::size_t a = 0; a < kMaxAxes; ++a) p[a] = start[a] + (target[a] - start[a]) * t;
      const double r = r0 + (r1 - r0) * t;
      const double theta = theta0 + sweep * t;
      p[pa.first] = c.a + r * std::cos(theta);
      p[pa.second] = c.b + r * std::sin(theta);
    }
    // The piece's own centre: c moved onto the bisector of its chord (its radii differ by
    // (r1 − r0)/n at most, far inside any tolerance).
    Vec2 pc = c;
    check_centre({pos_[pa.first], pos_[pa.second]}, {p[pa.first], p[pa.second]}, pc, 1e9, 1.0);
    emit_arc(p, pc, ccw, 0, col);
    pos_ = p;
  }
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
