// Spindle-synchronised motion: G33 (a threading move), G33.1 (rigid tapping), the G76
// threading cycle as LinuxCNC expands it, and G96/G97 constant surface speed.
//
// A synchronised move advances K per spindle revolution along its path. The simulated spindle
// turns at its programmed speed exactly, so following its angle is the feed v = K·S; the
// move carries Block::sync_mm_rev and the feed override does not act on it. Every series of
// synchronised moves starts from rest (a zero dwell: the wait for the spindle's index pulse),
// so each pass of a thread starts the same way.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

namespace {
// G96: a line is cut where the spindle speed changes by more than this fraction.
constexpr double kCssStep = 0.02;
constexpr std::size_t kX = 0, kZ = 2;
}  // namespace

// ---------------------------------------------------------------------------------------------
// Spindle speed: S in G97 (rpm) or G96 (surface speed), D (G96's rpm limit).

double Interpreter::Impl::work_radius_mm(const AxisVec& m) const {
  return std::fabs(to_program(m, tool_offset_)[kX]);
}

// rpm = v_surface / (2π·r), at most D.
double Interpreter::Impl::css_rpm(double radius_mm, std::uint32_t col) const {
  const double limit = modal_.css_max_rpm > 0 ? modal_.css_max_rpm : HUGE_VAL;
  if (radius_mm <= 1e-9) {
    if (modal_.css_max_rpm <= 0) {
      fail(col,
           "G96 at X0 without D: the spindle speed would be infinite (program D, the "
           "maximum rpm)");
    }
    return limit;
  }
  return std::min(limit, modal_.css_mm_min / (2 * std::numbers::pi * radius_mm));
}

// Steps 5 and 14 of the order of execution: S, G96 D / G97.
void Interpreter::Impl::spindle_speed_words(double unit) {
  const Words& w = words_;
  if (const auto* g = w.group(GGroup::kSpindleMode)) modal_.css = g->code10 == 960;
  if (w.has('d') && w.group(GGroup::kSpindleMode) != nullptr && modal_.css) {
    if (w['d'].value < 0) fail(w['d'].col, "negative spindle speed limit D");
    modal_.css_max_rpm = w['d'].value;
  }
  if (!w.has('s')) {
    if (w.group(GGroup::kSpindleMode) != nullptr && modal_.css) css_update(pos_, w.first_col);
    return;
  }
  if (w['s'].value < 0) fail(w['s'].col, "negative spindle speed S");
  if (!modal_.css) {
    modal_.spindle_rpm = w['s'].value;
    emit_aux('S', w['s'].value, false);
    return;
  }
  // Metres (G21) or feet (G20) of surface per minute.
  modal_.css_mm_min = w['s'].value * (unit == 1.0 ? 1000.0 : 304.8);
  css_update(pos_, w['s'].col);
}

// G96: the spindle speed for the tool at machine position `at` (an S event when it changed).
void Interpreter::Impl::css_update(const AxisVec& at, std::uint32_t col) {
  const double rpm = css_rpm(work_radius_mm(at), col);
  if (rpm == modal_.spindle_rpm) return;
  modal_.spindle_rpm = rpm;
  emit_aux('S', rpm, false);
}

// M19 R Q P: orient the spindle to R degrees (P 0 clockwise, 1 counter-clockwise, 2 the
// shorter way; Q the time allowed). The spindle stops there; the simulated spindle has no
// angle, so the orientation itself is instantaneous.
void Interpreter::Impl::orient_words() const {
  const Words& w = words_;
  if (w.has('p')) {
    const double p = w['p'].value;
    if (p != 0 && p != 1 && p != 2) fail(w['p'].col, "M19 P must be 0, 1 or 2 (the direction)");
  }
  if (w.has('q') && w['q'].value <= 0) fail(w['q'].col, "M19 Q (the time allowed) must be > 0");
}

// G1 in G96: the line is cut into pieces over which the speed changes by at most kCssStep,
// each run at the speed of its middle (its feed too, in G95). Below the radius where D caps
// the speed it is constant, and that stretch stays one piece.
void Interpreter::Impl::css_line(const AxisVec& target, std::uint32_t col) {
  const AxisVec from = pos_;
  const AxisVec p0 = to_program(from, tool_offset_);
  const AxisVec p1 = to_program(target, tool_offset_);
  const double x0 = p0[kX], dx = p1[kX] - p0[kX];
  const double capped_r = modal_.css_max_rpm > 0
                              ? modal_.css_mm_min / (2 * std::numbers::pi * modal_.css_max_rpm)
                              : 0.0;
  auto point = [&](double t) {
    AxisVec p;
    for (std::size_t a = 0; a < kMaxAxes; ++a) p[a] = from[a] + (target[a] - from[a]) * t;
    return p;
  };
  if (modal_.css_max_rpm <= 0 && std::fabs(dx) > 1e-12 && -x0 / dx >= 0 && -x0 / dx <= 1) {
    css_rpm(0, col);  // through X0 without a limit: the error
  }
  double t = 0;
  for (int pieces = 0; t < 1.0; ++pieces) {
    double next = 1.0;
    if (std::fabs(dx) > 1e-12 && pieces < 100000) {
      const double r = std::fabs(x0 + dx * t);
      // The stretch |x| ≤ capped_r runs at D: the line leaves it at t_out.
      const double lo = (-capped_r - x0) / dx, hi = (capped_r - x0) / dx;
      const double t_in = std::min(lo, hi), t_out = std::max(lo, hi);
      if (r <= capped_r && capped_r > 0) {
        next = std::min(1.0, t_out);
      } else {
        next = std::min(1.0, t + kCssStep * r / std::fabs(dx));
        if (t_in > t + 1e-12 && capped_r > 0) next = std::min(next, t_in);
      }
      next = std::max(next, t + 1e-9);
    }
    const AxisVec mid = point((t + next) / 2);
    const double rpm = css_rpm(work_radius_mm(mid), col);
    if (rpm != modal_.spindle_rpm) {
      modal_.spindle_rpm = rpm;
      emit_aux('S', rpm, false);
    }
    plain_line_motion(next >= 1.0 ? target : point(next), col);
    t = next;
  }
}

// ---------------------------------------------------------------------------------------------
// Synchronised moves.

double Interpreter::Impl::sync_rpm(std::uint32_t col, const char* what) const {
  if (modal_.spindle_dir == 0) {
    fail(col, fmt::format("{} needs the spindle turning: program S and M3 or M4 first", what));
  }
  if (modal_.spindle_rpm <= 0) fail(col, fmt::format("{} without a spindle speed S", what));
  if (modal_.feed_mode == FeedMode::kInverseTime) {
    fail(col, fmt::format("{} cannot run in G93 inverse time mode", what));
  }
  return modal_.spindle_rpm;
}

// One synchronised line to `target`: mm_rev of path per revolution, v = mm_rev·rpm. A series
// starts from rest (the index wait). An axis limit the thread's speed exceeds would bend the
// pitch: that is an error at the line, as a real control refuses it.
void Interpreter::Impl::emit_sync_line(const AxisVec& target, double mm_rev, std::uint32_t col,
                                       const char* what) {
  const double feed = mm_rev * sync_rpm(col, what);
  double len2 = 0;
  for (std::size_t a = 0; a < kLinearAxes; ++a)
    len2 += (target[a] - pos_[a]) * (target[a] - pos_[a]);
  const double len = std::sqrt(len2);
  check_travel(target, target, target, col);
  if (len <= kZeroMoveMm) {
    pos_ = target;
    return;
  }
  for (std::size_t a = 0; a < kLinearAxes; ++a) {
    const double v_axis = feed * std::fabs(target[a] - pos_[a]) / len;
    const double limit = machine_.axes[a].max_speed_mm_min;
    if (limit > 0 && v_axis > limit * (1 + 1e-9)) {
      fail(col, fmt::format("{}: {:.1f} mm/min per revolution pitch at {:.0f} rpm needs {} at "
                            "{:.0f} mm/min, beyond its limit {:.0f} mm/min: lower S",
                            what, mm_rev, modal_.spindle_rpm, kAxisLetters[a], v_axis, limit));
    }
  }
  if (!in_sync_) {
    Block wait = base_block(BlockKind::kDwell);
    wait.dwell_s = 0;
    wait.index_wait = true;
    out_.push_back(wait);
  }
  Block b = base_block(BlockKind::kLine);
  b.end = target;
  b.col = col;
  b.feed_mm_min = feed;
  b.sync_mm_rev = mm_rev;
  b.sync_start_deg = sync_start_deg_;
  b.rigid_tap = sync_tap_;
  b.override_fixed = true;
  set_path_mode(b);
  out_.push_back(b);
  in_sync_ = true;
  pos_ = target;
}

// The K word of G33 / G33.1: the distance per revolution (program units).
double Interpreter::Impl::pitch_word(const char* what) const {
  const Words& w = words_;
  if (!w.has('k'))
    fail(w.first_col, fmt::format("{} without K (the distance per revolution)", what));
  if (w['k'].value <= 0) fail(w['k'].col, "K (the distance per revolution) must be > 0");
  return w['k'].value * modal_.length_unit_mm();
}

// D of G33 / G76: the spindle angle past the index where the thread starts; LinuxCNC takes a
// negative D by its magnitude.
double Interpreter::Impl::start_angle_word() const {
  return words_.has('d') ? std::fabs(words_['d'].value) : std::numeric_limits<double>::quiet_NaN();
}

// G33 X Y Z K [D]: a move that follows the spindle.
void Interpreter::Impl::spindle_sync_motion(const AxisVec& target, std::uint32_t col) {
  sync_start_deg_ = start_angle_word();
  emit_sync_line(target, pitch_word("G33"), col, "G33");
  sync_start_deg_ = std::numeric_limits<double>::quiet_NaN();
}

// G33.1 X Y Z K [I]: in to the target following the spindle, stop, reverse the spindle, out to
// the start following it again (I times faster), the spindle's direction restored.
void Interpreter::Impl::rigid_tap(const AxisVec& target, std::uint32_t col) {
  const Words& w = words_;
  const double k_mm = pitch_word("G33.1");
  double out_factor = 1;
  if (w.has('i')) {
    if (w['i'].value < 1) fail(w['i'].col, "I (the speed factor of the way out) must be >= 1");
    out_factor = w['i'].value;
  }
  const AxisVec start = pos_;
  const int dir = modal_.spindle_dir;
  const double rpm = modal_.spindle_rpm;
  const PathMode saved = modal_.path_mode;
  modal_.path_mode = PathMode::kExactStop;
  sync_tap_ = RigidTap::kIn;
  emit_sync_line(target, k_mm, col, "G33.1");
  emit_aux('M', dir > 0 ? 4 : 3, true);
  modal_.spindle_dir = -dir;
  if (out_factor != 1) {
    modal_.spindle_rpm = rpm * out_factor;
    emit_aux('S', modal_.spindle_rpm, false);
  }
  sync_tap_ = RigidTap::kOut;
  emit_sync_line(start, k_mm, col, "G33.1");
  sync_tap_ = RigidTap::kNone;
  modal_.path_mode = saved;
  emit_aux('M', dir > 0 ? 3 : 4, true);
  modal_.spindle_dir = dir;
  if (out_factor != 1) {
    modal_.spindle_rpm = rpm;
    emit_aux('S', rpm, false);
  }
  in_sync_ = false;
}

// ---------------------------------------------------------------------------------------------
// G76 P Z I J K [R Q H E L]: the threading cycle of a lathe (G18), as LinuxCNC expands it.
// The drive line runs from the current position to Z; the thread's peaks are I from it
// (negative: an outside thread). Pass n cuts depth d = J·n^(1/R) beyond the peaks while
// d < K, then one pass at K and H spring passes at K. The compound angle Q moves each pass's
// start along the thread by d·tan Q; E and L taper the start and/or end over E along Z.

struct ThreadPass {
  double start_x = 0, start_z = 0, end_z = 0;  // drive line (machine mm)
  double peaks_x = 0, dir = -1, travel = -1;   // dir: +1 inside; travel: sign of end − start
  double full_mm = 0, clear_mm = 0, tan_q = 0, taper_mm = 0;
  double pitch_mm = 0, taper_pitch_mm = 0;
  bool taper_in = false, taper_out = false;
};

void Interpreter::Impl::threading_pass(const ThreadPass& t, double depth, std::uint32_t col) {
  const double cut_x = t.peaks_x + t.dir * depth;
  const double back_x = cut_x - t.dir * t.clear_mm;
  const double crest_x = cut_x - t.dir * t.full_mm;
  const double zoff = t.travel * depth * t.tan_q;
  // The end of every pass lies at the full-depth pass's end shifted by the same compound move.
  const double target_z = t.end_z - t.travel * t.full_mm * t.tan_q;
  auto at = [&](double x, double z) {
    AxisVec p = pos_;
    p[kX] = x;
    p[kZ] = z;
    return p;
  };
  auto rapid = [&](double x, double z) {
    const Motion saved = modal_.motion;
    modal_.motion = Motion::kRapid;
    plain_line_motion(at(x, z), col);
    modal_.motion = saved;
    in_sync_ = false;
  };
  rapid(back_x, t.start_z + zoff);
  if (t.taper_in) {
    emit_sync_line(at(crest_x, t.start_z + zoff), t.taper_pitch_mm, col, "G76");
    emit_sync_line(at(cut_x, t.start_z + zoff + t.travel * t.taper_mm), t.taper_pitch_mm, col,
                   "G76");
  } else {
    rapid(cut_x, t.start_z + zoff);
  }
  if (t.taper_out) {
    emit_sync_line(at(cut_x, target_z + zoff - t.travel * t.taper_mm), t.pitch_mm, col, "G76");
    // LinuxCNC stamps the start angle on every synchronised start of a pass but the exit taper's.
    const double angle = std::exchange(sync_start_deg_, std::numeric_limits<double>::quiet_NaN());
    emit_sync_line(at(crest_x, target_z + zoff), t.taper_pitch_mm, col, "G76");
    sync_start_deg_ = angle;
  } else {
    emit_sync_line(at(cut_x, target_z + zoff), t.pitch_mm, col, "G76");
  }
  rapid(back_x, target_z + zoff);
}

// Size: the words' checks (each with its message) and the pass loop; split, the checks would
// need the whole word set handed over.
void Interpreter::Impl::threading_cycle(std::uint32_t col) {
  const Words& w = words_;
  if (modal_.plane != Plane::kZX) fail(col, "G76 needs the ZX plane: program G18 first");
  if (rotation_deg(modal_.coord_system) != 0) {
    fail(col, "G76 in a rotated coordinate system (G10 L2 R)");
  }
  for (char c : {'x', 'y', 'a', 'b', 'c'}) {
    if (w.has(c)) {
      fail(w[c].col, fmt::format("{} word with G76: the drive line starts where the tool is",
                                 static_cast<char>(c - 'a' + 'A')));
    }
  }
  auto need = [&](char c, const char* what) {
    if (!w.has(c))
      fail(col, fmt::format("G76 without {} ({})", static_cast<char>(c - 'a' + 'A'), what));
    return w[c].value;
  };
  const double unit = modal_.length_unit_mm();
  // In diameter mode (G7) I, J and K are diameters too.
  const double radial = unit * (modal_.diameter_mode ? 0.5 : 1.0);
  const double p = need('p', "the pitch") * unit;
  const double z_word = need('z', "the end of the drive line");
  const double i = need('i', "the offset of the thread's peaks from the drive line") * radial;
  const double j = need('j', "the first cut's depth") * radial;
  const double k = need('k', "the thread's depth") * radial;
  if (p <= 0) fail(w['p'].col, "G76: P (the pitch) must be > 0");
  if (j <= 0) fail(w['j'].col, "G76: J (the first cut's depth) must be > 0");
  if (k < j) fail(w['k'].col, "G76: K (the thread's depth) must be at least J");
  const double r = w.has('r') ? w['r'].value : 1.0;
  if (r < 1) fail(w['r'].col, "G76: R (the depth degression) must be >= 1");
  const double q = w.has('q') ? w['q'].value : 0.0;
  if (q < 0 || q >= 90) fail(w['q'].col, "G76: Q (the compound angle) must be in [0, 90) degrees");
  const double h = w.has('h') ? w['h'].value : 0.0;
  if (h < 0 || h != std::floor(h))
    fail(w['h'].col, "G76: H (spring passes) must be a whole number >= 0");
  const double l = w.has('l') ? w['l'].value : 0.0;
  if (l != 0 && l != 1 && l != 2 && l != 3) fail(w['l'].col, "G76: L must be 0, 1, 2 or 3");
  const double e = w.has('e') ? w['e'].value * unit : 0.0;
  if (e < 0) fail(w['e'].col, "G76: E (the taper length) must be >= 0");

  ThreadPass t;
  t.start_x = pos_[kX];
  t.start_z = pos_[kZ];
  t.end_z = modal_.absolute ? z_word * unit + offset(kZ) : pos_[kZ] + z_word * unit;
  if (std::fabs(t.end_z - t.start_z) <= kZeroMoveMm)
    fail(w['z'].col, "G76: Z is where the tool is");
  if (2 * e > std::fabs(t.end_z - t.start_z)) {
    fail(w['e'].col, "G76: E is more than half the thread's length");
  }
  t.travel = t.end_z > t.start_z ? 1.0 : -1.0;
  t.dir = i > 0 ? 1.0 : -1.0;  // inside threads (I > 0) are cut outwards
  t.peaks_x = t.start_x + i;
  t.full_mm = k;
  t.clear_mm = k + std::fabs(i);
  t.tan_q = std::tan(q * std::numbers::pi / 180.0);
  t.taper_mm = e;
  t.pitch_mm = p;
  // Along the tapered stretch the path is longer than its Z: p·√(K² + E²)/E keeps p along Z.
  t.taper_pitch_mm = e > 0 ? p * std::hypot(k, e) / e : p;
  t.taper_in = e > 0 && (l == 1 || l == 3);
  t.taper_out = e > 0 && (l == 2 || l == 3);
  sync_rpm(col, "G76");

  sync_start_deg_ = start_angle_word();
  double depth = j;
  for (double pass = 1; depth < k; depth = j * std::pow(++pass, 1.0 / r)) {
    spend(ctx_.line, col);
    threading_pass(t, depth, col);
  }
  for (double n = 0; n <= h; ++n) {
    spend(ctx_.line, col);
    threading_pass(t, k, col);
  }
  sync_start_deg_ = std::numeric_limits<double>::quiet_NaN();
  // Back to the drive line at the thread's end.
  AxisVec end = pos_;
  end[kX] = t.start_x;
  end[kZ] = t.end_z;
  const Motion saved = modal_.motion;
  modal_.motion = Motion::kRapid;
  plain_line_motion(end, col);
  modal_.motion = saved;
}

}  // namespace cncore::interp
