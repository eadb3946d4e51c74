// Motion kernel, end to end: the produced trajectory is measured by the independent checker
// (tests/support) against the programmed blocks — P1–P5 of spec 01.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "limits.hpp"
#include "motion_test_util.hpp"
#include "trajectory_checker.hpp"

namespace cncore::motion::test {
namespace {

testing::CheckReport check(const MachineConfig& m, const std::vector<Block>& blocks,
                           const RunResult& r) {
  return testing::check_trajectory(r.traj, blocks, testing::limits_from_config(m));
}

class BothModes : public ::testing::TestWithParam<Mode> {};

TEST_P(BothModes, SeedExampleKeepsEveryLimit) {
  const MachineConfig m = test_machine();
  const Prog p = seed_example();
  RunOpts o;
  o.kernel.mode = GetParam();
  o.kernel.check_reference_walk = true;
  const RunResult r = run(m, p.blocks, o);
  const auto rep = check(m, p.blocks, r);
  EXPECT_TRUE(rep.ok()) << rep.summary();
  EXPECT_EQ(r.mismatches, 0u);
  // First sample: the start at t = 0; last: the programmed end, at rest.
  ASSERT_GE(r.samples.size(), 2u);
  EXPECT_EQ(r.samples.front().t_s, 0.0);
  EXPECT_EQ(r.samples.front().position, AxisVec{});
  EXPECT_NEAR(r.samples.back().position[kX], 0.0, 1e-9);
  EXPECT_NEAR(r.samples.back().position[kY], 20.0, 1e-9);
  EXPECT_EQ(r.samples.back().feed_mm_min, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Kernel, BothModes, ::testing::Values(Mode::kLookahead, Mode::kStop),
                         [](const auto& param_info) {
                           return std::string(param_info.param == Mode::kLookahead ? "Lookahead"
                                                                                   : "Stop");
                         });

}  // namespace
}  // namespace cncore::motion::test
