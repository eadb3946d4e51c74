// The machine states of `cncore serve` and the one table that says which command is legal in
// which state and where it leads (docs/runtime.md draws it). The cycle thread applies it; the
// control interface consults it first so an illegal command is refused with a reason and moves
// nothing.
#pragma once

#include <cstdint>
#include <string_view>

namespace cncore::runtime {

enum class MachineState : std::uint8_t {
  kIdle,    // nothing moves; programs, MDI, jog and homing may start
  kRun,     // a program or MDI line runs (cycle)
  kHold,    // feed hold: decelerating on the path, then stopped; resume continues the same path
  kJog,     // a jog move (continuous or incremental), cancellable
  kHoming,  // per-axis search and latch against the switches, then machine zero
  kAlarm,   // soft limit, following error, E-stop, lost planner feed, homing failure: latched
  kCheck,   // programs are interpreted without motion
};

enum class AlarmCode : std::uint8_t {
  kNone,
  kSoftLimit,       // a move would leave the travel
  kFollowingError,  // |commanded − actual| above servo.following_error_limit_mm
  kEStop,           // emergency stop
  kPlannerLost,     // the planning thread failed while a program ran
  kHomingFailed,    // no switch found within the travel
  kProgramError,    // the program had an error while it ran (the tool stopped before it)
};

enum class Command : std::uint8_t {
  kStart,   // cycle start of a loaded program
  kResume,  // cycle start in Hold
  kHold,    // feed hold
  kReset,   // controlled stop, the program ends
  kEStop,
  kClearAlarm,  // unlock
  kJog,
  kJogCancel,
  kHome,
  kMdi,
  kLoad,  // load a program (no motion)
  kFeedOverride,
  kRapidOverride,
  kSwitches,
  kCheckOn,
  kCheckOff,
  kLimits,  // the running machine's limits change (nothing may move)
  kCount,
};

struct Transition {
  bool allowed = false;
  MachineState next = MachineState::kIdle;  // the state right after the command (when allowed)
  std::string_view why_not;                 // when refused: a reason for the operator
};

// Pure: the table. Events that are not commands (a program ends, a hold completes, an alarm is
// raised by the cycle) are the cycle thread's and are drawn in docs/runtime.md.
Transition transition(MachineState state, Command command);

std::string_view state_name(MachineState state);
std::string_view alarm_text(AlarmCode alarm);
std::string_view command_name(Command command);

}  // namespace cncore::runtime
