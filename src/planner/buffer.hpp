// The execution-data buffer: a fixed-capacity ring of Segments (blocks and events in program
// order), allocated once. Items are addressed by a running 64-bit index; index % capacity is
// the item's slot, which also names its look-ahead points.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "planner/segment.hpp"

namespace cncore::planner {

class SegmentBuffer {
 public:
  explicit SegmentBuffer(std::size_t capacity) : items_(capacity > 0 ? capacity : 1) {}

  std::size_t capacity() const { return items_.size(); }
  std::size_t size() const { return static_cast<std::size_t>(end_ - begin_); }
  bool empty() const { return end_ == begin_; }
  bool full() const { return size() == capacity(); }
  std::uint64_t begin_index() const { return begin_; }  // oldest item still held
  std::uint64_t end_index() const { return end_; }      // one past the newest
  std::size_t slot(std::uint64_t index) const {
    return static_cast<std::size_t>(index % items_.size());
  }

  Segment& operator[](std::uint64_t index) { return items_[slot(index)]; }
  const Segment& operator[](std::uint64_t index) const { return items_[slot(index)]; }

  // Precondition: !full(). Returns the new item's index.
  std::uint64_t push(const Segment& s) {
    items_[slot(end_)] = s;
    return end_++;
  }
  void pop_front() { ++begin_; }

 private:
  std::vector<Segment> items_;
  std::uint64_t begin_ = 0, end_ = 0;
};

}  // namespace cncore::planner
