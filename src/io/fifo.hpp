// A first-in first-out queue in one ring, allocated once for the largest size the caller
// expects and grown (doubled) only if that is exceeded: pushing and popping allocate nothing
// (std::deque allocates a node and frees another every few dozen elements, a malloc call per
// block of the program for the summary's queue of pending blocks). The ring is not initialised
// (for trivial T): its pages are first touched as the queue fills them, no more memory than a
// deque of the same length touches (on this VM the first touch of a 4 KB page costs ~30 µs).
#pragma once

#include <cstddef>
#include <memory>
#include <utility>

namespace cncore::io {

template <typename T>
class GrowingFifo {
 public:
  explicit GrowingFifo(std::size_t capacity = 64)
      : cap_(capacity > 0 ? capacity : 1), ring_(std::make_unique_for_overwrite<T[]>(cap_)) {}

  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  T& front() { return ring_[head_]; }
  const T& front() const { return ring_[head_]; }
  T& back() { return (*this)[size_ - 1]; }
  // The i-th element from the front (i < size()).
  T& operator[](std::size_t i) { return ring_[wrap(head_ + i)]; }
  const T& operator[](std::size_t i) const { return ring_[wrap(head_ + i)]; }

  void push_back(T value) {
    if (size_ == cap_) grow();
    ring_[wrap(head_ + size_)] = std::move(value);
    ++size_;
  }
  void pop_front() { drop_front(1); }
  // Removes the first n elements (n ≤ size()).
  void drop_front(std::size_t n) {
    head_ = wrap(head_ + n);
    size_ -= n;
  }

 private:
  // i < 2·cap_: the ring index by compare, not `%`.
  std::size_t wrap(std::size_t i) const { return i >= cap_ ? i - cap_ : i; }

  void grow() {
    auto bigger = std::make_unique_for_overwrite<T[]>(2 * cap_);
    for (std::size_t i = 0; i < size_; ++i) bigger[i] = std::move((*this)[i]);
    ring_ = std::move(bigger);
    cap_ *= 2;
    head_ = 0;
  }

  std::size_t cap_;
  std::unique_ptr<T[]> ring_;
  std::size_t head_ = 0, size_ = 0;
};

}  // namespace cncore::io
