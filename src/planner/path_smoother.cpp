#include "planner/path_smoother.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace cncore::planner {
namespace {

constexpr double kSameRate = 1 + 1e-3;

// A G1 that moves X Y Z only, by a nonzero distance.
bool smoothable_kind(const Block& b) {
  if (b.kind != BlockKind::kLine) return false;
  for (std::size_t i = kA; i < kMaxAxes; ++i) {
    if (b.end[i] != b.start[i]) return false;
  }
  return b.end.xyz() != b.start.xyz();
}

// The unit direction of a straight move in X Y Z (zero for anything else).
Vec3 line_direction(const Block& b) {
  if (b.kind != BlockKind::kLine && b.kind != BlockKind::kRapid) return {};
  const Vec3 d = b.end.xyz() - b.start.xyz();
  const double n = norm(d);
  return n > 0 ? (1 / n) * d : Vec3{};
}

}  // namespace

PathSmoother::PathSmoother(const SmoothingSettings& settings)
    : settings_(settings),
      cos_corner_(std::cos(settings.corner_deg * std::numbers::pi / 180)),
      cos_free_turn_(std::cos(settings.free_turn_rad)) {
  run_.reserve(kMaxChords);
  points_.reserve(kMaxChords + 1);
  out_.reserve(kMaxChords + 2);
}

double PathSmoother::tolerance_of(const Block& b) const {
  if (!smoothable_kind(b)) return 0;
  const double q = b.smooth_tolerance_mm < 0 ? settings_.tolerance_mm : b.smooth_tolerance_mm;
  const double p = b.tolerance_mm < 0 ? settings_.contour_tolerance_mm : b.tolerance_mm;
  return std::max(0.0, std::min(q, p) - settings_.reserve_mm);
}

bool PathSmoother::joins(const Block& b, double tol) const {
  const Block& a = run_.back();
  if (a.path_mode != PathMode::kBlend || tol != run_tol_ || b.start != a.end) return false;
  if (b.tolerance_mm != a.tolerance_mm || b.override_fixed != a.override_fixed ||
      std::isnan(b.correction) != std::isnan(a.correction)) {
    return false;
  }
  const double lo = std::min(feed_lo_mm_min_, b.feed_mm_min);
  if (std::max(feed_hi_mm_min_, b.feed_mm_min) > kSameRate * lo) return false;
  // A real corner: a turn above the corner angle between chords both longer than the tolerance.
  const Vec3 da = a.end.xyz() - a.start.xyz();
  const Vec3 db = b.end.xyz() - b.start.xyz();
  const double la = norm(da), lb = norm(db);
  return std::min(la, lb) <= tol || dot(da, db) >= cos_corner_ * la * lb;
}

void PathSmoother::put(const Block& block) {
  const double tol = tolerance_of(block);
  if (!run_.empty() && tol > 0 && joins(block, tol)) {
    run_.push_back(block);
    points_.push_back(block.end.xyz());
    feed_lo_mm_min_ = std::min(feed_lo_mm_min_, block.feed_mm_min);
    feed_hi_mm_min_ = std::max(feed_hi_mm_min_, block.feed_mm_min);
    ++chords_in_;
    if (run_.size() == kMaxChords) emit_front();
    return;
  }
  // The move after the run, if it starts where the run ends (the run's last joint).
  if (!run_.empty()) {
    out_dir_ = block.start == run_.back().end ? line_direction(block) : Vec3{};
  }
  finish();
  out_dir_ = Vec3{};
  if (tol > 0) {
    in_dir_ = chord_in_dir_ = block.start == exit_pos_ ? exit_dir_ : Vec3{};
    continued_ = false;
    run_.push_back(block);
    points_.push_back(block.start.xyz());
    points_.push_back(block.end.xyz());
    run_tol_ = tol;
    feed_lo_mm_min_ = feed_hi_mm_min_ = block.feed_mm_min;
    ++chords_in_;
  } else {
    emit(block);
    set_exit(block, line_direction(block));
  }
}

void PathSmoother::set_exit(const Block& b, const Vec3& dir) {
  exit_pos_ = b.end;
  exit_dir_ = is_motion(b) ? dir : Vec3{};
}

bool PathSmoother::keeps_joints(std::size_t chords, const CurveFit& fit) const {
  Vec3 t0, tn;
  fit.end_tangents(points_[0], points_[chords], t0, tn);
  const Vec3 first = line_direction(run_[0]), last = line_direction(run_[chords - 1]);
  // Turns compared by their cosines (unit vectors; a larger cosine is a smaller turn).
  constexpr double kSlack = 1e-12;
  // The joint before: the block handed out before it (in_dir_) against the curve's start turns
  // no more than the chords did there (chord_in_dir_ against the first chord), or the free turn.
  if (dot(in_dir_, in_dir_) > 0 &&
      dot(in_dir_, t0) < std::min(dot(chord_in_dir_, first), cos_free_turn_) - kSlack) {
    return false;
  }
  // The joint after, where the run goes on at least a span L = 50·tolerance past it in 4 chords
  // or more: the curve ends along the data's own direction there, the chord between the
  // vertices a span before and after it (a circle's chord is parallel to its tangent at the
  // middle), within the free turn or half the data's turn over the two spans (how far a smooth
  // curve's tangent can be from that chord). A curve that reaches past an inflection of the
  // data by x ends off it by ~2x/R, where the data does not turn: a kink the next curve cannot
  // remove.
  const double span = 50 * run_tol_;
  const Vec3 pn = points_[chords];
  std::size_t ahead = chords + 1, behind = chords;
  while (ahead < points_.size() && norm(points_[ahead] - pn) < span) ++ahead;
  while (behind > 0 && norm(points_[behind] - pn) < span) --behind;
  if (ahead < points_.size() && ahead >= chords + 4) {
    const Vec3 back = pn - points_[behind], fwd = points_[ahead] - pn;
    const double data_turn =
        std::acos(std::clamp(dot(back, fwd) / (norm(back) * norm(fwd)), -1.0, 1.0));
    const Vec3 d = points_[ahead] - points_[behind];
    const double cos_allowed = std::min(cos_free_turn_, std::cos(0.5 * data_turn));
    return dot(tn, d) >= cos_allowed * norm(d) - kSlack;
  }
  // Else the next chord against the curve's end turns no more than the chords did there, or the
  // free turn, or the curve's own end against its last chord.
  const Vec3 next = chords < run_.size() ? line_direction(run_[chords]) : out_dir_;
  if (dot(next, next) == 0) return true;
  const double allowed = std::min({dot(last, next), cos_free_turn_, dot(last, tn)});
  return dot(tn, next) >= allowed - kSlack;
}

void PathSmoother::finish() {
  while (!run_.empty()) emit_front();
  points_.clear();
}

bool PathSmoother::next(Block& out) {
  if (out_head_ == out_.size()) {
    out_.clear();
    out_head_ = 0;
    return false;
  }
  out = out_[out_head_++];
  return true;
}

void PathSmoother::emit(const Block& b) {
  out_.push_back(b);
}

std::size_t PathSmoother::longest_fit(bool tangent, CurveFit& best_fit) const {
  const std::size_t k = run_.size();
  const CurveFitLimits limits{run_tol_, std::numbers::pi, 1e4};
  auto fits = [&](std::size_t m, CurveFit& f) {
    const std::span<const Vec3> p(points_.data(), m + 1);
    return (tangent ? fit_tangent_curve(p, in_dir_, limits, f) : fit_curve(p, limits, f)) &&
           keeps_joints(m, f);
  };
  // The longest prefix of m ≥ 2 chords one curve fits: try m = 2, 4, 8, … up to the whole run
  // (a short prefix of noisy chords may fit no curve where a longer one does), then bisect
  // between the longest fit and the first miss above it (the fit is checked whole at the
  // length taken).
  CurveFit f;
  std::size_t best = 1, miss = k + 1;
  for (std::size_t m = 2; m <= k; m = std::min(2 * m, k)) {
    if (fits(m, f)) {
      best = m;
      best_fit = f;
      miss = k + 1;
    } else if (miss > k) {
      miss = m;
    }
    if (m == k) break;
  }
  while (best > 1 && miss <= k && miss - best > 1) {
    const std::size_t mid = best + (miss - best) / 2;
    if (fits(mid, f)) {
      best = mid;
      best_fit = f;
    } else {
      miss = mid;
    }
  }
  return best;
}

void PathSmoother::emit_front() {
  // After a curve of this run, the next one leaves along its end tangent (no kink); where no
  // such curve fits, or at the run's first vertex (a corner, or the run's start), any curve
  // that keeps the joints.
  // The tangent arc is taken unless a curve with a joint twice as long fits: at an inflection
  // the arc through the last curve's end tangent straddles it and the arcs after it shrink.
  CurveFit best_fit, tangent_fit;
  std::size_t best = longest_fit(false, best_fit);
  if (continued_) {
    const std::size_t t = longest_fit(true, tangent_fit);
    if (t > 1 && t >= best) {
      best = t;
      best_fit = tangent_fit;
    }
  }
  // (best == 1: no curve fits; the first chord goes out as programmed.)
  const Block piece = make_piece(best, best > 1 ? &best_fit : nullptr);
  emit(piece);
  Vec3 t0, tn = line_direction(piece);
  if (best > 1) best_fit.end_tangents(points_[0], points_[best], t0, tn);
  set_exit(piece, tn);
  in_dir_ = tn;
  chord_in_dir_ = line_direction(run_[best - 1]);
  continued_ = best > 1;
  ++blocks_out_;
  if (best > 1) ++curves_out_;
  run_.erase(run_.begin(), run_.begin() + static_cast<std::ptrdiff_t>(best));
  points_.erase(points_.begin(), points_.begin() + static_cast<std::ptrdiff_t>(best));
  if (run_.empty()) points_.clear();
}

Block PathSmoother::make_piece(std::size_t chords, const CurveFit* fit) const {
  Block o = run_.front();
  if (fit == nullptr) return o;
  const Block& last = run_[chords - 1];
  o.end = last.end;
  o.path_mode = last.path_mode;
  o.last_line = last.last_line != 0 ? last.last_line : last.line;
  for (std::size_t i = 1; i < chords; ++i) {
    if (run_[i].feed_mm_min < o.feed_mm_min) {
      o.feed_mm_min = run_[i].feed_mm_min;
      o.correction = run_[i].correction;
    }
  }
  o.first_piece_dir = o.last_piece_dir = Vec3{};
  if (fit->kind == CurveFit::Kind::kArc) {
    o.kind = BlockKind::kArc;
    o.center = fit->center;
    o.normal = fit->normal;
    o.turns = 0;
  }
  return o;
}

}  // namespace cncore::planner
