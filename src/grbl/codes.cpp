#include "grbl/codes.hpp"

namespace cncore::grbl {

Error error_for(std::string_view m) {
  auto has = [&](std::string_view s) { return m.find(s) != std::string_view::npos; };
  if (has("travel limit")) return Error::kInvalidTarget;
  if (has("no feed rate") || has("feed rate F is zero")) return Error::kUndefinedFeedRate;
  if (has("number")) return Error::kBadNumberFormat;
  return Error::kUnsupportedCommand;
}

int alarm_number(runtime::AlarmCode alarm) {
  switch (alarm) {
    case runtime::AlarmCode::kNone:
      return 0;
    case runtime::AlarmCode::kFollowingError:
      return 1;  // position lost, like a hard limit
    case runtime::AlarmCode::kSoftLimit:
      return 2;
    case runtime::AlarmCode::kPlannerLost:  // motion stopped abruptly
    case runtime::AlarmCode::kProgramError:
      return 3;
    case runtime::AlarmCode::kHomingFailed:
      return 9;
    case runtime::AlarmCode::kEStop:
      return 10;  // grblHAL's E-stop alarm
  }
  return 0;
}

}  // namespace cncore::grbl
