// Shop-floor telemetry of `cncore serve` (docs/telemetry.md): front ends that read the
// controller's published status and never command it.
//
// The MQTT publisher sends JSON messages to a broker under a topic prefix: retained birth / last
// will, state, program and alarm; cycle start / end events; samples at a fixed rate. It
// subscribes to nothing.
//
// The MTConnect adapter speaks SHDR, the line protocol MTConnect agents read over TCP: one line
// per change, `TIMESTAMP|key|value|key|value…`, conditions on lines of their own
// (`TIMESTAMP|system|FAULT|CODE||QUALIFIER|TEXT`), and `* PING` answered by `* PONG <ms>`.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "runtime/control.hpp"

namespace cncore::telemetry {

// One data item as SHDR carries it: its key and its fields (one for a sample or event, five for
// a condition: level, native code, native severity, qualifier, message).
struct ShdrItem {
  std::string key;
  std::vector<std::string> fields;
  bool condition() const { return fields.size() > 1; }
};

// MTConnect's Execution (READY, ACTIVE, FEED_HOLD, STOPPED, INTERRUPTED) and ControllerMode
// (AUTOMATIC, SEMI_AUTOMATIC, MANUAL, EDIT) of a status; the MQTT state says the same.
std::string execution_name(const runtime::Status& status);
std::string controller_mode_name(const runtime::Status& status);

// The data items of a 3-axis mill for one status (docs/telemetry.md lists them). `program`: the
// program's name as the adapter knows it ("" : UNAVAILABLE).
std::vector<ShdrItem> mtconnect_items(const runtime::Status& status, const std::string& program);

// "2026-12-01T19:58:43.123Z" (UTC, milliseconds), the SHDR timestamp.
std::string shdr_timestamp(std::chrono::system_clock::time_point t);

// The SHDR lines for the items: samples and events joined on one line, each condition on its own.
std::vector<std::string> shdr_lines(const std::string& timestamp,
                                    const std::vector<const ShdrItem*>& items);

struct ShdrOptions {
  std::string address = "127.0.0.1:7878";  // HOST:PORT to listen on (port 0: any free port)
  double sample_hz = 10;                   // status polls per second; lines only on change
  std::uint32_t heartbeat_ms = 10000;      // announced in `* PONG <ms>`
};

// The SHDR server: a thread that accepts agents, sends each a full snapshot on connection and the
// changed items at every poll after that, and answers their heartbeats. Reads the controller
// only.
class ShdrAdapter {
 public:
  // Listens at once; throws std::runtime_error when the address cannot be bound.
  ShdrAdapter(const runtime::Controller& controller, ShdrOptions options);
  ~ShdrAdapter();
  ShdrAdapter(const ShdrAdapter&) = delete;
  ShdrAdapter& operator=(const ShdrAdapter&) = delete;

  std::uint16_t port() const;  // the bound port
  // The name the `program` item reports (the front end that loads programs knows it).
  void set_program(const std::string& name);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---- MQTT ----

// Where `--mqtt` publishes: mqtt://HOST[:PORT]/PREFIX (port 1883) or mqtts://… (TLS, port 8883).
struct MqttTarget {
  bool tls = false;
  std::string host;
  std::uint16_t port = 0;
  std::string prefix;  // topics are PREFIX/online, PREFIX/state, … (no leading or trailing '/')
  std::string server_uri() const;  // tcp://HOST:PORT or ssl://HOST:PORT, as Paho takes it
};
// Throws std::runtime_error saying what is wrong with the URL.
MqttTarget parse_mqtt_url(const std::string& url);

// One message as it goes to the broker. QoS 1 and retained for what a dashboard must not miss
// (birth, state, program, alarm) or must see once (cycle events); QoS 0 for the samples.
struct MqttMessage {
  std::string topic;
  std::string payload;  // JSON
  int qos = 0;
  bool retain = false;
};

// Turns successive statuses into messages (no I/O: the publisher's thread calls it; tests feed it
// statuses). Topics and payloads are listed in docs/telemetry.md.
class MqttTopics {
 public:
  MqttTopics(std::string prefix, const MachineConfig& machine);
  using Clock = std::chrono::system_clock;

  // The retained messages that describe the controller now: online, program, state, alarm. Sent
  // after every (re)connection; the events below then report only later changes. A job running
  // at the first status either call sees is not reported.
  std::vector<MqttMessage> birth(const runtime::Status& s, const std::string& program,
                                 Clock::time_point now);
  // What happened since the previous call, in order: cycle start, cycle end, program, alarm,
  // state. Call it for every status read, connected or not, so no cycle is counted twice.
  std::vector<MqttMessage> events(const runtime::Status& s, const std::string& program,
                                  Clock::time_point now);
  // The fast sample: line, positions, feed, overrides, spindle load; `dropped`: messages not
  // sent so far (queue full or broker away).
  MqttMessage sample(const runtime::Status& s, std::uint64_t dropped, Clock::time_point now) const;
  // online = false: `will` for the last will the broker sends when the connection dies, else a
  // clean shutdown.
  MqttMessage offline(bool will) const;

 private:
  std::string topic(const char* leaf) const { return prefix_ + "/" + leaf; }
  MqttMessage state_message(const runtime::Status& s, Clock::time_point now);
  MqttMessage alarm_message(const runtime::Status& s, Clock::time_point now);
  MqttMessage program_message(const std::string& program, Clock::time_point now);
  void baseline(const runtime::Status& s);  // the first status seen
  void cycle_events(const runtime::Status& s, const std::string& program, Clock::time_point now,
                    std::vector<MqttMessage>& out);

  std::string prefix_;
  const MachineConfig& machine_;
  std::string last_state_, last_alarm_, last_program_;  // compared without their timestamps
  std::uint64_t started_job_ = 0;                       // the job whose start was reported
  std::uint64_t ended_job_ = 0;                         // the job whose end was reported
  std::string job_program_;                             // the program name its start reported
  bool first_ = true;
};

struct MqttOptions {
  std::string url;                // mqtt://HOST:PORT/PREFIX or mqtts://…
  std::string user;               // empty: no user name
  std::string password;           // the contents of --mqtt-password-file
  std::string ca_file;            // mqtts: the CAs that sign the broker's certificate (empty:
                                  // the system's)
  double sample_hz = 10;          // samples per second, (0, 100]
  std::string client_id;          // empty: cncore-<prefix>
  std::string program;            // the program loaded at start (set_program() later ones)
  std::size_t max_pending = 256;  // messages handed to Paho and not yet sent; more are dropped
  std::chrono::milliseconds connect_timeout{5000};
};

// What the publisher did so far.
struct MqttCounters {
  std::uint64_t published = 0;  // messages the client library took
  std::uint64_t dropped = 0;    // messages not sent: queue full, or no connection
  bool connected = false;
};

// The publisher: a thread that reads the controller's status 100 times a second for events and
// sends samples at the sample rate, over Eclipse Paho's asynchronous client. A broker that is
// down or slow costs dropped messages, never a wait: at most `max_pending` messages are queued.
// Nothing it receives reaches the controller (it subscribes to nothing).
class MqttPublisher {
 public:
  // Connects first (waits up to connect_timeout). Throws std::runtime_error when the URL or
  // options are wrong, the broker refuses the login or the TLS handshake fails; a broker that
  // does not answer is tried again in the background (a message says so).
  MqttPublisher(const runtime::Controller& controller, MqttOptions options);
  // Publishes online = false (retained) and disconnects.
  ~MqttPublisher();
  MqttPublisher(const MqttPublisher&) = delete;
  MqttPublisher& operator=(const MqttPublisher&) = delete;

  void set_program(const std::string& name);
  MqttCounters counters() const;
  // News for the operator (connected, connection lost, login refused), each taken once.
  std::optional<std::string> take_message();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cncore::telemetry
