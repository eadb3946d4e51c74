// Memory for the motion kernel's fixed buffers (execution-data ring, look-ahead points, the
// min-trees): a few MB allocated and touched once, at construction.
//
// Why not plain operator new: on the machines we measure on (a VM), every first touch of a 4 KB
// page is a page fault costing ~30 µs, so a 10 000-block window (5–11 MB) took 40–80 ms to
// construct — more than the cycles of a whole `cncore run` of a 700 k-cycle program. Here the
// buffers are carved from 2 MB-aligned regions advised MADV_HUGEPAGE (Linux transparent huge
// pages), so the same touch is a handful of 2 MB faults (~0.5 ms for 8 MB). Where huge pages are
// not available the madvise is a no-op and the memory behaves as before.
//
// Every buffer is still allocated and touched at construction (nothing is faulted in later, in
// the cycle). Freed memory goes back to its region; an empty region is kept for the next kernel
// (tests and benchmarks construct many in a row) or unmapped when another is already kept.
// Thread-safe (construction and destruction only; never called in the motion cycle).
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>

namespace cncore::planner {

// At least `bytes` bytes, 64-byte aligned. Throws std::bad_alloc when the system has no memory.
void* huge_alloc(std::size_t bytes);
// Returns memory from huge_alloc (same size).
void huge_free(void* p, std::size_t bytes) noexcept;

// Totals since the process started (benchmarks: this memory bypasses a replaced operator new).
struct HugeAllocStats {
  std::uint64_t allocations = 0;  // huge_alloc calls
  std::uint64_t bytes = 0;        // bytes asked for
};
HugeAllocStats huge_alloc_stats();

// std-compatible allocator over huge_alloc: std::vector<T, HugePageAllocator<T>>.
template <typename T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>& /*other*/) noexcept {}  // NOLINT: rebind
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(huge_alloc(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t n) noexcept { huge_free(p, n * sizeof(T)); }
  template <typename U>
  friend bool operator==(const HugePageAllocator& /*a*/, const HugePageAllocator<U>& /*b*/) {
    return true;
  }
};

}  // namespace cncore::planner
