// A fixed-capacity lock-free single-producer / single-consumer ring (the block producer
// thread hands blocks to the motion cycle). One thread calls only try_push, one other thread only
// try_pop; both are wait-free and never allocate (the slots are allocated and constructed once,
// in the constructor). Blocking waits belong to the caller (see simulation/run.cpp).
//
// head_ (next slot to read) is written only by the consumer, tail_ (next slot to write) only by
// the producer; both count up forever (64 bits: no wrap in practice) and a slot is
// index & (capacity − 1). The producer publishes a slot with a release store of tail_ after
// writing it, the consumer acquires tail_ before reading it; symmetrically the consumer frees a
// slot with a release store of head_ after moving out of it. Each side keeps a cached copy of the
// other's index and reloads it only when the ring looks full (producer) or empty (consumer), so
// a transfer normally touches one shared cache line. The two indices live on separate cache
// lines, so the sides do not invalidate each other's line on every operation (false sharing).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <stdexcept>
#include <utility>

namespace cncore {

template <typename T>
class SpscRing {
 public:
  // capacity: a power of two ≥ 2 (index → slot is a mask).
  explicit SpscRing(std::size_t capacity) : capacity_(capacity), mask_(capacity - 1) {
    if (capacity < 2 || (capacity & (capacity - 1)) != 0) {
      throw std::invalid_argument("SpscRing: capacity must be a power of two >= 2");
    }
    slots_ = std::make_unique<T[]>(capacity);
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  std::size_t capacity() const { return capacity_; }

  // Producer only. Copies (or moves) `value` into the ring; false when it is full.
  template <typename U>
  bool try_push(U&& value) {
    const std::uint64_t tail = tail_.value.load(std::memory_order_relaxed);
    if (tail - head_cache_ >= capacity_) {
      head_cache_ = head_.value.load(std::memory_order_acquire);
      if (tail - head_cache_ >= capacity_) return false;
    }
    slots_[tail & mask_] = std::forward<U>(value);
    tail_.value.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Consumer only. Moves the oldest element into `out`; false when the ring is empty.
  bool try_pop(T& out) {
    const std::uint64_t head = head_.value.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.value.load(std::memory_order_acquire);
      if (head == tail_cache_) return false;
    }
    out = std::move(slots_[head & mask_]);
    head_.value.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer only: the oldest element, or nullptr when empty. It stays in the ring (and may be
  // modified in place) until pop().
  T* front() {
    const std::uint64_t head = head_.value.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.value.load(std::memory_order_acquire);
      if (head == tail_cache_) return nullptr;
    }
    return &slots_[head & mask_];
  }
  // Consumer only; precondition: front() != nullptr.
  void pop() {
    head_.value.store(head_.value.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  // Consumer only: starts moving the element after front() into this core's cache, if the
  // producer has published it (never a slot it may still be writing).
  void prefetch_next() const {
    const std::uint64_t next = head_.value.load(std::memory_order_relaxed) + 1;
    if (next >= tail_cache_) return;
    const char* p = reinterpret_cast<const char*>(&slots_[next & mask_]);
    for (std::size_t off = 0; off < sizeof(T); off += kCacheLine) __builtin_prefetch(p + off);
  }

  // Either side: the number of elements (exact for the calling side's own operations, a
  // snapshot of the other side's).
  std::size_t size() const {
    const std::uint64_t head = head_.value.load(std::memory_order_acquire);
    const std::uint64_t tail = tail_.value.load(std::memory_order_acquire);
    return static_cast<std::size_t>(tail - head);
  }

  // For blocking waits outside the ring (std::atomic::wait/notify on an index).
  const std::atomic<std::uint64_t>& head_index() const { return head_.value; }
  std::atomic<std::uint64_t>& head_index() { return head_.value; }
  const std::atomic<std::uint64_t>& tail_index() const { return tail_.value; }
  std::atomic<std::uint64_t>& tail_index() { return tail_.value; }

 private:
  // 64 bytes on the x86-64 and AArch64 targets (std::hardware_destructive_interference_size
  // warns under gcc 12 -Winterference-size, as its value may differ between compiler flags).
  static constexpr std::size_t kCacheLine = 64;
  struct alignas(kCacheLine) Index {
    std::atomic<std::uint64_t> value{0};
  };

  Index head_;                                        // consumer's
  alignas(kCacheLine) std::uint64_t tail_cache_ = 0;  // consumer's copy of tail_
  Index tail_;                                        // producer's
  alignas(kCacheLine) std::uint64_t head_cache_ = 0;  // producer's copy of head_
  alignas(kCacheLine) std::size_t capacity_;
  std::size_t mask_;
  std::unique_ptr<T[]> slots_;
};

}  // namespace cncore
