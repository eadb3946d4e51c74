#include "feedcontrol/direction_correction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "config/correction_law.hpp"
#include "core/error.hpp"
#include "planner/segment.hpp"

namespace cncore::feed {

namespace {

bool is_feed_move(const Block& b) {
  return b.kind == BlockKind::kLine || b.kind == BlockKind::kArc;
}

// Unit tangent of the arc/helix of `s` at angle phi from its start (see Segment: H(φ) =
// centre + r(φ)(cos φ·e1 + sin φ·e2) + rise·(φ/Φ)·n, r linear in φ).
Vec3 arc_tangent(const planner::Segment& s, double phi) {
  const double f = phi / s.sweep_rad;
  const double r = s.r0 + (s.r1 - s.r0) * f;
  const double dr = (s.r1 - s.r0) / s.sweep_rad;
  const double c = std::cos(phi), sn = std::sin(phi);
  const Vec3 d =
      (r * -sn + dr * c) * s.e1 + (r * c + dr * sn) * s.e2 + (s.rise_mm / s.sweep_rad) * s.n;
  const double len = norm(d);
  return len > 0 ? (1 / len) * d : Vec3{};
}

}  // namespace

struct DirectionCorrector::Impl {
  Impl(const MachineConfig& m, std::string path)
      : program(std::move(path)),
        cfg(m.direction_correction),
        lim(planner::make_limits(m, m.bound_resultant_accel)),
        uphill(cfg.uphill),
        downhill(cfg.downhill),
        on(cfg.enabled && cfg.active_at_start) {}

  std::string program;
  DirectionCorrectionConfig cfg;
  planner::Limits lim;
  CorrectionEvaluator uphill, downhill;
  bool on;

  // The block being handed out: a single block (pieces = 1) or an arc split into sub-arcs.
  Block current;
  bool pending = false;
  std::uint32_t pieces = 0, next_piece = 0;
  planner::Segment arc;  // geometry of the split arc
  AxisVec piece_start;
};

DirectionCorrector::DirectionCorrector(const MachineConfig& machine,
                                       const std::string& program_path)
    : impl_(std::make_unique<Impl>(machine, program_path)) {}
DirectionCorrector::~DirectionCorrector() = default;

bool DirectionCorrector::enabled() const {
  return impl_->cfg.enabled;
}
bool DirectionCorrector::active() const {
  return impl_->on;
}

double DirectionCorrector::ratio(const Vec3& d) const {
  return std::clamp(dot(d, impl_->cfg.direction), -1.0, 1.0);
}

double DirectionCorrector::coefficient(const Vec3& d, double feed_mm_min,
                                       const Block& where) const {
  const double fi = ratio(d);
  // The seed: ΔZs ≥ 0 (uphill, FI ≥ 0) uses the uphill formula, ΔZs < 0 the downhill one.
  const bool up = fi >= 0;
  double c = 0;
  try {
    c = (up ? impl_->uphill : impl_->downhill)(fi, feed_mm_min, impl_->cfg.tool_diameter_mm);
  } catch (const CorrectionLawError&) {
    c = std::nan("");  // reported below with the FI
  }
  if (!std::isfinite(c) || c <= 0) {
    throw InputError(
        impl_->program, where.line, where.col,
        fmt::format("direction correction: the {} law gives C = {} at FI = {:.6g} (F = {} mm/min, "
                    "D = {} mm): the coefficient must be finite and > 0",
                    up ? "uphill" : "downhill",
                    std::isnan(c) ? std::string("NaN") : fmt::format("{}", c), fi, feed_mm_min,
                    impl_->cfg.tool_diameter_mm));
  }
  return c;
}

void DirectionCorrector::put(const Block& b) {
  Impl& m = *impl_;
  m.current = b;
  m.pending = true;
  m.pieces = 1;
  m.next_piece = 0;
  if (!m.cfg.enabled) return;  // pass through untouched (NaN correction)
  if (b.kind == BlockKind::kAux && b.aux_letter == 'M') {
    if (b.aux_value == kCorrectionOnM) m.on = true;
    if (b.aux_value == kCorrectionOffM) m.on = false;
  }
  if (b.kind == BlockKind::kRapid) m.current.correction = 1;
  if (!is_feed_move(b) || !m.on) {
    if (is_feed_move(b)) m.current.correction = 1;
    return;
  }
  if (b.kind == BlockKind::kArc) {
    m.arc = planner::make_motion_segment(b, m.lim);
    if (m.arc.arc && m.arc.length_mm > 0) {
      // FI varies along the arc when u has a component in the arc's plane, or on a helix whose
      // radius changes (the tangent's slope then changes).
      const Vec3 u = m.cfg.direction;
      const Vec3 in_plane = u - dot(u, m.arc.n) * m.arc.n;
      const bool varies = norm(in_plane) > 1e-12 || (m.arc.rise_mm != 0 && m.arc.r0 != m.arc.r1);
      const double step = m.cfg.arc_step_deg * std::numbers::pi / 180;
      if (varies) {
        m.pieces = static_cast<std::uint32_t>(
            std::clamp(std::ceil(m.arc.sweep_rad / step - 1e-9), 1.0, 4.0e9));
      }
      m.piece_start = b.start;
    }
  }
}

bool DirectionCorrector::next(Block& out) {
  Impl& m = *impl_;
  if (!m.pending) return false;
  const Block& b = m.current;
  // A move that follows the spindle has its feed from the spindle: not corrected.
  if (!m.cfg.enabled || !m.on || !is_feed_move(b) || !std::isnan(b.correction) ||
      b.sync_mm_rev > 0) {
    out = b;
    m.pending = false;
    return true;
  }
  if (b.kind == BlockKind::kLine || !m.arc.arc || m.arc.length_mm <= 0) {
    out = b;
    const Vec3 d = b.end.xyz() - b.start.xyz();
    const double len = norm(d);
    // Moves of rotary axes only have no direction in space: not corrected.
    const double c = len > 1e-12 ? coefficient((1 / len) * d, b.feed_mm_min, b) : 1.0;
    out.correction = c;
    out.feed_mm_min = b.feed_mm_min * c;
    out.override_fixed = m.cfg.override_mode == CorrectionOverrideMode::kReplace;
    m.pending = false;
  } else {
    // Sub-arc k of N: from φ_k to φ_k+1 = (k+1)/N·Φ, C from the tangent at the middle.
    const std::uint32_t k = m.next_piece;
    const bool last = k + 1 == m.pieces;
    const double n = m.pieces;
    out = b;
    out.start = m.piece_start;
    out.end = last ? b.end : m.arc.point_at((k + 1) / n * m.arc.length_mm);
    out.turns = 0;
    if (!last && b.path_mode == PathMode::kExactStop) out.path_mode = PathMode::kExactPath;
    if (m.pieces == 1) out.turns = b.turns;
    const double phi_mid = (k + 0.5) / n * m.arc.sweep_rad;
    const double c = coefficient(arc_tangent(m.arc, phi_mid), b.feed_mm_min, b);
    out.correction = c;
    out.feed_mm_min = b.feed_mm_min * c;
    out.override_fixed = m.cfg.override_mode == CorrectionOverrideMode::kReplace;
    m.piece_start = out.end;
    m.next_piece = k + 1;
    if (last) m.pending = false;
  }
  return true;
}

}  // namespace cncore::feed
