#include "runtime/state_machine.hpp"

namespace cncore::runtime {

namespace {

Transition to(MachineState next) {
  return {true, next, {}};
}
Transition refuse(std::string_view why) {
  return {false, MachineState::kIdle, why};
}

Transition from_idle(Command c) {
  switch (c) {
    case Command::kStart:
    case Command::kMdi:
      return to(MachineState::kRun);
    case Command::kJog:
      return to(MachineState::kJog);
    case Command::kHome:
      return to(MachineState::kHoming);
    case Command::kCheckOn:
      return to(MachineState::kCheck);
    case Command::kResume:
      return refuse("nothing to resume: the machine is idle");
    case Command::kLimits:
      return to(MachineState::kIdle);
    default:  // hold, jog cancel, check off, reset, unlock: harmless, nothing happens
      return to(MachineState::kIdle);
  }
}

Transition from_run(Command c) {
  switch (c) {
    case Command::kHold:
      return to(MachineState::kHold);
    case Command::kLoad:
      return refuse("a program is running: reset or wait for its end");
    case Command::kMdi:
      return refuse("a program is running: MDI waits until it ends");
    case Command::kJog:
      return refuse("a program is running: no jog");
    case Command::kHome:
      return refuse("a program is running: no homing");
    case Command::kCheckOn:
      return refuse("a program is running: check mode waits until it ends");
    case Command::kLimits:
      return refuse("a program is running: the machine's limits change when it is idle");
    default:  // reset (stops on the path, then Idle), start (already running), overrides
      return to(MachineState::kRun);
  }
}

Transition from_hold(Command c) {
  switch (c) {
    case Command::kResume:
    case Command::kStart:
      return to(MachineState::kRun);
    case Command::kLoad:
    case Command::kMdi:
    case Command::kJog:
    case Command::kHome:
    case Command::kCheckOn:
    case Command::kLimits:
      return refuse("the program is held: resume it or reset first");
    default:  // reset (then Idle), hold, overrides, switches
      return to(MachineState::kHold);
  }
}

Transition from_motion(MachineState s, Command c) {  // Jog, Homing
  switch (c) {
    case Command::kJogCancel:
    case Command::kReset:
    case Command::kHold:
      return to(s);  // decelerate, then Idle
    case Command::kJog:
      return s == MachineState::kJog ? to(s) : refuse("homing: wait until it ends or reset");
    case Command::kFeedOverride:
    case Command::kRapidOverride:
    case Command::kSwitches:
      return to(s);
    default:
      return refuse(s == MachineState::kJog ? "jogging: cancel the jog first"
                                            : "homing: wait until it ends or reset");
  }
}

Transition from_alarm(Command c) {
  switch (c) {
    case Command::kClearAlarm:
      return to(MachineState::kIdle);
    case Command::kReset:
      return to(MachineState::kAlarm);  // an E-stop stays latched
    case Command::kHome:
      return to(MachineState::kHoming);  // homing may clear a soft-limit alarm
    case Command::kFeedOverride:
    case Command::kRapidOverride:
    case Command::kSwitches:
    case Command::kLoad:
    case Command::kLimits:
      return to(MachineState::kAlarm);
    default:
      return refuse("alarm: clear it (unlock) first");
  }
}

Transition from_check(Command c) {
  switch (c) {
    case Command::kCheckOff:
      return to(MachineState::kIdle);
    case Command::kStart:
    case Command::kMdi:
    case Command::kLoad:
    case Command::kReset:
    case Command::kCheckOn:
    case Command::kFeedOverride:
    case Command::kRapidOverride:
    case Command::kSwitches:
    case Command::kLimits:
      return to(MachineState::kCheck);
    default:
      return refuse("check mode: nothing moves; leave check mode first");
  }
}

}  // namespace

Transition transition(MachineState state, Command command) {
  // Always legal: the E-stop, wherever the machine is.
  if (command == Command::kEStop) return to(MachineState::kAlarm);
  switch (state) {
    case MachineState::kIdle:
      return from_idle(command);
    case MachineState::kRun:
      return from_run(command);
    case MachineState::kHold:
      return from_hold(command);
    case MachineState::kJog:
    case MachineState::kHoming:
      return from_motion(state, command);
    case MachineState::kAlarm:
      return from_alarm(command);
    case MachineState::kCheck:
      return from_check(command);
  }
  return refuse("unknown state");
}

std::string_view state_name(MachineState state) {
  switch (state) {
    case MachineState::kIdle:
      return "Idle";
    case MachineState::kRun:
      return "Run";
    case MachineState::kHold:
      return "Hold";
    case MachineState::kJog:
      return "Jog";
    case MachineState::kHoming:
      return "Home";
    case MachineState::kAlarm:
      return "Alarm";
    case MachineState::kCheck:
      return "Check";
  }
  return "?";
}

std::string_view alarm_text(AlarmCode alarm) {
  switch (alarm) {
    case AlarmCode::kNone:
      return "no alarm";
    case AlarmCode::kSoftLimit:
      return "soft limit: a move would leave the travel";
    case AlarmCode::kFollowingError:
      return "following error above the limit";
    case AlarmCode::kEStop:
      return "emergency stop";
    case AlarmCode::kPlannerLost:
      return "the planner stopped feeding the motion";
    case AlarmCode::kHomingFailed:
      return "homing failed: no switch within the travel";
    case AlarmCode::kProgramError:
      return "program error: stopped before the failing block";
  }
  return "?";
}

std::string_view command_name(Command command) {
  switch (command) {
    case Command::kStart:
      return "start";
    case Command::kResume:
      return "resume";
    case Command::kHold:
      return "hold";
    case Command::kReset:
      return "reset";
    case Command::kEStop:
      return "estop";
    case Command::kClearAlarm:
      return "unlock";
    case Command::kJog:
      return "jog";
    case Command::kJogCancel:
      return "jog-cancel";
    case Command::kHome:
      return "home";
    case Command::kMdi:
      return "mdi";
    case Command::kLoad:
      return "load";
    case Command::kFeedOverride:
      return "feed-override";
    case Command::kRapidOverride:
      return "rapid-override";
    case Command::kSwitches:
      return "switches";
    case Command::kCheckOn:
      return "check-on";
    case Command::kCheckOff:
      return "check-off";
    case Command::kLimits:
      return "limits";
    case Command::kCount:
      break;
  }
  return "?";
}

}  // namespace cncore::runtime
