// The `cncore check --blocks` line format (documented in docs/gcode.md):
//   N<line> RAPID from <axes> to <axes>[ <path>]
//   N<line> LINE from <axes> to <axes> F<feed>[ <sync>][ <path>]
//   N<line> ARC from <axes> to <axes> centre <x y z> normal <±X|±Y|±Z> turns <n> F<feed>[ <path>]
//   N<line> DWELL <seconds> s[ INDEX]
//   N<line> AUX <M|S|T><value>[ P<p> (M52)][ WAIT]
// <sync> is SYNC <mm/rev>[ START <deg>][ TAP IN|TAP OUT] (G33, G33.1, G76); INDEX marks the
// wait for the spindle's index pulse before them.
// <path> is EXACT_PATH (G61), EXACT_STOP (G61.1, G9) or TOL <mm> (G64 P); nothing for G64.
// Positions %.4f (mm, deg), feed %.3f mm/min.
#include <fmt/format.h>

#include <cmath>

#include "interpreter/interpreter.hpp"

namespace cncore::interp {

namespace {

double clean(double v) {
  return v == 0.0 ? 0.0 : v;
}  // no "-0.0000"

void append_num(std::string& s, double v) {
  v = clean(v);
  std::string t = fmt::format("{:.4f}", v);
  if (t == "-0.0000") t = "0.0000";
  s += t;
}

void append_axes(std::string& s, const AxisVec& p, const std::array<bool, kMaxAxes>& axes) {
  bool first = true;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!axes[a]) continue;
    if (!first) s += ' ';
    first = false;
    append_num(s, p[a]);
  }
}

void append_sync(std::string& s, const Block& b) {
  if (b.sync_mm_rev <= 0) return;
  s += fmt::format(" SYNC {:.4f}", b.sync_mm_rev);
  if (!std::isnan(b.sync_start_deg)) s += fmt::format(" START {:.4f}", b.sync_start_deg);
  if (b.rigid_tap == RigidTap::kIn) s += " TAP IN";
  if (b.rigid_tap == RigidTap::kOut) s += " TAP OUT";
}

std::string format_with(const Block& b, const std::array<bool, kMaxAxes>& axes) {
  std::string s = fmt::format("N{} ", b.line);
  auto path = [&] {
    switch (b.path_mode) {
      case PathMode::kExactPath:
        s += " EXACT_PATH";
        break;
      case PathMode::kExactStop:
        s += " EXACT_STOP";
        break;
      case PathMode::kBlend:
        if (b.tolerance_mm >= 0) s += fmt::format(" TOL {:.4f}", b.tolerance_mm);
        break;
    }
  };
  switch (b.kind) {
    case BlockKind::kRapid:
    case BlockKind::kLine:
    case BlockKind::kArc: {
      s += b.kind == BlockKind::kRapid  ? "RAPID from "
           : b.kind == BlockKind::kLine ? "LINE from "
                                        : "ARC from ";
      append_axes(s, b.start, axes);
      s += " to ";
      append_axes(s, b.end, axes);
      if (b.kind == BlockKind::kArc) {
        s += " centre ";
        append_num(s, b.center.x);
        s += ' ';
        append_num(s, b.center.y);
        s += ' ';
        append_num(s, b.center.z);
        s += " normal ";
        const Vec3 n = b.normal;
        if (std::fabs(n.x) == 1 && n.y == 0 && n.z == 0) {
          s += n.x > 0 ? "+X" : "-X";
        } else if (std::fabs(n.y) == 1 && n.x == 0 && n.z == 0) {
          s += n.y > 0 ? "+Y" : "-Y";
        } else if (std::fabs(n.z) == 1 && n.x == 0 && n.y == 0) {
          s += n.z > 0 ? "+Z" : "-Z";
        } else {
          s += fmt::format("{:.4f} {:.4f} {:.4f}", clean(n.x), clean(n.y), clean(n.z));
        }
        s += fmt::format(" turns {}", b.turns);
      }
      if (b.kind != BlockKind::kRapid) s += fmt::format(" F{:.3f}", b.feed_mm_min);
      append_sync(s, b);
      path();
      break;
    }
    case BlockKind::kDwell:
      s += fmt::format("DWELL {:.3f} s", b.dwell_s);
      if (b.index_wait) s += " INDEX";
      break;
    case BlockKind::kAux: {
      s += "AUX ";
      s += b.aux_letter;
      if (b.aux_value == std::floor(b.aux_value) && std::fabs(b.aux_value) < 1e15) {
        s += fmt::format("{}", static_cast<long long>(b.aux_value));
      } else {
        s += fmt::format("{:.4f}", b.aux_value);
      }
      if (b.aux_letter == 'M' && b.aux_value == 52) s += fmt::format(" P{:g}", b.aux_p);
      if (b.aux_waits) s += " WAIT";
      break;
    }
  }
  return s;
}

}  // namespace

std::string format_block(const Block& block) {
  return format_with(block, {true, true, true, false, false, false});
}

std::string format_block(const Block& block, const MachineConfig& machine) {
  std::array<bool, kMaxAxes> axes{};
  for (std::size_t a = 0; a < kMaxAxes; ++a) axes[a] = machine.axes[a].enabled;
  return format_with(block, axes);
}

}  // namespace cncore::interp
