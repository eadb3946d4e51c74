// Shop-floor telemetry of `cncore serve` (docs/telemetry.md): front ends that read the
// controller's published status and never command it.
//
// The MTConnect adapter speaks SHDR, the line protocol MTConnect agents read over TCP: one line
// per change, `TIMESTAMP|key|value|key|value…`, conditions on lines of their own
// (`TIMESTAMP|system|FAULT|CODE||QUALIFIER|TEXT`), and `* PING` answered by `* PONG <ms>`.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
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

}  // namespace cncore::telemetry
