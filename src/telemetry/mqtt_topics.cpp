// The MQTT topics of the controller's status: which message each change makes, and its JSON
// (docs/telemetry.md, "MQTT", lists every topic).
#include <cmath>
#include <nlohmann/json.hpp>

#include "telemetry/telemetry.hpp"

namespace cncore::telemetry {
namespace {

using nlohmann::json;
using runtime::AlarmCode;
using runtime::JobEnd;

// Rounded to `decimals` so that the JSON's shortest form is short (0.944, not
// 0.9440000000000001): an integer divided by a power of ten is the double nearest the decimal.
double rounded(double v, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(v * scale) / scale;
}

const char* job_end_name(JobEnd e) {
  switch (e) {
    case JobEnd::kCompleted:
      return "completed";
    case JobEnd::kReset:
      return "reset";
    case JobEnd::kAlarm:
      return "alarm";
    case JobEnd::kRunning:
      break;
  }
  return "running";
}

// A message whose payload is compared with the last one sent (without its timestamp): sent only
// when it differs.
bool changed(std::string& last, const json& body) {
  std::string text = body.dump();
  if (text == last) return false;
  last = std::move(text);
  return true;
}

MqttMessage make(std::string topic, json body, MqttTopics::Clock::time_point now, int qos,
                 bool retain) {
  body["ts"] = shdr_timestamp(now);
  return {std::move(topic), body.dump(), qos, retain};
}

json state_body(const runtime::Status& s) {
  return {{"state", std::string(runtime::state_name(s.state))},
          {"execution", execution_name(s)},
          {"mode", controller_mode_name(s)},
          {"hold_complete", s.hold_complete},
          {"homed", s.homed}};
}

json alarm_body(const runtime::Status& s) {
  if (s.alarm == AlarmCode::kNone) return {{"active", false}};
  return {{"active", true},
          {"code", static_cast<int>(s.alarm)},
          {"text", std::string(runtime::alarm_text(s.alarm))},
          {"line", s.alarm_line}};
}

json program_body(const std::string& program) {
  return {{"program", program.empty() ? json(nullptr) : json(program)}};
}

}  // namespace

MqttTopics::MqttTopics(std::string prefix, const MachineConfig& machine)
    : prefix_(std::move(prefix)), machine_(machine) {}

MqttMessage MqttTopics::state_message(const runtime::Status& s, Clock::time_point now) {
  return make(topic("state"), state_body(s), now, 1, true);
}

MqttMessage MqttTopics::alarm_message(const runtime::Status& s, Clock::time_point now) {
  return make(topic("alarm"), alarm_body(s), now, 1, true);
}

MqttMessage MqttTopics::program_message(const std::string& program, Clock::time_point now) {
  return make(topic("program"), program_body(program), now, 1, true);
}

void MqttTopics::baseline(const runtime::Status& s) {
  if (!first_) return;
  first_ = false;
  started_job_ = ended_job_ = s.job;  // a job already running or run before: not ours to report
}

std::vector<MqttMessage> MqttTopics::birth(const runtime::Status& s, const std::string& program,
                                           Clock::time_point now) {
  baseline(s);
  json axes = json::array();
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (machine_.axes[i].enabled) axes.push_back(std::string(1, kAxisLetters[i]));
  }
  std::vector<MqttMessage> out;
  out.push_back(make(topic("online"),
                     {{"online", true},
                      {"controller", "cncore"},
                      {"machine", machine_.name},
                      {"axes", axes},
                      {"period_s", machine_.period_s}},
                     now, 1, true));
  last_program_ = program_body(program).dump();
  out.push_back(program_message(program, now));
  last_state_ = state_body(s).dump();
  out.push_back(state_message(s, now));
  last_alarm_ = alarm_body(s).dump();
  out.push_back(alarm_message(s, now));
  return out;
}

void MqttTopics::cycle_events(const runtime::Status& s, const std::string& program,
                              Clock::time_point now, std::vector<MqttMessage>& out) {
  baseline(s);
  const json name = s.job_mdi || program.empty() ? json(nullptr) : json(program);
  if (s.job != started_job_ && s.job != 0) {
    started_job_ = s.job;
    job_program_ = name.dump();
    out.push_back(make(topic("cycle"),
                       {{"event", "start"},
                        {"job", s.job},
                        {"program", name},
                        {"mdi", s.job_mdi},
                        {"cycle", s.job_first_cycle}},
                       now, 1, false));
  }
  if (s.job == started_job_ && ended_job_ != s.job && s.job_end != JobEnd::kRunning) {
    ended_job_ = s.job;
    // Samples at cycles first…last: (last − first) periods, the way `cncore run` counts the
    // cycle time of its samples.
    const std::uint64_t periods = s.job_last_cycle - s.job_first_cycle;
    out.push_back(
        make(topic("cycle"),
             {{"event", "end"},
              {"job", s.job},
              {"program", json::parse(job_program_)},
              {"mdi", s.job_mdi},
              {"result", job_end_name(s.job_end)},
              {"cycles", periods + 1},
              {"cycle_time_s", rounded(static_cast<double>(periods) * machine_.period_s, 6)}},
             now, 1, false));
  }
}

std::vector<MqttMessage> MqttTopics::events(const runtime::Status& s, const std::string& program,
                                            Clock::time_point now) {
  std::vector<MqttMessage> out;
  if (changed(last_program_, program_body(program))) out.push_back(program_message(program, now));
  cycle_events(s, program, now, out);
  if (changed(last_alarm_, alarm_body(s))) out.push_back(alarm_message(s, now));
  if (changed(last_state_, state_body(s))) out.push_back(state_message(s, now));
  return out;
}

MqttMessage MqttTopics::sample(const runtime::Status& s, std::uint64_t dropped,
                               Clock::time_point now) const {
  json body = {{"cycle", s.cycle},
               {"line", s.line},
               {"feed_mm_min", rounded(s.feed_mm_min, 3)},
               {"feed_override_pct", s.feed_override_pct},
               {"rapid_override_pct", s.rapid_override_pct},
               {"spindle_load_pct", rounded(s.load_pct, 2)},
               {"following_error_mm", rounded(s.following_error_mm, 6)},
               {"dropped", dropped}};
  // Linear axes in mm, rotary axes in degrees: under keys that say so.
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!machine_.axes[i].enabled) continue;
    const char* unit = machine_.axes[i].rotary ? "_deg" : "_mm";
    const std::string axis(1, kAxisLetters[i]);
    body[std::string("actual") + unit][axis] = rounded(s.actual[i], 4);
    body[std::string("commanded") + unit][axis] = rounded(s.commanded[i], 4);
  }
  return make(topic("sample"), std::move(body), now, 0, false);
}

MqttMessage MqttTopics::offline(bool will) const {
  const json body = {{"online", false}, {"reason", will ? "connection lost" : "shutdown"}};
  return {topic("online"), body.dump(), 1, true};
}

}  // namespace cncore::telemetry
