// LinuxCNC's canonical-machine calls for blocks (`cncore check --canon`), so that a listing
// compares line by line with `rs274 -g`: positions in program units with the tool length
// offset taken off (LinuxCNC applies it below the canonical interface), 4 decimals, arcs in
// their plane's axis order.
#include <fmt/format.h>

#include "interpreter/interpreter.hpp"

namespace cncore::interp {

namespace {

std::string num(double v) {
  std::string s = fmt::format("{:.4f}", v);
  if (s == "-0.0000") s = "0.0000";
  return s;
}

}  // namespace

std::string CanonPrinter::print(const Block& b, const CanonFrame& f) {
  auto at = [&](const AxisVec& p, std::size_t a) {
    const double v = p[a] - f.tool_offset_mm[a];
    return a < 3 ? v / f.unit_mm : v;
  };
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
  switch (b.kind) {
    case BlockKind::kRapid:
      out += fmt::format("STRAIGHT_TRAVERSE({})\n", axes(b.end));
      break;
    case BlockKind::kLine:
      feed();
      out += fmt::format("STRAIGHT_FEED({})\n", axes(b.end));
      break;
    case BlockKind::kArc: {
      feed();
      // The plane from the normal: G17 (X, Y; axis Z), G18 (Z, X; axis Y), G19 (Y, Z; axis X).
      std::size_t p = 0, q = 1, n = 2;
      double turn = b.normal.z;
      if (b.normal.y != 0) {
        p = 2, q = 0, n = 1;
        turn = b.normal.y;
      } else if (b.normal.x != 0) {
        p = 1, q = 2, n = 0;
        turn = b.normal.x;
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
      out += fmt::format("DWELL({})\n", num(b.dwell_s));
      break;
    case BlockKind::kAux:
      break;
  }
  return out;
}

}  // namespace cncore::interp
