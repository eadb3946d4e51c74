// The execution-data buffer: a fixed-capacity ring of Segments (blocks and events in program
// order), allocated once. Items are addressed by a running 64-bit index; index % capacity is
// the item's slot, which also names its look-ahead points.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "planner/huge_pages.hpp"
#include "planner/segment.hpp"

namespace cncore::planner {

class SegmentBuffer {
 public:
  explicit SegmentBuffer(std::size_t capacity)
      : items_(capacity > 0 ? capacity : 1),
        end_mm_(items_.size(), 0.0),
        motion_(items_.size(), 0),
        cap_(items_.size()) {}

  std::size_t capacity() const { return items_.size(); }
  std::size_t size() const { return static_cast<std::size_t>(end_ - begin_); }
  bool empty() const { return end_ == begin_; }
  bool full() const { return size() == capacity(); }
  std::uint64_t begin_index() const { return begin_; }  // oldest item still held
  std::uint64_t end_index() const { return end_; }      // one past the newest
  // index % capacity. Every access of the motion cycle goes through here, so the items held
  // (begin ≤ index < begin + capacity) take the slot from the oldest item's slot without a
  // 64-bit division; other indices (retired or far ahead) fall back to the division.
  std::size_t slot(std::uint64_t index) const {
    const std::uint64_t off = index - begin_;  // wraps for index < begin_: slow path
    if (off < cap_) {
      const std::uint64_t s = begin_slot_ + off;
      return static_cast<std::size_t>(s >= cap_ ? s - cap_ : s);
    }
    return static_cast<std::size_t>(index % cap_);
  }

  // end_mm() of item `index` from the compact array seek() probes (the same double). Items are
  // contiguous along the path (the kernel starts each at the end of the one before), so this is
  // also s0_mm of item index + 1.
  double end_mm_of(std::uint64_t index) const { return end_mm_[slot(index)]; }
  // Whether item `index` is a motion item, from a compact array: the cycle's walk over the
  // items under the tool decides from here and end_mm_of() without loading a cold Segment.
  bool is_motion(std::uint64_t index) const { return motion_[slot(index)] != 0; }

  Segment& operator[](std::uint64_t index) { return items_[slot(index)]; }
  const Segment& operator[](std::uint64_t index) const { return items_[slot(index)]; }

  // Precondition: !full(). Returns the new item's index. An item's s0_mm and length_mm are
  // fixed once it is pushed (end_mm is kept in a compact array for seek()).
  std::uint64_t push(const Segment& s) {
    const std::size_t k = slot(end_);
    items_[k] = s;
    end_mm_[k] = s.end_mm();
    motion_[k] = s.kind == ItemKind::kMotion ? 1 : 0;
    return end_++;
  }
  void pop_front() {
    ++begin_;
    begin_slot_ = begin_slot_ + 1 == cap_ ? 0 : begin_slot_ + 1;
  }

  // The first item j in [from, end_index() − 1] with pos_mm < end_mm(j), or the last item when
  // there is none: where a walk "skip j while pos ≥ end_mm(j) and j has a successor" from `from`
  // stops (end_mm never decreases along the buffer: each item starts where the one before it
  // ends, so the answer is unique). `last` caps the result (an index ≥ from). Precondition:
  // from < end_index().
  //
  // Found over a compact array of the items' end positions by galloping from `hint` (a guess
  // of the answer; default from + 1) in whichever direction the answer lies, then bisection:
  // O(log d) probes for an answer d items from the hint. The motion cycle passes the last
  // cycle's skip as the hint (fine segments of even length and an even speed: d ≈ 0), so a cycle
  // crossing k tiny segments costs a few probes, not 2·log k mostly mispredicted ones.
  std::uint64_t seek(std::uint64_t from, double pos_mm, std::uint64_t last = UINT64_MAX,
                     std::uint64_t hint = 0) const {
    const std::uint64_t hi_max = last < end_ - 1 ? last : end_ - 1;
    if (from >= hi_max || pos_mm < end_mm_[slot(from)]) return from;
    // From here on: `lo` is skipped (pos ≥ end_mm(lo)); `hi` is where the walk stops or hi_max.
    std::uint64_t g = hint > from ? hint : from + 1;
    if (g > hi_max) g = hi_max;
    std::uint64_t lo = from, hi = g;
    std::uint64_t step = 1;
    if (g < hi_max && pos_mm >= end_mm_[slot(g)]) {
      // The answer is after g: gallop forward.
      lo = g;
      hi = hi_max - lo > step ? lo + step : hi_max;
      while (hi < hi_max && pos_mm >= end_mm_[slot(hi)]) {
        lo = hi;
        step *= 2;
        hi = hi_max - lo > step ? lo + step : hi_max;
      }
    } else {
      // The answer is g or before it: gallop back towards from.
      while (hi - lo > 1) {
        const std::uint64_t probe = hi - lo > step ? hi - step : lo;
        if (probe == lo || pos_mm >= end_mm_[slot(probe)]) {
          lo = probe;
          break;
        }
        hi = probe;
        step *= 2;
      }
    }
    while (hi - lo > 1) {
      const std::uint64_t mid = lo + (hi - lo) / 2;
      if (pos_mm >= end_mm_[slot(mid)]) {
        lo = mid;
      } else {
        hi = mid;
      }
    }
    return hi;
  }

 private:
  // Allocated from huge pages (huge_pages.hpp): ~3.3 MB for a 10 000-block window.
  std::vector<Segment, HugePageAllocator<Segment>> items_;
  // end_mm() of every slot: seek() probes 8 bytes per item instead of a cold ~330-byte Segment.
  std::vector<double, HugePageAllocator<double>> end_mm_;
  std::vector<std::uint8_t, HugePageAllocator<std::uint8_t>> motion_;  // kind == kMotion
  std::uint64_t cap_;
  std::uint64_t begin_ = 0, end_ = 0;
  std::uint64_t begin_slot_ = 0;  // begin_ % cap_
};

}  // namespace cncore::planner
