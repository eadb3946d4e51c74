// The machine-state table of `cncore serve`: every state × command pair, legal and illegal.
#include "runtime/state_machine.hpp"

#include <gtest/gtest.h>

#include <map>
#include <utility>

namespace cncore::runtime {
namespace {

using S = MachineState;
using C = Command;

constexpr S kStates[] = {S::kIdle, S::kRun, S::kHold, S::kJog, S::kHoming, S::kAlarm, S::kCheck};

TEST(StateMachine, EStopIsLegalEverywhereAndLatchesAnAlarm) {
  for (S s : kStates) {
    const Transition t = transition(s, C::kEStop);
    EXPECT_TRUE(t.allowed) << state_name(s);
    EXPECT_EQ(t.next, S::kAlarm) << state_name(s);
  }
}

TEST(StateMachine, EveryPairIsDecidedAndEveryRefusalSaysWhy) {
  for (S s : kStates) {
    for (int c = 0; c < static_cast<int>(C::kCount); ++c) {
      const Transition t = transition(s, static_cast<C>(c));
      if (!t.allowed) {
        EXPECT_FALSE(t.why_not.empty()) << state_name(s) << " " << command_name(static_cast<C>(c));
      }
    }
  }
}

// The transitions a user relies on, and the refusals that keep the machine safe.
TEST(StateMachine, TableOfTransitions) {
  const std::map<std::pair<S, C>, S> legal = {
      {{S::kIdle, C::kStart}, S::kRun},        {{S::kIdle, C::kMdi}, S::kRun},
      {{S::kIdle, C::kJog}, S::kJog},          {{S::kIdle, C::kHome}, S::kHoming},
      {{S::kIdle, C::kCheckOn}, S::kCheck},    {{S::kRun, C::kHold}, S::kHold},
      {{S::kHold, C::kResume}, S::kRun},       {{S::kHold, C::kStart}, S::kRun},
      {{S::kAlarm, C::kClearAlarm}, S::kIdle}, {{S::kAlarm, C::kHome}, S::kHoming},
      {{S::kCheck, C::kCheckOff}, S::kIdle},   {{S::kJog, C::kJog}, S::kJog},
      {{S::kRun, C::kFeedOverride}, S::kRun},  {{S::kHold, C::kRapidOverride}, S::kHold},
  };
  for (const auto& [from_cmd, to] : legal) {
    const Transition t = transition(from_cmd.first, from_cmd.second);
    EXPECT_TRUE(t.allowed) << state_name(from_cmd.first) << " " << command_name(from_cmd.second);
    EXPECT_EQ(t.next, to) << state_name(from_cmd.first) << " " << command_name(from_cmd.second);
  }
  const std::pair<S, C> refused[] = {
      {S::kIdle, C::kResume},  {S::kRun, C::kLoad},    {S::kRun, C::kMdi},    {S::kRun, C::kJog},
      {S::kRun, C::kHome},     {S::kRun, C::kCheckOn}, {S::kHold, C::kMdi},   {S::kHold, C::kJog},
      {S::kHold, C::kLoad},    {S::kJog, C::kStart},   {S::kJog, C::kHome},   {S::kHoming, C::kJog},
      {S::kHoming, C::kStart}, {S::kAlarm, C::kStart}, {S::kAlarm, C::kJog},  {S::kAlarm, C::kMdi},
      {S::kAlarm, C::kResume}, {S::kCheck, C::kJog},   {S::kCheck, C::kHome},
  };
  for (const auto& [s, c] : refused) {
    EXPECT_FALSE(transition(s, c).allowed) << state_name(s) << " " << command_name(c);
  }
}

}  // namespace
}  // namespace cncore::runtime
