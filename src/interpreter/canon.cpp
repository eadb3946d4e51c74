// LinuxCNC's canonical-machine calls for blocks (`cncore check --canon`), so that a listing
// compares line by line with `rs274 -g`: positions in program coordinates and units (LinuxCNC
// applies the work and G92 offsets, the rotation and the tool length offset below the
// canonical interface), 4 decimals, arcs in their plane's axis order.
#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "interpreter/interpreter.hpp"

namespace cncore::interp {

namespace {

std::string num(double v) {
  std::string s = fmt::format("{:.4f}", v);
  if (s == "-0.0000") s = "0.0000";
  return s;
}

// program = R(−θ)·(machine − tool − work) − g92, in program units (rotary axes in degrees).
AxisVec to_program(const AxisVec& m, const CanonFrame& f) {
  AxisVec p;
  for (std::size_t a = 0; a < kMaxAxes; ++a)
    p[a] = m[a] - f.tool_offset_mm[a] - f.work_offset_mm[a];
  if (f.rotation_deg != 0) {
    const double rad = -f.rotation_deg * std::numbers::pi / 180.0;
    const double x = p[0], y = p[1];
    p[0] = x * std::cos(rad) - y * std::sin(rad);
    p[1] = x * std::sin(rad) + y * std::cos(rad);
  }
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    p[a] -= f.g92_offset_mm[a];
    if (a < 3) p[a] /= f.unit_mm;
  }
  return p;
}

}  // namespace

std::string CanonPrinter::print(const Block& b, const CanonFrame& f) {
  auto at = [&](const AxisVec& p, std::size_t a) { return to_program(p, f)[a]; };
  auto axes = [&](const AxisVec& p) {
    return fmt::format("{}, {}, {}, {}, {}, {}", num(at(p, 0)), num(at(p, 1)), num(at(p, 2)),
                       num(at(p, 3)), num(at(p, 4)), num(at(p, 5)));
  };
  std::string out;
  auto feed = [&] {
    const double per_min = b.feed_mm_min / f.unit_mm;
    if (per_min != last_feed_) out += fmt::format("SET_FEED_RATE({})\n", num(per_min));
    last_feed_ = per_min;
  };
  // LinuxCNC: START_SPEED_FEED_SYNC(pitch, velocity mode[, start angle]) before synchronised
  // moves; a new pitch or angle starts a new synchronisation.
  const bool angle = !std::isnan(b.sync_start_deg);
  const bool same_angle = angle ? b.sync_start_deg == last_sync_deg_ : std::isnan(last_sync_deg_);
  if (is_motion(b) && (b.sync_mm_rev != last_sync_ || !same_angle)) {
    if (b.sync_mm_rev > 0) {
      out += fmt::format("START_SPEED_FEED_SYNC({:.6f},0", b.sync_mm_rev / f.unit_mm);
      out += angle ? fmt::format(",{:.6f})\n", b.sync_start_deg) : ")\n";
    } else {
      out += "STOP_SPEED_FEED_SYNCH()\n";
    }
    last_sync_ = b.sync_mm_rev;
    last_sync_deg_ = b.sync_start_deg;
  }
  switch (b.kind) {
    case BlockKind::kRapid:
      out += fmt::format("STRAIGHT_TRAVERSE({})\n", axes(b.end));
      break;
    case BlockKind::kLine:
      // G33.1 is one call: in to the depth, the spindle reversed, out again below the interface.
      if (b.rigid_tap == RigidTap::kOut) break;
      if (b.rigid_tap == RigidTap::kIn) {
        out += fmt::format("RIGID_TAP({}, {}, {})\n", num(at(b.end, 0)), num(at(b.end, 1)),
                           num(at(b.end, 2)));
        break;
      }
      if (b.sync_mm_rev <= 0) feed();
      out += fmt::format("STRAIGHT_FEED({})\n", axes(b.end));
      break;
    case BlockKind::kArc: {
      feed();
      // The plane from the normal: G17 (X, Y; axis Z), G18 (Z, X; axis Y), G19 (Y, Z; axis X).
      // (The normal in the program's frame: a G18/G19 arc of a rotated system is turned.)
      const double rad = -f.rotation_deg * std::numbers::pi / 180.0;
      const Vec3 nrm{b.normal.x * std::cos(rad) - b.normal.y * std::sin(rad),
                     b.normal.x * std::sin(rad) + b.normal.y * std::cos(rad), b.normal.z};
      std::size_t p = 0, q = 1, n = 2;
      double turn = nrm.z;
      if (std::fabs(nrm.y) > 0.5) {
        p = 2, q = 0, n = 1;
        turn = nrm.y;
      } else if (std::fabs(nrm.x) > 0.5) {
        p = 1, q = 2, n = 0;
        turn = nrm.x;
      }
      AxisVec c;
      c.set_xyz(b.center);
      const int rotation = (turn > 0 ? 1 : -1) * static_cast<int>(b.turns + 1);
      out +=
          fmt::format("ARC_FEED({}, {}, {}, {}, {}, {}, {}, {}, {})\n", num(at(b.end, p)),
                      num(at(b.end, q)), num(at(c, p)), num(at(c, q)), rotation, num(at(b.end, n)),
                      num(at(b.end, 3)), num(at(b.end, 4)), num(at(b.end, 5)));
      break;
    }
    case BlockKind::kDwell:
      // The index wait before synchronised moves is below the canonical interface in LinuxCNC.
      if (!b.index_wait) out += fmt::format("DWELL({})\n", num(b.dwell_s));
      break;
    case BlockKind::kAux:
      break;
  }
  return out;
}

}  // namespace cncore::interp
