// Grbl 1.1's numbered replies: error:N for a line, ALARM:N for a latched alarm, and the state
// names of the status report, from cncore's refusals, alarms and machine states.
#pragma once

#include <string>
#include <string_view>

#include "runtime/control.hpp"

namespace cncore::grbl {

// Grbl error codes used here (its wiki lists them all).
enum class Error : int {
  kExpectedCommandLetter = 1,
  kBadNumberFormat = 2,
  kInvalidStatement = 3,  // '$' statement not recognised or not supported
  kNegativeValue = 4,
  kIdleError = 8,           // '$' command only valid when idle
  kSystemGcLock = 9,        // G-code locked out during alarm or jog
  kOverflow = 11,           // line longer than the line buffer
  kTravelExceeded = 15,     // jog target beyond the travel
  kInvalidJogCommand = 16,  // $J without '=' or with a prohibited word
  kUnsupportedCommand = 20,
  kUndefinedFeedRate = 22,
  kInvalidTarget = 33,  // motion target invalid (here: beyond the travel)
};

// The Grbl code for an interpreter or controller refusal of a G-code line (cncore's message goes
// out as [MSG:…] before it).
Error error_for(std::string_view cncore_message);

// ALARM:N for a runtime alarm (docs/senders.md has the table).
int alarm_number(runtime::AlarmCode alarm);

}  // namespace cncore::grbl
