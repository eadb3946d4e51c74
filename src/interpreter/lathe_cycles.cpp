// G70 (finishing), G71 / G71.1 / G71.2 (roughing along Z) and G72 / G72.1 / G72.2 (facing)
// as LinuxCNC runs them: the block's X Z are the cycle's start point (a rapid goes there),
// Q names the subroutine whose G0 G1 G2 G3 lines are the finished profile. The subroutine is
// run for its profile only: its moves are collected, not made; O-word flow and parameters
// work as in any call. The geometry is in lathe_profile.hpp; here are the words and the moves.
//
// Profile lines: X Z (absolute, or incremental in G91), U W (incremental X Z in G90; U is a
// diameter in G7), I K or R for arcs (I K follow G90.1/G91.1), A (round the corner at the
// line's end with this radius) and C (chamfer it by this size).
#include <fmt/format.h>

#include <cmath>

#include "interpreter/interpreter_impl.hpp"
#include "interpreter/lathe_profile.hpp"

namespace cncore::interp {

using lathe::Pt;

struct LatheCapture {
  lathe::Profile profile;
  Pt at;            // where the profile is (program units, X a radius)
  int motion = -1;  // the profile's motion mode (G code × 10)
  bool incremental = false;
  bool ijk_incremental = true;
  std::size_t depth = 0;  // call depth of the cycle's line
};

namespace {
// Moves of the cycle's geometry → the interpreter.
template <class Fn>
class CycleMoves final : public lathe::MoveSink {
 public:
  explicit CycleMoves(Fn fn) : fn_(fn) {}
  void rapid(Pt end) override { fn_(0, Pt{}, end); }
  void feed(Pt end) override { fn_(1, Pt{}, end); }
  void arc(bool ccw, Pt centre, Pt end) override { fn_(ccw ? 3 : 2, centre, end); }

 private:
  Fn fn_;
};

// Resets the interpreter's capture pointer however the profile's reading ends.
class CaptureScope {
 public:
  CaptureScope(LatheCapture*& slot, LatheCapture& cap) : slot_(slot) { slot_ = &cap; }
  ~CaptureScope() { slot_ = nullptr; }
  CaptureScope(const CaptureScope&) = delete;
  CaptureScope& operator=(const CaptureScope&) = delete;

 private:
  LatheCapture*& slot_;
};
}  // namespace

bool Interpreter::Impl::lathe_cycle_block() const {
  const Words::Code* m = words_.group(GGroup::kMotion);
  if (m == nullptr) return false;
  const int c = m->code10;
  return c == 700 || c == 710 || c == 711 || c == 712 || c == 720 || c == 721 || c == 722;
}

Pt Interpreter::Impl::program_zx() const {
  const double unit = modal_.length_unit_mm();
  const AxisVec p = to_program(pos_, tool_offset_);
  return {p[kZ] / unit, p[kX] / unit};
}

AxisVec Interpreter::Impl::lathe_target(Pt p) const {
  const double unit = modal_.length_unit_mm();
  AxisVec prog = to_program(pos_, tool_offset_);
  prog[kX] = p.imag() * unit;
  prog[kZ] = p.real() * unit;
  return from_program(prog);
}

void Interpreter::Impl::lathe_move(bool rapid, Pt end, std::uint32_t col) {
  const Motion saved = modal_.motion;
  modal_.motion = rapid ? Motion::kRapid : Motion::kLine;
  line_motion(lathe_target(end), col);
  modal_.motion = saved;
}

void Interpreter::Impl::lathe_arc(bool ccw, Pt centre, Pt end, std::uint32_t col) {
  // LinuxCNC leaves out an arc that ends where the tool is (within 1e-4 on both axes).
  const Pt at = program_zx();
  if (std::fabs(at.real() - end.real()) < 1e-4 && std::fabs(at.imag() - end.imag()) < 1e-4) return;
  const PlaneAxes pa = plane_axes(modal_.plane);
  const AxisVec mc = turned(lathe_target(centre), -arc_turn_deg());
  // r1 − r0 (a spiral's growth) in program coordinates: the frame's turn keeps distances.
  const double dr_mm = (std::abs(end - centre) - std::abs(at - centre)) * modal_.length_unit_mm();
  arc_move(lathe_target(end), {mc[pa.first], mc[pa.second]}, dr_mm, ccw, 0, col);
}

// One line of the profile's subroutine (instead of executing it).
void Interpreter::Impl::capture_profile_block() {
  const Words& w = words_;
  LatheCapture& cap = *lathe_capture_;
  if (const auto* g = w.group(GGroup::kMotion)) {
    if (g->code10 != 0 && g->code10 != 10 && g->code10 != 20 && g->code10 != 30) {
      fail(g->col, fmt::format("{} in a lathe cycle's profile (only G0, G1, G2, G3)",
                               code_text('G', g->code10)));
    }
    cap.motion = g->code10;
  }
  Pt end = cap.incremental ? Pt{} : cap.at;
  for (const char c : {'u', 'w'}) {
    if (!w.has(c)) continue;
    const char other = c == 'u' ? 'x' : 'z';
    if (cap.incremental) fail(w[c].col, "U and W cannot be used in a profile in G91");
    if (w.has(other)) fail(w[c].col, "U and X (or W and Z) in one block of a profile");
  }
  if (w.has('u')) {
    end.imag(end.imag() + w['u'].value / (modal_.diameter_mode ? 2 : 1));
  } else if (w.has('x')) {
    end.imag(w['x'].value / (modal_.diameter_mode ? 2 : 1));
  }
  if (w.has('w')) {
    end.real(end.real() + w['w'].value);
  } else if (w.has('z')) {
    end.real(w['z'].value);
  }
  if (cap.incremental) end += cap.at;
  if (end == cap.at) return;
  // A line before any G0–G3 in the profile is a straight segment (LinuxCNC reads it so).
  const Pt from = cap.at;
  if (cap.motion <= 10) {
    cap.profile.push_back(lathe::line_seg(from, end));
  } else {
    cap.profile.push_back(lathe::arc_seg(cap.motion == 30, from, profile_centre(from, end), end));
  }
  if (w.has('a') && w.has('c')) fail(w['c'].col, "both A (round) and C (chamfer) on one corner");
  for (const char c : {'a', 'c'}) {
    if (!w.has(c)) continue;
    lathe::Seg corner = lathe::line_seg(end, end);
    corner.kind = c == 'a' ? lathe::SegKind::kFillet : lathe::SegKind::kChamfer;
    corner.centre = end;
    corner.finish = w[c].value;
    cap.profile.push_back(corner);
  }
  cap.at = end;
}

// The centre of a profile arc from its R or I K words (checked as a programmed arc is).
Pt Interpreter::Impl::profile_centre(Pt from, Pt end) const {
  const Words& w = words_;
  const LatheCapture& cap = *lathe_capture_;
  const bool ccw = cap.motion == 30;
  if (w.has('r')) {
    if (w.has('i') || w.has('k')) fail(w['r'].col, "arc with both R and I/K");
    // The shorter arc whatever R's sign (LinuxCNC's profiles), and no tolerance on the chord.
    Vec2 c;
    const ArcCheck chk = centre_from_radius({from.real(), from.imag()}, {end.real(), end.imag()},
                                            std::fabs(w['r'].value), ccw, 0, c);
    if (!chk.ok) fail(w['r'].col, chk.message);
    return {c.a, c.b};
  }
  if (!w.has('i') && !w.has('k')) fail(w.first_col, "profile arc without I/K or R");
  Pt c{w['k'].value, w['i'].value};
  if (cap.ijk_incremental) c += from;
  const double unit = modal_.length_unit_mm();
  const Vec2 s{from.real() * unit, from.imag() * unit}, e{end.real() * unit, end.imag() * unit};
  Vec2 cc{c.real() * unit, c.imag() * unit};
  const ArcCheck chk =
      check_centre(s, e, cc, modal_.inch ? kArcAbsTolInch * 25.4 : kArcAbsTolMm, kArcRelTol);
  if (!chk.ok) fail(w.first_col, chk.message);
  return c;
}

// Runs the subroutine named by Q for its profile; the reader is back after the cycle's line.
lathe::Profile Interpreter::Impl::read_profile(const Words::Value& q, Pt from) {
  OWord o;
  o.label = std::to_string(std::lround(q.value));
  o.keyword = OKeyword::kCall;
  o.col = q.col;
  o.args = line_.text.size();  // no arguments
  const NormLine line = line_;
  const std::uint32_t line_no = ctx_.line;
  LatheCapture cap;
  cap.at = from;
  cap.incremental = !modal_.absolute;
  cap.ijk_incremental = !modal_.arc_absolute;
  cap.depth = frames_.size();
  {
    const CaptureScope scope(lathe_capture_, cap);
    call_sub(o);
    while (frames_.size() > cap.depth) {
      if (at_eof_ || finished_) fail(q.col, "the profile's subroutine does not return");
      step();
    }
  }
  line_ = line;
  ctx_.line = line_no;
  if (cap.motion >= 0) set_motion_mode(cap.motion);  // as the profile left it (LinuxCNC)
  return std::move(cap.profile);
}

void Interpreter::Impl::lathe_cycle(std::uint32_t col) {
  const Words w = words_;  // the profile's lines overwrite words_
  const int code = w.group(GGroup::kMotion)->code10;
  const std::string name = code_text('G', code);
  if (!w.has('q')) fail(col, name + " without Q (the subroutine of the profile)");
  if (modal_.plane != Plane::kZX) fail(col, name + " works in the ZX plane only: program G18");
  if (w.has('i') && w['i'].value <= 0) fail(w['i'].col, name + " I (depth of cut) must be > 0");
  const Pt before = program_zx();
  Pt start = before;
  if (w.has('x')) start.imag(modal_.absolute ? w['x'].value : before.imag() + w['x'].value);
  if (w.has('z')) start.real(modal_.absolute ? w['z'].value : before.real() + w['z'].value);
  lathe_move(true, start, col);
  lathe::Profile profile = read_profile(w['q'], start);
  words_ = w;
  if (profile.size() < 2) return;
  // G71 / G72 close the profile back to the start point's X (Z for G72) when it ends away from
  // it on the far side.
  const Pt first = profile.front().end - profile.front().start;
  const lathe::Seg& last = profile.back();
  const Pt end = last.end;
  if (code / 10 == 71 && std::fabs((last.end - last.start).real()) > 0 &&
      first.imag() * (start.imag() - end.imag()) < 0) {
    profile.push_back(lathe::line_seg(end, {end.real(), start.imag()}));
  }
  if (code / 10 == 72 && std::fabs((last.end - last.start).imag()) > 0 &&
      first.real() * (start.real() - end.real()) < 0) {
    profile.push_back(lathe::line_seg(end, {start.real(), end.imag()}));
  }
  auto move = [&](int kind, Pt centre, Pt to) {
    if (kind < 2) {
      lathe_move(kind == 0, to, col);
    } else {
      lathe_arc(kind == 3, centre, to, col);
    }
  };
  CycleMoves<decltype(move)> out(move);
  auto value = [&](char c, double fallback) { return w.has(c) ? w[c].value : fallback; };
  try {
    if (code == 700) {
      const double passes = value('p', 1);
      if (passes < 1 || passes != std::floor(passes)) fail(w['p'].col, "G70 P must be ≥ 1 passes");
      lathe::finish(std::move(profile),
                    {start, value('d', 0), value('e', 0), static_cast<int>(passes)}, out);
    } else {
      lathe::RoughingParams p;
      p.variant = code % 10;
      p.facing = code / 10 == 72;
      p.start = start;
      p.shift = {value('w', 0), value('u', 0)};
      p.allowance = value('d', 0);
      p.depth = value('i', 1);
      p.retract = value('r', 0.5);
      lathe::rough(std::move(profile), p, out);
    }
  } catch (const lathe::ProfileError& e) {
    fail(col, fmt::format("{}: {}", name, e.message));
  }
}

}  // namespace cncore::interp
