// The run streams: the heap allocations it makes do not depend on how long it runs.
#include <gtest/gtest.h>

#include <cstdlib>

#include "alloc_counter.hpp"
#include "helpers.hpp"

namespace cncore::tables::test {
namespace {

// Allocations made by run_tables for a cyclic cam repeated `reps` times; the callback only
// counts and checks.
std::size_t allocations_for(std::uint32_t reps, std::uint64_t& cycles) {
  RunOptions o;
  o.reference = ReferenceSource::spindle(120);  // 720 deg/s: 500 ms per revolution
  o.cyclic_repeats = reps;
  o.values.signals[3] = 0;
  std::vector<Table> t{
      parse_table("REF SPINDLE\nAXES X Z\nCUBIC\nCYCLIC\nL0 X0 Z0\nL120 X5 Z-2 SFT=R3\n"
                  "L240 X1 Z-4 M7\nL360 X0 Z0\n",
                  "cam.tbl"),
      parse_table("REF SPINDLE\nAXES Y\nCYCLIC\nL0 Y0\nL180 Y1\nL360 Y0\n", "y.tbl")};
  TablePlan plan = plan_tables(t, stiff_machine(), o);
  double max_x = 0;
  const long before = cncore::testing::allocations();
  RunSummary s =
      run_tables(plan, [&](const TableSample& ts) { max_x = std::max(max_x, ts.position[kX]); });
  const long after = cncore::testing::allocations();
  cycles = s.cycles;
  EXPECT_NEAR(max_x, 5, 0.01);
  return static_cast<std::size_t>(after - before);
}

TEST(Streaming, AllocationsDoNotGrowWithTheRunLength) {
  std::uint64_t short_cycles = 0, long_cycles = 0;
  std::size_t short_run = allocations_for(2, short_cycles);
  std::size_t long_run = allocations_for(1000, long_cycles);
  EXPECT_EQ(short_cycles, 1001U);  // 2 revolutions of 500 ms, 1 ms cycles, plus t = 0
  EXPECT_EQ(long_cycles, 500001U);
  EXPECT_EQ(short_run, long_run);
  EXPECT_LT(long_run, 20U);
}

}  // namespace
}  // namespace cncore::tables::test
