// The kernel buffers' allocator (planner/huge_pages.hpp): aligned, disjoint, keeps what is
// written, and hands the memory of a destroyed kernel to the next one.
#include "planner/huge_pages.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "planner/buffer.hpp"

namespace cncore::planner {
namespace {

bool aligned64(const void* p) {
  return reinterpret_cast<std::uintptr_t>(p) % 64 == 0;
}

TEST(HugePages, BlocksAreAlignedDisjointAndKeepTheirContents) {
  // Small (operator new), large (a region), larger than a region (its own region).
  const std::vector<std::size_t> sizes = {
      1, 100, 64 * 1024 - 1, 64 * 1024, 300 * 1000, 3 * 1000 * 1000, 20 * 1000 * 1000, 77};
  std::vector<std::pair<unsigned char*, std::size_t>> blocks;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    auto* p = static_cast<unsigned char*>(huge_alloc(sizes[i]));
    ASSERT_NE(p, nullptr);
    EXPECT_TRUE(aligned64(p)) << sizes[i];
    std::memset(p, static_cast<int>(i + 1), sizes[i]);
    blocks.emplace_back(p, sizes[i]);
  }
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const auto [p, n] = blocks[i];
    EXPECT_EQ(p[0], i + 1);
    EXPECT_EQ(p[n - 1], i + 1);
    EXPECT_EQ(p[n / 2], i + 1);
    for (std::size_t j = 0; j < i; ++j) {
      const auto [q, m] = blocks[j];
      EXPECT_TRUE(p + n <= q || q + m <= p) << "blocks " << i << " and " << j << " overlap";
    }
  }
  for (const auto& [p, n] : blocks) huge_free(p, n);
}

TEST(HugePages, TheMemoryOfAFreedBufferIsReused) {
  // Two kernels' worth in a row: the second gets the first one's (already touched) memory.
  void* first = huge_alloc(5 * 1000 * 1000);
  huge_free(first, 5 * 1000 * 1000);
  void* second = huge_alloc(5 * 1000 * 1000);
  EXPECT_EQ(first, second);
  huge_free(second, 5 * 1000 * 1000);
}

TEST(HugePages, StatsCountEveryAllocation) {
  const HugeAllocStats before = huge_alloc_stats();
  void* small = huge_alloc(1000);
  void* large = huge_alloc(1000 * 1000);
  const HugeAllocStats after = huge_alloc_stats();
  EXPECT_EQ(after.allocations - before.allocations, 2u);
  EXPECT_EQ(after.bytes - before.bytes, 1000u + 1000u * 1000u);
  huge_free(large, 1000 * 1000);
  huge_free(small, 1000);
}

TEST(HugePages, SegmentBufferOfAWholeWindowWorks) {
  SegmentBuffer buf(10002);
  for (std::uint64_t k = 0; k < 3 * buf.capacity(); ++k) {
    if (buf.full()) buf.pop_front();
    Segment s;
    s.s0_mm = static_cast<double>(k);
    s.length_mm = 1;
    s.line = static_cast<std::uint32_t>(k);
    EXPECT_EQ(buf.push(s), k);
  }
  EXPECT_EQ(buf[buf.begin_index()].line, buf.begin_index());
  EXPECT_EQ(buf.seek(buf.begin_index(), static_cast<double>(buf.begin_index()) + 500.5),
            buf.begin_index() + 500);
}

}  // namespace
}  // namespace cncore::planner
