// The MQTT messages of successive statuses (no broker): which topic each change makes, in which
// order, with what QoS and retain flag, and the cycle time of a job from the cycles it ran.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "telemetry/telemetry.hpp"

namespace {

using namespace cncore;
using nlohmann::json;
using runtime::JobEnd;
using runtime::MachineState;
using telemetry::MqttMessage;
using telemetry::MqttTopics;

// "leaf:key" for each message, the key picked per topic (what a sequence check compares).
std::vector<std::string> summary(const std::vector<MqttMessage>& ms) {
  std::vector<std::string> out;
  for (const MqttMessage& m : ms) {
    const json j = json::parse(m.payload);
    const std::string leaf = m.topic.substr(m.topic.rfind('/') + 1);
    if (leaf == "state") out.push_back("state:" + j["execution"].get<std::string>());
    if (leaf == "cycle") out.push_back("cycle:" + j["event"].get<std::string>());
    if (leaf == "alarm") out.push_back(std::string("alarm:") + (j["active"] ? "on" : "off"));
    if (leaf == "program") out.push_back("program");
    if (leaf == "online") out.push_back(std::string("online:") + (j["online"] ? "yes" : "no"));
  }
  return out;
}

TEST(MqttUrl, SchemesPortsAndPrefix) {
  const auto t = telemetry::parse_mqtt_url("mqtt://broker.local/shop/mill1/");
  EXPECT_FALSE(t.tls);
  EXPECT_EQ(t.host, "broker.local");
  EXPECT_EQ(t.port, 1883);
  EXPECT_EQ(t.prefix, "shop/mill1");
  EXPECT_EQ(t.server_uri(), "tcp://broker.local:1883");
  const auto s = telemetry::parse_mqtt_url("mqtts://127.0.0.1:9883/m");
  EXPECT_TRUE(s.tls);
  EXPECT_EQ(s.port, 9883);
  EXPECT_EQ(s.server_uri(), "ssl://127.0.0.1:9883");
  EXPECT_EQ(telemetry::parse_mqtt_url("mqtt://[::1]:1884/m").server_uri(), "tcp://[::1]:1884");
  for (const char* bad : {"tcp://h/p", "mqtt://h", "mqtt://h/", "mqtt://:1883/p", "mqtt://h:0/p",
                          "mqtt://h:x/p", "mqtt://h/p/#"}) {
    EXPECT_THROW((void)telemetry::parse_mqtt_url(bad), std::runtime_error) << bad;
  }
}

class MqttTopicsTest : public ::testing::Test {
 protected:
  MachineConfig machine = default_machine_config();
  MqttTopics topics{"shop/m1", machine};
  MqttTopics::Clock::time_point now = MqttTopics::Clock::now();
  runtime::Status s;
  std::vector<MqttMessage> events() { return topics.events(s, "part.ngc", now); }
};

TEST_F(MqttTopicsTest, BirthIsRetainedAndAProgramRunGivesStartStatesAndEnd) {
  const auto birth = topics.birth(s, "part.ngc", now);
  EXPECT_EQ(summary(birth),
            (std::vector<std::string>{"online:yes", "program", "state:READY", "alarm:off"}));
  for (const MqttMessage& m : birth) {
    EXPECT_EQ(m.qos, 1);
    EXPECT_TRUE(m.retain) << m.topic;
    EXPECT_TRUE(m.topic.starts_with("shop/m1/"));
  }
  EXPECT_TRUE(events().empty());  // nothing changed since the birth
  s.state = MachineState::kRun;
  s.job = 1;
  s.job_first_cycle = 1000;
  s.job_last_cycle = 1000;
  const auto start = events();
  EXPECT_EQ(summary(start), (std::vector<std::string>{"cycle:start", "state:ACTIVE"}));
  EXPECT_FALSE(start[0].retain);
  EXPECT_EQ(json::parse(start[0].payload)["program"], "part.ngc");
  s.job_last_cycle = 1500;
  EXPECT_TRUE(events().empty());  // samples carry the motion, not events
  s.state = MachineState::kHold;
  EXPECT_EQ(summary(events()), (std::vector<std::string>{"state:FEED_HOLD"}));
  s.state = MachineState::kIdle;
  s.job_end = JobEnd::kCompleted;
  s.job_last_cycle = 1944;
  const auto end = events();
  ASSERT_EQ(summary(end), (std::vector<std::string>{"cycle:end", "state:READY"}));
  const json e = json::parse(end[0].payload);
  EXPECT_EQ(e["result"], "completed");
  EXPECT_EQ(e["cycles"], 945);                               // samples at cycles 1000…1944
  EXPECT_DOUBLE_EQ(e["cycle_time_s"].get<double>(), 0.944);  // 944 periods of 1 ms
  EXPECT_EQ(end[0].qos, 1);
  EXPECT_TRUE(events().empty());  // the end is reported once
}

TEST_F(MqttTopicsTest, AJobSeenOnlyAfterItEndedStillGivesStartThenEnd) {
  (void)topics.birth(s, "part.ngc", now);
  s.job = 4;
  s.job_mdi = true;
  s.job_end = JobEnd::kAlarm;
  s.job_first_cycle = 10;
  s.job_last_cycle = 12;
  s.state = MachineState::kAlarm;
  s.alarm = runtime::AlarmCode::kEStop;
  const auto ms = events();
  EXPECT_EQ(summary(ms),
            (std::vector<std::string>{"cycle:start", "cycle:end", "alarm:on", "state:STOPPED"}));
  EXPECT_EQ(json::parse(ms[0].payload)["program"], nullptr);  // MDI
  EXPECT_EQ(json::parse(ms[1].payload)["result"], "alarm");
  const json alarm = json::parse(ms[2].payload);
  EXPECT_EQ(alarm["text"], std::string(runtime::alarm_text(runtime::AlarmCode::kEStop)));
}

TEST_F(MqttTopicsTest, AJobRunningBeforeTheFirstStatusIsNotReported) {
  s.job = 2;
  s.state = MachineState::kRun;
  (void)events();
  s.job_end = JobEnd::kCompleted;
  s.state = MachineState::kIdle;
  EXPECT_EQ(summary(events()), (std::vector<std::string>{"state:READY"}));
}

TEST_F(MqttTopicsTest, SampleAndWill) {
  s.line = 30;
  s.actual[0] = 12.345678;
  s.commanded[1] = -4;
  s.feed_mm_min = 6000;
  s.load_pct = 42.5;
  const MqttMessage m = topics.sample(s, 7, now);
  EXPECT_EQ(m.topic, "shop/m1/sample");
  EXPECT_EQ(m.qos, 0);
  EXPECT_FALSE(m.retain);
  const json j = json::parse(m.payload);
  EXPECT_EQ(j["line"], 30);
  EXPECT_DOUBLE_EQ(j["actual_mm"]["X"].get<double>(), 12.3457);
  EXPECT_DOUBLE_EQ(j["commanded_mm"]["Y"].get<double>(), -4);
  EXPECT_FALSE(j.contains("actual_deg"));  // the built-in mill has no rotary axis
  EXPECT_EQ(j["feed_mm_min"], 6000);
  EXPECT_EQ(j["spindle_load_pct"], 42.5);
  EXPECT_EQ(j["dropped"], 7);
  const MqttMessage will = topics.offline(true);
  EXPECT_EQ(will.topic, "shop/m1/online");
  EXPECT_TRUE(will.retain);
  EXPECT_EQ(json::parse(will.payload)["online"], false);
}

}  // namespace
