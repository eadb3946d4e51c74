// A single-writer seqlock: the cycle thread publishes a value every cycle without waiting, any
// number of readers take consistent copies. The writer makes the sequence odd, stores the
// value, makes it even; a reader retries while the sequence is odd or changed under it. The
// value is kept as relaxed atomic words, so a reader racing the writer reads stale words, never
// undefined behaviour, and the sequence check throws such a copy away.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace cncore::runtime {

template <typename T>
class Seqlock {
  static_assert(std::is_trivially_copyable_v<T>);
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;

 public:
  // Writer only (one thread).
  void store(const T& value) {
    std::array<std::uint64_t, kWords> w{};
    std::memcpy(w.data(), &value, sizeof(T));
    const std::uint64_t s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(w[i], std::memory_order_relaxed);
    seq_.store(s + 2, std::memory_order_release);
  }

  // Any thread. Spins only while a store is in progress (a few hundred nanoseconds).
  T load() const {
    std::array<std::uint64_t, kWords> w{};
    while (true) {
      const std::uint64_t s0 = seq_.load(std::memory_order_acquire);
      if ((s0 & 1U) != 0) continue;
      for (std::size_t i = 0; i < kWords; ++i) w[i] = words_[i].load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == s0) break;
    }
    T value;
    std::memcpy(static_cast<void*>(&value), w.data(), sizeof(T));
    return value;
  }

 private:
  std::atomic<std::uint64_t> seq_{0};
  std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace cncore::runtime
