// G38.2–G38.5: a straight probing move against the simulated probe's solids ([probe] of the
// machine configuration, and the [stock] box). The trip point is where the tool tip's line first
// enters a solid (G38.2/.3) or leaves the last one (G38.4/.5); the move ends there and
// #5061…#5069 / #5070 hold the result, as in LinuxCNC.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "interpreter/interpreter_impl.hpp"

namespace cncore::interp {

namespace {

// The solids as boxes: the stock's (when it is one of them) and the configured ones.
std::vector<ProbeBox> probe_solids(const MachineConfig& m) {
  std::vector<ProbeBox> solids;
  const StockConfig& s = m.cutting.stock;
  if (m.probe.touch_stock && s.enabled) {
    ProbeBox stock{s.min_mm, s.min_mm};
    for (std::size_t i = 0; i < 3; ++i) stock.max_mm[i] += s.size_mm[i];
    solids.push_back(stock);
  }
  solids.insert(solids.end(), m.probe.boxes.begin(), m.probe.boxes.end());
  return solids;
}

bool inside(const ProbeBox& b, const Vec3& p) {
  constexpr double kEps = 1e-9;
  for (std::size_t i = 0; i < 3; ++i) {
    if (component(p, i) < b.min_mm[i] - kEps || component(p, i) > b.max_mm[i] + kEps) return false;
  }
  return true;
}

// The parameter interval [t0, t1] ⊂ [0, 1] of p(t) = a + t·(b − a) inside `box` (slab method:
// per axis lo ≤ a + t·d ≤ hi); empty when t0 > t1.
std::pair<double, double> clip(const ProbeBox& box, const Vec3& a, const Vec3& b) {
  double t0 = 0, t1 = 1;
  for (std::size_t i = 0; i < 3; ++i) {
    const double s = component(a, i), d = component(b, i) - s;
    const double lo = box.min_mm[i], hi = box.max_mm[i];
    if (std::abs(d) < 1e-15) {
      if (s < lo || s > hi) return {1, 0};
      continue;
    }
    double ta = (lo - s) / d, tb = (hi - s) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return {t0, t1};
}

// Toward (G38.2/.3): the first t at which the line is inside a solid; away (G38.4/.5): the first
// t at which it is inside none. Returns > 1 when that never happens on the move.
double trip_parameter(const std::vector<ProbeBox>& solids, const Vec3& a, const Vec3& b,
                      bool toward) {
  if (toward) {
    double best = 2;
    for (const ProbeBox& s : solids) {
      const auto [t0, t1] = clip(s, a, b);
      if (t0 <= t1) best = std::min(best, t0);
    }
    return best;
  }
  // Away: leave the solid holding the point, then any other the exit point is in, and so on.
  double t = 0;
  for (std::size_t guard = 0; guard <= solids.size(); ++guard) {
    const Vec3 p = a + t * (b - a);
    double exit = t;
    for (const ProbeBox& s : solids) {
      if (!inside(s, p)) continue;
      const auto [t0, t1] = clip(s, a, b);
      if (t0 <= t1) exit = std::max(exit, t1);
    }
    if (exit <= t + 1e-12) return t;  // inside none beyond its own faces
    if (exit >= 1) return 2;
    t = exit;
  }
  return t;
}

}  // namespace

void Interpreter::Impl::probe_motion(const AxisVec& target, std::uint32_t col) {
  const int code = modal_.probe_code;  // 382 … 385
  const bool toward = code == 382 || code == 383;
  const bool must_trip = code == 382 || code == 384;
  const std::string g = fmt::format("G38.{}", code - 380);
  if (modal_.feed_mode == FeedMode::kInverseTime) {
    fail(col, fmt::format("{} with inverse time feed G93: probe in G94", g));
  }
  double len2 = 0;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    const double d = target[a] - pos_[a];
    if (is_rotary(a) && std::abs(d) > kZeroMoveMm) {
      fail(col, fmt::format("{} moves a rotary axis: probe with X, Y and Z only", g));
    }
    len2 += d * d;
  }
  move_feed_mm_min_ = move_feed_mm_min(std::sqrt(len2), col);
  if (len2 < 0.254 * 0.254) {
    fail(col, fmt::format("{}: the target is within 0.254 mm of the start (LinuxCNC's minimum "
                          "probe move)",
                          g));
  }
  check_travel(target, target, target, col);
  const std::vector<ProbeBox> solids = probe_solids(machine_);
  // The tool tip: the controlled point less the tool length offset.
  const Vec3 a = (pos_ - tool_offset_).xyz();
  const Vec3 b = (target - tool_offset_).xyz();
  const bool in_contact =
      std::any_of(solids.begin(), solids.end(), [&](const ProbeBox& s) { return inside(s, a); });
  if (toward && in_contact) {
    fail(col, fmt::format("{}: the probe is already tripped at the start of the move", g));
  }
  if (!toward && !in_contact) {
    fail(col, fmt::format("{}: the probe is not tripped at the start of a move away from the "
                          "part",
                          g));
  }
  const double t = trip_parameter(solids, a, b, toward);
  const bool tripped = t <= 1;
  if (!tripped && must_trip) fail(col, fmt::format("{}: the move ended without contact", g));
  AxisVec end = target;
  if (tripped) {
    for (std::size_t i = 0; i < kMaxAxes; ++i) end[i] = pos_[i] + (target[i] - pos_[i]) * t;
  }
  if (norm((end - pos_).xyz()) > kZeroMoveMm) {
    emit_motion(BlockKind::kLine, end, col);
    // The machine stops at the trip point (no blending into the next move), as a probe does.
    out_.back().path_mode = PathMode::kExactStop;
    out_.back().tolerance_mm = -1;
  }
  pos_ = end;
  // #5061…#5069: the trip point (or the target) in the program's coordinates and units.
  const AxisVec p = to_program(end, tool_offset_);
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    const double unit = is_rotary(i) ? 1.0 : modal_.length_unit_mm();
    params_.set_numbered(kParamProbe + static_cast<int>(i), p[i] / unit);
  }
  params_.set_numbered(kParamProbeTripped, tripped ? 1 : 0);
}

}  // namespace cncore::interp
