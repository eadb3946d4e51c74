// The MTConnect SHDR adapter read by a TCP client while the controller serves a program: every
// line is checked against the protocol (timestamps, key/value pairs, conditions, heartbeat) and
// the data items change when the machine does.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "runtime/control.hpp"
#include "telemetry/telemetry.hpp"

namespace {

using namespace cncore;
using namespace std::chrono_literals;
using runtime::MachineState;

// A TCP client that collects the adapter's lines on a thread of its own.
class ShdrClient {
 public:
  explicit ShdrClient(std::uint16_t port) {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    thread_ = std::thread([this] { read_lines(); });
  }
  ~ShdrClient() {
    stop_.store(true);
    thread_.join();
    close(fd_);
  }
  ShdrClient(const ShdrClient&) = delete;
  ShdrClient& operator=(const ShdrClient&) = delete;

  bool connected() const { return connected_; }
  void send_line(const std::string& line) const {
    const std::string text = line + "\n";
    ASSERT_EQ(send(fd_, text.data(), text.size(), MSG_NOSIGNAL), static_cast<ssize_t>(text.size()));
  }
  std::vector<std::string> lines() {
    const std::lock_guard lock(mutex_);
    return lines_;
  }
  bool wait_line(const std::string& prefix, std::chrono::milliseconds timeout = 5s) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      for (const std::string& l : lines()) {
        if (l.starts_with(prefix)) return true;
      }
      std::this_thread::sleep_for(5ms);
    }
    return false;
  }

 private:
  void read_lines() {
    std::string pending;
    while (!stop_.load()) {
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 20) <= 0) continue;
      char buf[4096];
      const ssize_t n = recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) return;
      pending.append(buf, static_cast<std::size_t>(n));
      for (auto nl = pending.find('\n'); nl != std::string::npos; nl = pending.find('\n')) {
        const std::lock_guard lock(mutex_);
        lines_.push_back(pending.substr(0, nl));
        pending.erase(0, nl + 1);
      }
    }
  }
  int fd_ = -1;
  bool connected_ = false;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::string> lines_;
  std::thread thread_;
};

std::vector<std::string> split_bars(const std::string& s) {
  std::vector<std::string> f(1);
  for (const char c : s) {
    if (c == '|') {
      f.emplace_back();
    } else {
      f.back() += c;
    }
  }
  return f;
}

bool is_number(const std::string& s) {
  return std::regex_match(s, std::regex(R"(-?\d+(\.\d+)?)"));
}

// One value change as the client saw it, in stream order.
struct Change {
  std::string key, value;
};

// Checks every line against SHDR; `changes`: the value changes in order.
void check_protocol(const std::vector<std::string>& lines, std::uint32_t pong_ms,
                    std::vector<Change>& changes) {
  static const std::regex kTimestamp(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z)");
  static const std::set<std::string> kEvents{"avail",     "estop",   "mode",
                                             "execution", "program", "line"};
  static const std::set<std::string> kSamples{"Xact", "Yact",          "Zact", "Xcom", "Ycom",
                                              "Zcom", "path_feedrate", "Fovr", "Rovr", "Sload"};
  static const std::map<std::string, std::set<std::string>> kControlled{
      {"avail", {"AVAILABLE", "UNAVAILABLE"}},
      {"estop", {"ARMED", "TRIGGERED"}},
      {"mode", {"AUTOMATIC", "SEMI_AUTOMATIC", "MANUAL", "MANUAL_DATA_INPUT", "EDIT"}},
      {"execution",
       {"READY", "ACTIVE", "INTERRUPTED", "FEED_HOLD", "STOPPED", "OPTIONAL_STOP",
        "PROGRAM_STOPPED", "PROGRAM_COMPLETED"}}};
  std::map<std::string, std::string> current;
  std::string previous_timestamp;
  const auto now = std::chrono::system_clock::now();
  for (const std::string& line : lines) {
    SCOPED_TRACE(line);
    if (line.starts_with("* ")) {
      EXPECT_EQ(line, "* PONG " + std::to_string(pong_ms));
      continue;
    }
    const std::vector<std::string> f = split_bars(line);
    ASSERT_GE(f.size(), 3U);
    ASSERT_TRUE(std::regex_match(f[0], kTimestamp));
    EXPECT_GE(f[0], previous_timestamp);  // ISO 8601 of one length: text order is time order
    EXPECT_LE(f[0], telemetry::shdr_timestamp(now + 60s));
    EXPECT_GE(f[0], telemetry::shdr_timestamp(now - 600s));
    previous_timestamp = f[0];
    if (f[1] == "system") {
      // A condition alone on its line: level, native code, severity, qualifier, message.
      ASSERT_EQ(f.size(), 7U);
      EXPECT_TRUE(f[2] == "NORMAL" || f[2] == "FAULT" || f[2] == "WARNING" ||
                  f[2] == "UNAVAILABLE");
      if (f[2] == "NORMAL") {
        EXPECT_EQ(f[6], "");
      }
      if (f[2] == "FAULT") {
        EXPECT_FALSE(f[6].empty());
      }
      changes.push_back({"system", f[2] + ":" + f[6]});
      continue;
    }
    ASSERT_EQ(f.size() % 2, 1U) << "key|value pairs";
    for (std::size_t i = 1; i + 1 < f.size(); i += 2) {
      const std::string& key = f[i];
      const std::string& value = f[i + 1];
      ASSERT_TRUE(kEvents.contains(key) || kSamples.contains(key)) << key;
      if (kSamples.contains(key) || key == "line") {
        EXPECT_TRUE(is_number(value) || value == "UNAVAILABLE") << key << "=" << value;
      }
      if (kControlled.contains(key)) {
        EXPECT_TRUE(kControlled.at(key).contains(value)) << value;
      }
      // Only changes are sent: a value is never repeated.
      EXPECT_NE(current[key], value) << key;
      current[key] = value;
      changes.push_back({key, value});
    }
  }
}

std::vector<std::string> values_of(const std::vector<Change>& changes, const std::string& key) {
  std::vector<std::string> v;
  for (const Change& c : changes) {
    if (c.key == key) v.push_back(c.value);
  }
  return v;
}

// `want` appears in `seen` in this order (other values may come between).
bool in_order(const std::vector<std::string>& seen, const std::vector<std::string>& want) {
  std::size_t i = 0;
  for (const std::string& s : seen) {
    if (i < want.size() && s == want[i]) ++i;
  }
  return i == want.size();
}

std::string write_program(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream(path) << text;
  return path.string();
}

bool wait_for(const runtime::Controller& c, MachineState s, bool hold_complete = false) {
  const auto end = std::chrono::steady_clock::now() + 30s;
  while (std::chrono::steady_clock::now() < end) {
    const runtime::Status st = c.status();
    if (st.state == s && !st.resetting && (!hold_complete || st.hold_complete)) return true;
    std::this_thread::sleep_for(1ms);
  }
  return false;
}

runtime::ControllerOptions controller_options() {
  runtime::ControllerOptions o;
  o.realtime = false;
  o.sample_ring = 0;
  return o;
}

TEST(Shdr, TimestampsAndLinesHaveTheProtocolsForm) {
  using namespace std::chrono;
  const system_clock::time_point t = sys_days{2026y / 12 / 1} + 19h + 58min + 43s + 123ms;
  EXPECT_EQ(telemetry::shdr_timestamp(t), "2026-12-01T19:58:43.123Z");
  const telemetry::ShdrItem x{"Xact", {"1.500"}}, mode{"mode", {"AUTOMATIC"}};
  const telemetry::ShdrItem fault{"system", {"FAULT", "3", "", "", "emergency stop"}};
  EXPECT_EQ(telemetry::shdr_lines("T", {&x, &fault, &mode}),
            (std::vector<std::string>{"T|Xact|1.500|mode|AUTOMATIC",
                                      "T|system|FAULT|3|||emergency stop"}));
}

TEST(Shdr, AgentReadsAServedProgramHoldEStopAndHeartbeat) {
  const MachineConfig machine = default_machine_config();
  runtime::Controller controller(machine, controller_options());
  telemetry::ShdrOptions options;
  options.address = "127.0.0.1:0";
  options.sample_hz = 50;
  options.heartbeat_ms = 2500;
  telemetry::ShdrAdapter adapter(controller, options);
  ASSERT_GT(adapter.port(), 0);
  ShdrClient agent(adapter.port());
  ASSERT_TRUE(agent.connected());
  ASSERT_TRUE(agent.wait_line("20"));  // the snapshot
  agent.send_line("* PING");
  ASSERT_TRUE(agent.wait_line("* PONG "));

  const std::string program =
      write_program("square.ngc", "G21 G90\nG1 X60 F3000\nG1 Y40\nG1 X0 Y0\nM30\n");
  ASSERT_TRUE(controller.load_program(program).ok);
  adapter.set_program("square.ngc");
  ASSERT_TRUE(controller.cycle_start().ok);
  std::this_thread::sleep_for(400ms);
  ASSERT_TRUE(controller.feed_hold().ok);
  ASSERT_TRUE(wait_for(controller, MachineState::kHold, true));
  std::this_thread::sleep_for(200ms);
  ASSERT_TRUE(controller.set_feed_override(150).ok);
  ASSERT_TRUE(controller.cycle_start().ok);
  ASSERT_TRUE(wait_for(controller, MachineState::kIdle));
  std::this_thread::sleep_for(200ms);
  ASSERT_TRUE(controller.estop().ok);
  std::this_thread::sleep_for(200ms);
  ASSERT_TRUE(controller.clear_alarm().ok);
  std::this_thread::sleep_for(200ms);
  agent.send_line("* PING");
  std::this_thread::sleep_for(200ms);

  const std::vector<std::string> lines = agent.lines();
  std::vector<Change> changes;
  check_protocol(lines, options.heartbeat_ms, changes);
  EXPECT_EQ(std::count(lines.begin(), lines.end(), "* PONG 2500"), 2);
  // The snapshot: every data item on connection.
  for (const char* key : {"avail", "estop", "mode", "execution", "program", "line", "Xact", "Yact",
                          "Zact", "path_feedrate", "Fovr", "Rovr", "Sload", "system"}) {
    EXPECT_FALSE(values_of(changes, key).empty()) << key;
  }
  EXPECT_TRUE(in_order(values_of(changes, "execution"),
                       {"READY", "ACTIVE", "FEED_HOLD", "ACTIVE", "READY", "STOPPED", "READY"}));
  EXPECT_TRUE(in_order(values_of(changes, "program"), {"UNAVAILABLE", "square.ngc"}));
  EXPECT_TRUE(in_order(values_of(changes, "line"), {"2", "3", "4"}));
  EXPECT_TRUE(in_order(values_of(changes, "Fovr"), {"100", "150"}));
  EXPECT_TRUE(in_order(values_of(changes, "estop"), {"ARMED", "TRIGGERED", "ARMED"}));
  const std::vector<std::string> system = values_of(changes, "system");
  ASSERT_GE(system.size(), 3U);
  EXPECT_EQ(system.front(), "NORMAL:");
  EXPECT_TRUE(system[1].starts_with("FAULT:")) << system[1];
  EXPECT_EQ(system.back(), "NORMAL:");
  // The tool went round the square: X reached 60 and Y 40, reported many times on the way.
  const std::vector<std::string> x = values_of(changes, "Xact");
  const std::vector<std::string> y = values_of(changes, "Yact");
  EXPECT_GT(x.size(), 20U);
  double x_max = 0, y_max = 0;
  for (const std::string& v : x) x_max = std::max(x_max, std::stod(v));
  for (const std::string& v : y) y_max = std::max(y_max, std::stod(v));
  // Polled at 50 Hz, the corners are seen within a sampling step of the slowed-down tool.
  EXPECT_NEAR(x_max, 60, 0.1);
  EXPECT_NEAR(y_max, 40, 0.1);
  // The path feed: up to 3000 mm/min = 50 mm/s, ×1.5 after the override.
  double feed_max = 0;
  for (const std::string& v : values_of(changes, "path_feedrate")) {
    feed_max = std::max(feed_max, std::stod(v));
  }
  EXPECT_GT(feed_max, 50.5);
  EXPECT_LE(feed_max, 75.01);
}

TEST(Shdr, WhatAnAgentSendsNeverMovesTheMachine) {
  runtime::Controller controller(default_machine_config(), controller_options());
  telemetry::ShdrOptions options;
  options.address = "127.0.0.1:0";
  telemetry::ShdrAdapter adapter(controller, options);
  ShdrClient agent(adapter.port());
  ASSERT_TRUE(agent.connected());
  const runtime::Status before = controller.status();
  for (const char* line : {"G1 X100 F5000", "cycle_start", "~", "$J=X10F100", "* PING"}) {
    agent.send_line(line);
  }
  ASSERT_TRUE(agent.wait_line("* PONG 10000"));
  std::this_thread::sleep_for(200ms);
  const runtime::Status after = controller.status();
  EXPECT_EQ(after.state, MachineState::kIdle);
  EXPECT_EQ(after.applied_commands, before.applied_commands);
  EXPECT_EQ(after.commanded, before.commanded);
}

TEST(Shdr, AnAddressInUseIsRefused) {
  runtime::Controller controller(default_machine_config(), controller_options());
  telemetry::ShdrOptions options;
  options.address = "127.0.0.1:0";
  telemetry::ShdrAdapter first(controller, options);
  options.address = "127.0.0.1:" + std::to_string(first.port());
  EXPECT_THROW(telemetry::ShdrAdapter(controller, options), std::runtime_error);
  options.address = "no-port";
  EXPECT_THROW(telemetry::ShdrAdapter(controller, options), std::runtime_error);
}

}  // namespace
