#include "planner/line_merge.hpp"

#include <cmath>

namespace cncore::planner {
namespace {

constexpr double kSameRate = 1 + 1e-3;

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

}  // namespace

// x ≤ y, for x a sum of angles in [0, 3π/2] and y in [0, π/2]: x lies in [0, π/2] only if its
// cosine and sine are both ≥ 0, and then y − x is in [−π/2, π/2], where sin(y − x) ≥ 0 decides.
bool LineMerger::within(const Angle& x, const Angle& y) {
  return x.c >= 0 && x.s >= 0 && y.s * x.c - y.c * x.s >= 0;
}

bool LineMerger::extends(const Block& b, Cone& cone) const {
  const Block& a = line_;
  if (a.path_mode != PathMode::kBlend || pieces_ >= kMaxPiecesShort) return false;
  if (b.kind != a.kind || b.tolerance_mm != a.tolerance_mm ||
      b.override_fixed != a.override_fixed ||
      std::isnan(b.correction) != std::isnan(a.correction)) {
    return false;
  }
  // Feeds within kSameRate of each other (the direction correction's C differs by rounding
  // between the wobbling pieces of one line); the line runs at the lowest.
  const double lo = std::min(a.feed_mm_min, b.feed_mm_min);
  if (std::max(feed_hi_mm_min_, b.feed_mm_min) > kSameRate * lo) return false;
  if (b.start != a.end || !mergeable_kind(b)) return false;
  const Vec3 piece = b.end.xyz() - b.start.xyz();
  if (dot(last_dir_, piece) < min_cos_ * norm(piece)) return false;  // turns by more
  // The line's end becomes an inner vertex v at r = |v − P0| from its start P0: the line from
  // P0 along a direction e passes within δ of v when angle(e, v − P0) ≤ β = asin(δ/r). The
  // directions allowed by every inner vertex so far are kept as one cone inside their
  // intersection (O(1) per piece): on the great circle from the cone's axis to v the two caps
  // (half-angles α and β, axes γ apart) overlap in [γ − β, α], and the cap centred there (axis
  // turned by m = (γ − β + α)/2 towards v, half-angle h = (α + β − γ)/2) touches both
  // boundaries, so it lies inside both. Angles are kept as (cos, sin) pairs: sums by the
  // addition theorems, halves as in Angle::half(), and x ≤ y by sin(y − x) ≥ 0 (within()),
  // which stays exact at the µrad angles of long lines where comparing cosines would not, and
  // costs no trigonometric call (asin, atan2, cos, sin per piece were 24 % of the kernel's
  // push side on refined programs). After the first vertex α, β ≤ π/2.
  const Vec3 p0 = a.start.xyz();
  const Vec3 v = a.end.xyz() - p0;
  const double r = norm(v);  // (also the line's length so far)
  if (pieces_ >= kMaxPieces && r >= kShortLineMm) return false;
  if (!(r > cone_.r_mm)) return false;  // inner vertices ever farther from P0: in order
  cone = cone_;
  const Vec3 vu = (1 / r) * v;
  const Angle beta = r > tolerance_mm_ ? Angle::from_sin(tolerance_mm_ / r) : Angle{0, 1};
  if (cone.r_mm == 0) {  // the whole sphere: v's cap
    cone.axis = vu;
    cone.half = beta;
  } else {
    const Angle alpha = cone.half;
    const Angle gamma{dot(cone.axis, vu), norm(cross(cone.axis, vu))};
    if (within(gamma + beta, alpha)) {
      cone.axis = vu;  // v's cap inside the cone
      cone.half = beta;
    } else if (!within(gamma + alpha, beta)) {  // (else the cone is inside v's cap)
      // γ > |α − β| here, so x = α + β − γ < π, and once x > 0, 0 < y = γ + α − β < 2α ≤ π.
      const Angle x = (alpha + beta) - gamma;
      if (!(x.s > 0)) return false;  // h ≤ 0: no direction passes near every vertex
      const Angle m = ((gamma + alpha) - beta).half();
      const Vec3 w = vu - dot(vu, cone.axis) * cone.axis;  // towards v, ⟂ the axis
      const double wn = norm(w);
      if (wn > 0) cone.axis = m.c * cone.axis + (m.s / wn) * w;
      cone.half = x.half();
    }
  }
  cone.r_mm = r;
  // The new chord must lie in the cone (angle ≤ h ≤ π/2: cos ≥ 0 and sin(h − angle) ≥ 0) and
  // reach past the last inner vertex.
  const Vec3 chord = b.end.xyz() - p0;
  const double along = dot(cone.axis, chord);
  return norm(chord) > r && along >= 0 &&
         cone.half.s * along >= cone.half.c * norm(cross(cone.axis, chord));
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
  Cone cone;
  if (pending_ && extends(block, cone)) {
    cone_ = cone;
    ++pieces_;
    pieces_of_line_.push_back(Piece::of(block));
    feed_hi_mm_min_ = std::max(feed_hi_mm_min_, block.feed_mm_min);
    if (block.feed_mm_min < line_.feed_mm_min) {
      line_.feed_mm_min = block.feed_mm_min;
      line_.correction = block.correction;
    }
    last_dir_ = unit_direction(block);
    line_.last_piece_dir = last_dir_;
    line_.end = block.end;
    line_.path_mode = block.path_mode;
    line_.last_line = block.last_line != 0 ? block.last_line : block.line;
    return;
  }
  finish();
  if (mergeable_kind(block)) {
    line_ = block;
    last_dir_ = unit_direction(block);
    line_.first_piece_dir = last_dir_;  // (kept only if a piece joins, finish())
    cone_ = Cone{};
    pieces_ = 1;
    pieces_of_line_.clear();
    pieces_of_line_.push_back(Piece::of(block));
    feed_hi_mm_min_ = block.feed_mm_min;
    pending_ = true;
  } else {
    emit(block);
  }
}

void LineMerger::finish() {
  if (!pending_) return;
  pending_ = false;
  if (pieces_ == 1) {
    line_.first_piece_dir = line_.last_piece_dir = Vec3{};  // as programmed
    emit(line_);
    return;
  }
  line_.pieces = static_cast<std::uint32_t>(pieces_);
  emit(line_);
  // put() runs only once everything handed out before has been taken (the pieces of the
  // previous line too): the vectors swap, no copy.
  out_pieces_.swap(pieces_of_line_);
  out_piece_ = 0;
}

bool LineMerger::next(Block& out) {
  // A merged line's pieces right after it (it is at the head of out_ when finish() emits it).
  if (out_piece_ < out_pieces_.size() && out_line_.pieces > 0) {
    const Piece& p = out_pieces_[out_piece_];
    const Vec3 start = out_piece_ == 0 ? out_line_.start.xyz() : out_pieces_[out_piece_ - 1].end;
    out = out_line_;
    out.line = p.line;
    out.col = p.col;
    out.last_line = 0;
    out.pieces = 0;
    out.piece = true;
    out.first_piece_dir = out.last_piece_dir = Vec3{};
    out.start.set_xyz(start);
    out.end.set_xyz(p.end);
    out.feed_mm_min = p.feed_mm_min;
    out.correction = p.correction;
    out.path_mode = p.path_mode;
    if (++out_piece_ == out_pieces_.size()) out_line_.pieces = 0;
    return true;
  }
  if (out_size_ == 0) return false;
  out = out_[out_head_];
  out_head_ = (out_head_ + 1) % out_.size();
  --out_size_;
  if (out.pieces > 0) {
    out_line_ = out;
    out_piece_ = 0;
  }
  return true;
}

}  // namespace cncore::planner
