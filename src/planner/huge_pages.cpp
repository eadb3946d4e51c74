#include "planner/huge_pages.hpp"

#include <atomic>
#include <cstdint>
#include <mutex>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace cncore::planner {

namespace {

constexpr std::size_t kAlign = 64;                      // cache line
constexpr std::size_t kSmall = std::size_t{64} * 1024;  // below: operator new (a few pages at most)
constexpr std::size_t kHugePage = std::size_t{2} * 1024 * 1024;  // x86-64 transparent huge page
constexpr std::size_t kRegion = 8 * kHugePage;  // virtual size of a region (touched lazily)

std::size_t round_up(std::size_t n, std::size_t to) {
  return (n + to - 1) / to * to;
}

std::atomic<std::uint64_t> g_allocations{0}, g_bytes{0};

#if defined(__linux__)

struct Region {
  char* base = nullptr;
  std::size_t size = 0;
  std::size_t used = 0;  // bump pointer
  std::size_t live = 0;  // allocations not yet freed
};

std::mutex g_mutex;
std::vector<Region> g_regions;  // a few at most: one per live kernel's worth of buffers

// A 2 MB-aligned anonymous mapping of `size` bytes (a multiple of 2 MB), advised to use huge
// pages; nullptr when the system refuses.
char* map_region(std::size_t size) {
  const std::size_t span = size + kHugePage;
  void* raw = ::mmap(nullptr, span, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) return nullptr;
  const auto addr = reinterpret_cast<std::uintptr_t>(raw);
  const std::size_t head = (kHugePage - addr % kHugePage) % kHugePage;
  // Trim the unaligned head and the tail so that only the aligned range stays mapped (pointer
  // arithmetic on the mapping, no integer-to-pointer casts).
  char* const base = static_cast<char*>(raw) + head;
  if (head > 0) ::munmap(raw, head);
  if (span > head + size) ::munmap(base + size, span - head - size);
  ::madvise(base, size, MADV_HUGEPAGE);  // best effort: 4 KB pages when THP is off
  return base;
}

#endif

}  // namespace

HugeAllocStats huge_alloc_stats() {
  return {g_allocations.load(std::memory_order_relaxed), g_bytes.load(std::memory_order_relaxed)};
}

void* huge_alloc(std::size_t bytes) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  g_bytes.fetch_add(bytes, std::memory_order_relaxed);
  if (bytes < kSmall) return ::operator new (bytes > 0 ? bytes : 1, std::align_val_t{kAlign});
#if defined(__linux__)
  const std::size_t need = round_up(bytes, kAlign);
  const std::lock_guard<std::mutex> lock(g_mutex);
  for (Region& r : g_regions) {
    if (r.size - r.used >= need) {
      char* p = r.base + r.used;
      r.used += need;
      ++r.live;
      return p;
    }
  }
  const std::size_t size = round_up(need > kRegion ? need : kRegion, kHugePage);
  char* base = map_region(size);
  if (base == nullptr) throw std::bad_alloc();
  g_regions.reserve(g_regions.size() + 1);  // may throw: before the region is in use
  g_regions.push_back({base, size, need, 1});
  return base;
#else
  return ::operator new (bytes, std::align_val_t{kAlign});
#endif
}

void huge_free(void* p, std::size_t bytes) noexcept {
  if (p == nullptr) return;
  if (bytes < kSmall) {
    ::operator delete (p, std::align_val_t{kAlign});
    return;
  }
#if defined(__linux__)
  const std::lock_guard<std::mutex> lock(g_mutex);
  auto* c = static_cast<char*>(p);
  for (std::size_t i = 0; i < g_regions.size(); ++i) {
    Region& r = g_regions[i];
    if (c < r.base || c >= r.base + r.size) continue;
    if (--r.live > 0) return;
    // Empty: keep it (its pages stay faulted in) for the next kernel, unless another empty
    // region is kept already.
    r.used = 0;
    for (std::size_t j = 0; j < g_regions.size(); ++j) {
      if (j != i && g_regions[j].live == 0) {
        ::munmap(r.base, r.size);
        g_regions.erase(g_regions.begin() + static_cast<std::ptrdiff_t>(i));
        return;
      }
    }
    return;
  }
#else
  ::operator delete (p, std::align_val_t{kAlign});
#endif
}

}  // namespace cncore::planner
