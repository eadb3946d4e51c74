// The source line of the programmed piece under the tool on a merged line
// (planner/line_merge.hpp): the kernel plans the merged line as one segment, but each sample
// names the piece the tool is on, as the program was written.
//
// The pieces arrive after their line (Kernel::push); each is kept as the path position where it
// ends, the projection of its end onto the line: s_end = s0 + clamp((P − P0)·u, 0, L) (the line
// starts at path position s0 at P0 and runs along the unit vector u for L mm). The pieces lie
// within the merge tolerance of the line, in order along it, so these positions increase.
// The ring is allocated once (kCapacity pieces); the kernel takes no block while it is full, so
// it holds the pieces of the lines in its buffer, whatever the program's length. Real-time:
// line_at() costs O(log k) for a cycle that passes k pieces (a galloping search), no allocation.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "core/block.hpp"

namespace cncore::motion {

class PieceLines {
 public:
  // 2^18 pieces (6 MB, touched only as far as programs fill it): the pieces of a few thousand
  // merged lines of a refined program, more than the look-ahead needs to plan at top speed.
  static constexpr std::size_t kCapacity = std::size_t{1} << 18;

  // capacity 0: no merged lines come (merge off).
  explicit PieceLines(std::size_t capacity)
      : cap_(capacity),
        ring_(std::make_unique_for_overwrite<Entry[]>(std::max<std::size_t>(capacity, 1))) {}

  bool full() const { return size_ >= cap_ && cap_ > 0; }

  // A merged line (Block::pieces > 0) was pushed as buffer item `item`, starting at path
  // position s0_mm.
  void on_line(const Block& line, std::uint64_t item, double s0_mm) {
    item_ = item;
    s0_mm_ = s0_mm;
    p0_ = line.start.xyz();
    const Vec3 d = line.end.xyz() - p0_;
    length_mm_ = norm(d);
    u_ = length_mm_ > 0 ? (1 / length_mm_) * d : Vec3{};
    left_ = line.pieces;
  }

  // One of its pieces (Block::piece), in order. Precondition: !full().
  void on_piece(const Block& piece) {
    if (left_ == 0 || cap_ == 0) return;  // a piece without its line: nothing to attribute
    --left_;
    // The last piece ends where the line ends, exactly.
    const double along =
        left_ == 0 ? length_mm_ : std::clamp(dot(piece.end.xyz() - p0_, u_), 0.0, length_mm_);
    ring_[wrap(head_ + size_)] = {s0_mm_ + along, item_, piece.line};
    ++size_;
  }

  // The line of the piece under the tool at path position tool_mm on buffer item `item`
  // (fallback: the item's own line). Pieces the tool has passed are dropped.
  std::uint32_t line_at(std::uint64_t item, double tool_mm, std::uint32_t fallback) {
    if (size_ == 0) return fallback;
    // The first piece that ends at or after the tool: gallop (1, 2, 4 … ahead), then bisect.
    if (ring_[head_].end_mm < tool_mm) {
      std::size_t lo = 0, step = 1;  // ring_[lo] ends before the tool
      while (lo + step < size_ && at(lo + step).end_mm < tool_mm) {
        lo += step;
        step *= 2;
      }
      std::size_t hi = std::min(lo + step, size_);  // ends at or after the tool (or size_)
      while (hi - lo > 1) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (at(mid).end_mm < tool_mm) {
          lo = mid;
        } else {
          hi = mid;
        }
      }
      head_ = wrap(head_ + hi);
      size_ -= hi;
      if (size_ == 0) return fallback;
    }
    const Entry& e = ring_[head_];
    return e.item == item ? e.line : fallback;
  }

 private:
  struct Entry {
    double end_mm;       // path position where the piece ends
    std::uint64_t item;  // buffer item of its merged line
    std::uint32_t line;  // its source line
  };
  std::size_t wrap(std::size_t i) const { return i >= cap_ ? i - cap_ : i; }
  const Entry& at(std::size_t k) const { return ring_[wrap(head_ + k)]; }

  std::size_t cap_;
  std::unique_ptr<Entry[]> ring_;
  std::size_t head_ = 0, size_ = 0;
  // The merged line whose pieces are coming.
  std::uint64_t item_ = 0;
  double s0_mm_ = 0, length_mm_ = 0;
  Vec3 p0_, u_;
  std::uint32_t left_ = 0;
};

}  // namespace cncore::motion
