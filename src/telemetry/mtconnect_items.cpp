// The MTConnect data items of the controller's status, and their SHDR text.
#include <fmt/format.h>

#include <ctime>

#include "telemetry/telemetry.hpp"

namespace cncore::telemetry {
namespace {

using runtime::AlarmCode;
using runtime::MachineState;

// SHDR separates fields with '|' and lines with '\n': neither may appear in a value.
std::string clean(std::string v) {
  for (char& c : v) {
    if (c == '|' || c == '\n' || c == '\r') c = ' ';
  }
  return v;
}

ShdrItem item(std::string key, std::string value) {
  return {std::move(key), {std::move(value)}};
}

}  // namespace

// MTConnect Execution: what the controller is doing with its program or motion.
std::string execution_name(const runtime::Status& s) {
  if (s.resetting) return "STOPPED";
  switch (s.state) {
    case MachineState::kRun:
    case MachineState::kJog:
    case MachineState::kHoming:
      return "ACTIVE";
    case MachineState::kHold:
      return "FEED_HOLD";
    case MachineState::kAlarm:
      return s.alarm == AlarmCode::kEStop ? "STOPPED" : "INTERRUPTED";
    case MachineState::kIdle:
    case MachineState::kCheck:
      return "READY";
  }
  return "UNAVAILABLE";
}

// MTConnect ControllerMode: programs run in AUTOMATIC (SEMI_AUTOMATIC with single block), jog
// and homing in MANUAL, check mode is EDIT (programs are read, nothing moves).
std::string controller_mode_name(const runtime::Status& s) {
  switch (s.state) {
    case MachineState::kJog:
    case MachineState::kHoming:
      return "MANUAL";
    case MachineState::kCheck:
      return "EDIT";
    default:
      return s.switches.single_block ? "SEMI_AUTOMATIC" : "AUTOMATIC";
  }
}

std::vector<ShdrItem> mtconnect_items(const runtime::Status& s, const std::string& program) {
  std::vector<ShdrItem> items;
  items.reserve(16);
  items.push_back(item("avail", "AVAILABLE"));
  items.push_back(item("estop", s.alarm == AlarmCode::kEStop ? "TRIGGERED" : "ARMED"));
  items.push_back(item("mode", controller_mode_name(s)));
  items.push_back(item("execution", execution_name(s)));
  items.push_back(item("program", program.empty() ? "UNAVAILABLE" : clean(program)));
  items.push_back(item("line", s.line == 0 ? "UNAVAILABLE" : fmt::format("{}", s.line)));
  // Machine coordinates, mm; 3 decimals (1 µm) so that a still axis does not flicker.
  static constexpr const char* kAxes[] = {"X", "Y", "Z"};
  for (std::size_t a = 0; a < 3; ++a) {
    items.push_back(item(fmt::format("{}act", kAxes[a]), fmt::format("{:.3f}", s.actual[a])));
    items.push_back(item(fmt::format("{}com", kAxes[a]), fmt::format("{:.3f}", s.commanded[a])));
  }
  // MTConnect's PathFeedrate unit is mm/s.
  items.push_back(item("path_feedrate", fmt::format("{:.2f}", s.feed_mm_min / 60)));
  items.push_back(item("Fovr", fmt::format("{:g}", s.feed_override_pct)));
  items.push_back(item("Rovr", fmt::format("{:g}", s.rapid_override_pct)));
  items.push_back(item("Sload", fmt::format("{:.1f}", s.load_pct)));
  if (s.alarm == AlarmCode::kNone) {
    items.push_back({"system", {"NORMAL", "", "", "", ""}});
  } else {
    std::string text(runtime::alarm_text(s.alarm));
    if (s.alarm_line != 0) text += fmt::format(" (line {})", s.alarm_line);
    items.push_back(
        {"system", {"FAULT", fmt::format("{}", static_cast<int>(s.alarm)), "", "", clean(text)}});
  }
  return items;
}

std::string shdr_timestamp(std::chrono::system_clock::time_point t) {
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count();
  const auto secs = static_cast<std::time_t>(ms / 1000);
  std::tm utc{};
  gmtime_r(&secs, &utc);
  return fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:03}Z", utc.tm_year + 1900,
                     utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, ms % 1000);
}

std::vector<std::string> shdr_lines(const std::string& timestamp,
                                    const std::vector<const ShdrItem*>& items) {
  std::vector<std::string> lines;
  std::string samples;
  for (const ShdrItem* i : items) {
    if (i->condition()) {
      std::string line = timestamp + "|" + i->key;
      for (const std::string& f : i->fields) line += "|" + f;
      lines.push_back(std::move(line));
    } else {
      samples += "|" + i->key + "|" + i->fields.front();
    }
  }
  if (!samples.empty()) lines.insert(lines.begin(), timestamp + samples);
  return lines;
}

}  // namespace cncore::telemetry
