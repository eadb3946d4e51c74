#include "planner/line_merge.hpp"

#include <cmath>

namespace cncore::planner {
namespace {

bool mergeable_kind(const Block& b) {
  if (b.kind != BlockKind::kLine && b.kind != BlockKind::kRapid) return false;
  for (std::size_t i = kA; i < kMaxAxes; ++i) {
    if (b.end[i] != b.start[i]) return false;
  }
  return b.end.xyz() != b.start.xyz();
}

Vec3 unit_direction(const Block& b) {
  const Vec3 d = b.end.xyz() - b.start.xyz();
  return (1 / norm(d)) * d;
}

bool same_value(double a, double b) {
  return a == b || (std::isnan(a) && std::isnan(b));
}

}  // namespace

bool LineMerger::extends(const Block& b) const {
  const Block& a = line_;
  if (a.path_mode != PathMode::kBlend || vertices_ == kMaxPieces) return false;
  if (b.kind != a.kind || b.feed_mm_min != a.feed_mm_min || b.tolerance_mm != a.tolerance_mm ||
      !same_value(b.correction, a.correction) || b.override_fixed != a.override_fixed) {
    return false;
  }
  if (b.start != a.end) return false;
  const Vec3 piece = b.end.xyz() - b.start.xyz();
  if (dot(last_dir_, piece) < min_cos_ * norm(piece)) return false;  // turns by more
  // The chord from the line's start to b's end, and every inner vertex (b's start the last).
  const Vec3 p0 = a.start.xyz();
  const Vec3 chord = b.end.xyz() - p0;
  const double len = norm(chord);
  if (!(len > 0)) return false;
  const Vec3 u = (1 / len) * chord;
  const double tol2 = tolerance_mm_ * tolerance_mm_;
  double t_prev = 0;
  auto inside = [&](const Vec3& v) {
    const Vec3 d = v - p0;
    const double t = dot(d, u);
    // |d|² − t² is the squared distance to the chord's line (cancellation: ≥ 0 up to rounding).
    if (!(t > t_prev && t < len) || dot(d, d) - t * t > tol2) return false;
    t_prev = t;
    return true;
  };
  for (std::size_t i = 0; i < vertices_; ++i) {
    if (!inside(vertex_[i])) return false;
  }
  return inside(a.end.xyz());
}

void LineMerger::emit(const Block& b) {
  out_[(out_head_ + out_size_) % out_.size()] = b;
  ++out_size_;
}

void LineMerger::put(const Block& block) {
  if (tolerance_mm_ <= 0) {
    emit(block);
    return;
  }
  if (pending_ && extends(block)) {
    vertex_[vertices_++] = line_.end.xyz();
    last_dir_ = unit_direction(block);
    line_.end = block.end;
    line_.path_mode = block.path_mode;
    return;
  }
  finish();
  if (mergeable_kind(block)) {
    line_ = block;
    last_dir_ = unit_direction(block);
    vertices_ = 0;
    pending_ = true;
  } else {
    emit(block);
  }
}

void LineMerger::finish() {
  if (!pending_) return;
  emit(line_);
  pending_ = false;
}

bool LineMerger::next(Block& out) {
  if (out_size_ == 0) return false;
  out = out_[out_head_];
  out_head_ = (out_head_ + 1) % out_.size();
  --out_size_;
  return true;
}

}  // namespace cncore::planner
