// A first-in first-out queue in one ring that grows by doubling and never shrinks: once it has
// reached the largest size a run needs, pushing and popping allocate nothing (std::deque
// allocates a node and frees another every few dozen elements, each a malloc call per block
// of the program for the summary's queue of pending blocks).
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace cncore::io {

template <typename T>
class GrowingFifo {
 public:
  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  T& front() { return ring_[head_]; }
  const T& front() const { return ring_[head_]; }
  T& back() { return (*this)[size_ - 1]; }
  // The i-th element from the front (i < size()).
  T& operator[](std::size_t i) { return ring_[(head_ + i) & mask_]; }
  const T& operator[](std::size_t i) const { return ring_[(head_ + i) & mask_]; }

  void push_back(T value) {
    if (size_ == ring_.size()) grow();
    ring_[(head_ + size_) & mask_] = std::move(value);
    ++size_;
  }
  void pop_front() { drop_front(1); }
  // Removes the first n elements (n ≤ size()).
  void drop_front(std::size_t n) {
    head_ = (head_ + n) & mask_;
    size_ -= n;
  }

 private:
  void grow() {
    std::vector<T> bigger(ring_.empty() ? kFirst : 2 * ring_.size());
    for (std::size_t i = 0; i < size_; ++i) bigger[i] = std::move((*this)[i]);
    ring_ = std::move(bigger);
    head_ = 0;
    mask_ = ring_.size() - 1;
  }

  static constexpr std::size_t kFirst = 64;  // a power of two, as every later size
  std::vector<T> ring_;
  std::size_t head_ = 0, size_ = 0, mask_ = 0;
};

}  // namespace cncore::io
