// Canned cycles G73 G74 G81 G82 G83 G84 G85 G86 G88 G89 as LinuxCNC expands them, in the active
// plane (G17 drills along Z, G18 along Y, G19 along X), with G98/G99, L repeats and G91
// incremental repeats. A cycle becomes ordinary rapid, feed, dwell and spindle blocks here, so
// the planner sees nothing new; its moves follow the exact path (LinuxCNC switches to G61 for
// the cycle).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

namespace {
// LinuxCNC G83_RAPID_DELTA: how far above the last peck G73/G83 stop (0.010 in).
constexpr double kPeckClearanceMm = 0.254;
}  // namespace

// One straight move of a cycle to `target` (machine coordinates).
void Interpreter::Impl::cycle_move(bool rapid, const AxisVec& target, std::uint32_t col) {
  const Motion saved = modal_.motion;
  const PathMode saved_path = modal_.path_mode;
  modal_.motion = rapid ? Motion::kRapid : Motion::kLine;
  modal_.path_mode = PathMode::kExactPath;
  line_motion(target, col);
  modal_.motion = saved;
  modal_.path_mode = saved_path;
}

// The part of a cycle below R at the current hole (the tool is at R): down to the bottom and
// back to the clearance height `clear_mm` (machine coordinates along the drill axis).
void Interpreter::Impl::cycle_body(std::size_t drill_axis, double r_mm, double bottom_mm,
                                   double clear_mm, std::uint32_t col) {
  auto at = [&](double v) {
    AxisVec p = pos_;
    p[drill_axis] = v;
    return p;
  };
  auto dwell = [&] {
    if (modal_.cycle_p <= 0) return;
    Block b = base_block(BlockKind::kDwell);
    b.dwell_s = modal_.cycle_p;
    out_.push_back(b);
  };
  auto spindle = [&](int m) { emit_aux('M', m, true); };
  const int code = modal_.cycle;
  switch (code) {
    case 730:    // chip breaking: peck Q, back off a little, go on
    case 830: {  // peck drilling: peck Q, out to R, rapid back to just above the last peck
      const double q = modal_.cycle_q * modal_.length_unit_mm();
      if (q <= 0) fail(col, fmt::format("{} needs a peck depth Q > 0", code_text('G', code)));
      for (double depth = r_mm - q; depth > bottom_mm; depth -= q) {
        cycle_move(false, at(depth), col);
        if (code == 830) cycle_move(true, at(r_mm), col);
        cycle_move(true, at(depth + kPeckClearanceMm), col);
      }
      cycle_move(false, at(bottom_mm), col);
      cycle_move(true, at(clear_mm), col);
      return;
    }
    case 740:    // left-hand tapping: spindle reverses at the bottom
    case 840: {  // right-hand tapping
      const bool right = code == 840;
      cycle_move(false, at(bottom_mm), col);
      spindle(5);
      spindle(right ? 4 : 3);
      dwell();
      cycle_move(false, at(clear_mm), col);  // LinuxCNC feeds out to the clearance, R or G98's
      spindle(5);
      spindle(right ? 3 : 4);
      return;
    }
    case 850:  // boring, feed out (to the clearance height, as LinuxCNC)
    case 890:  // boring, dwell, feed out
      cycle_move(false, at(bottom_mm), col);
      if (code == 890) dwell();
      cycle_move(false, at(clear_mm), col);
      return;
    case 860:  // boring, spindle stop, rapid out
    case 880:  // boring, spindle stop, manual out (program stop)
      cycle_move(false, at(bottom_mm), col);
      dwell();
      spindle(5);
      if (code == 880) emit_aux('M', 0, true);
      cycle_move(true, at(clear_mm), col);
      spindle(3);
      return;
    case 870:
      back_bore(drill_axis, bottom_mm, clear_mm, col);
      return;
    default:  // 810 drilling, 820 drilling with dwell
      cycle_move(false, at(bottom_mm), col);
      if (code == 820) dwell();
      cycle_move(true, at(clear_mm), col);
      return;
  }
}

// A block of an active canned cycle. In G90 the hole is at the axis words (program
// coordinates), R and Z are heights along the drill axis; in G91 the hole moves by the axis
// words once per repeat, R is relative to the height at the start and Z to R.
void Interpreter::Impl::canned_cycle(std::uint32_t col) {
  const Words& w = words_;
  if (modal_.feed_mode == FeedMode::kInverseTime) {
    fail(col, "canned cycles cannot run in G93 inverse time mode: program G94 first");
  }
  const PlaneAxes pa = plane_axes(modal_.plane);
  const std::size_t n = pa.normal;
  const char drill_word = kAxisWords[n];
  for (std::size_t a = kLinearAxes; a < kMaxAxes; ++a) {
    if (w.has(kAxisWords[a])) {
      fail(w[kAxisWords[a]].col, fmt::format("{} word in a canned cycle", kAxisLetters[a]));
    }
  }
  if (w.has('r')) {
    modal_.cycle_r = w['r'].value;
    modal_.cycle_r_set = true;
  }
  if (w.has(drill_word)) {
    modal_.cycle_z = w[drill_word].value;
    modal_.cycle_z_set = true;
  }
  if (w.has('p')) modal_.cycle_p = w['p'].value;
  if (modal_.cycle == 870) back_bore_words(col);
  if (w.has('q')) modal_.cycle_q = w['q'].value;
  const char up = static_cast<char>(drill_word - 'a' + 'A');
  const std::string g = code_text('G', modal_.cycle);
  if (!modal_.cycle_r_set) fail(col, fmt::format("{} without R (the retract height)", g));
  if (!modal_.cycle_z_set) fail(col, fmt::format("{} without {} (the bottom)", g, up));
  if (modal_.cycle_p < 0) fail(w['p'].col, "negative dwell time P");
  std::uint64_t repeats = 1;
  if (w.has('l')) {
    const double l = w['l'].value;
    if (l < 1 || l != std::floor(l) || l >= static_cast<double>(machine_.max_loop_iterations)) {
      fail(w['l'].col, "L must be the number of repeats (a positive integer)");
    }
    repeats = static_cast<std::uint64_t>(l);
  }

  const double unit = modal_.length_unit_mm();
  const bool turned = rotation_deg(modal_.coord_system) != 0;
  if (turned && modal_.plane != Plane::kXY) {
    fail(col, fmt::format("{} in {} in a rotated coordinate system (G10 L2 R): only G17 cycles "
                          "turn with the rotation",
                          g, plane_gcode(modal_.plane)));
  }
  if (!modal_.cycle_initial_set) {
    modal_.cycle_initial_mm = pos_[n];
    modal_.cycle_initial_set = true;
  }
  double old_cc = modal_.cycle_initial_mm;
  const double r_mm =
      modal_.absolute ? modal_.cycle_r * unit + offset(n) : old_cc + modal_.cycle_r * unit;
  const double bottom_mm =
      modal_.absolute ? modal_.cycle_z * unit + offset(n) : r_mm + modal_.cycle_z * unit;
  if (r_mm < bottom_mm) {
    fail(col, fmt::format("{}: R is below the bottom {} (the cycle would cut upwards)", g, up));
  }
  // Below R at the start: up to R first, where the tool is.
  if (old_cc < r_mm) {
    AxisVec p = pos_;
    p[n] = r_mm;
    cycle_move(true, p, col);
    old_cc = r_mm;
  }
  const double clear_mm = modal_.retract_to_r ? r_mm : old_cc;
  for (std::uint64_t k = 0; k < repeats; ++k) {
    if (k > 0) spend(ctx_.line, col);
    AxisVec hole = pos_;
    if (turned) {
      // The hole in the rotated program frame (G17: X and Y turn together).
      AxisVec p = to_program(pos_, tool_offset_);
      for (const std::size_t a : {pa.first, pa.second}) {
        const auto& v = w[kAxisWords[a]];
        if (v.present) p[a] = modal_.absolute ? v.value * unit : p[a] + v.value * unit;
      }
      const AxisVec m = from_program(p);
      hole[pa.first] = m[pa.first];
      hole[pa.second] = m[pa.second];
    }
    for (const std::size_t a : {pa.first, pa.second}) {
      const auto& v = w[kAxisWords[a]];
      if (!v.present || turned) continue;
      hole[a] = modal_.absolute ? v.value * unit + offset(a) : pos_[a] + v.value * unit;
    }
    hole[n] = old_cc;
    cycle_move(true, hole, col);
    if (old_cc != r_mm) {
      hole[n] = r_mm;
      cycle_move(true, hole, col);
    }
    cycle_body(n, r_mm, bottom_mm, clear_mm, col);
    old_cc = clear_mm;
  }
}

// G87's I J K: required on the first block of a series, then in force like R.
void Interpreter::Impl::back_bore_words(std::uint32_t col) {
  const Words& w = words_;
  const bool first = !modal_.cycle_initial_set;
  for (std::size_t a = 0; a < kLinearAxes; ++a) {
    const char c = static_cast<char>('i' + a);
    if (w.has(c)) {
      modal_.cycle_ijk[a] = w[c].value;
    } else if (first) {
      fail(col, fmt::format("G87 without {} (see docs/gcode.md)", static_cast<char>('I' + a)));
    }
  }
  if (modal_.spindle_dir == 0) fail(col, "G87 needs the spindle turning: program M3 or M4 first");
}

// G87 back boring, as LinuxCNC moves: the tool enters the hole beside its axis (the plane words'
// I J K offsets) with the spindle stopped, goes below the part to the bottom, centres, bores
// upward at feed to the top of the back bore (the drill axis's I J K word; in G91 from the
// bottom) and back down, stops the spindle and leaves the way it came.
void Interpreter::Impl::back_bore(std::size_t n, double bottom_mm, double clear_mm,
                                  std::uint32_t col) {
  const PlaneAxes pa = plane_axes(modal_.plane);
  const double unit = modal_.length_unit_mm();
  const double middle_mm = modal_.absolute ? modal_.cycle_ijk[n] * unit + offset(n)
                                           : bottom_mm + modal_.cycle_ijk[n] * unit;
  AxisVec hole = pos_;  // at R over the hole
  AxisVec entry = hole;
  entry[pa.first] += modal_.cycle_ijk[pa.first] * unit;
  entry[pa.second] += modal_.cycle_ijk[pa.second] * unit;
  const double turning = modal_.spindle_dir > 0 ? 3 : 4;
  auto along = [&](AxisVec p, double v) {
    p[n] = v;
    return p;
  };
  cycle_move(true, entry, col);
  emit_aux('M', 5, true);
  cycle_move(true, along(entry, bottom_mm), col);
  cycle_move(true, along(hole, bottom_mm), col);
  emit_aux('M', turning, true);
  cycle_move(false, along(hole, middle_mm), col);
  cycle_move(false, along(hole, bottom_mm), col);
  emit_aux('M', 5, true);
  cycle_move(true, along(entry, bottom_mm), col);
  cycle_move(true, along(entry, clear_mm), col);
  cycle_move(true, along(hole, clear_mm), col);
  emit_aux('M', turning, true);
}

}  // namespace cncore::interp
