// The Grbl 1.1 protocol for one connected sender, without sockets: bytes in, reply text out,
// commands to runtime::Controller. The transports (endpoint.hpp) only move bytes.
//
// What a Grbl board does and this connection reproduces:
// - real-time bytes (? ! ~ 0x18 0x84 0x85 0x90–0x9D) are taken out of the stream wherever they
//   appear and acted on at once, also when the receive buffer is full;
// - the other bytes form lines in a 128-byte receive buffer (what character-counting senders
//   count); each line is answered by exactly one `ok` or `error:N`, in order;
// - a probe line (G38.2 … G38.5) is answered once its move has ended: `[PRB:x,y,z:t]` (machine
//   coordinates of the trip point, t = 1 when the simulated probe tripped) and `ok`;
// - a G-code line is checked by cncore's interpreter and queued into one running stream job
//   (runtime::Controller::stream_line), so the look-ahead plans across the lines; `ok` when it
//   is queued, as Grbl answers when a line is in its planner. While the queue is full the line
//   stays in the receive buffer, so a sender that keeps sending is slowed by the buffer (Bf: in
//   the status report) and never has a line dropped or mixed.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <string_view>

#include "grbl/settings.hpp"
#include "runtime/control.hpp"

namespace cncore::grbl {

inline constexpr std::size_t kRxBufferBytes = 128;  // Grbl's serial receive buffer
inline constexpr std::size_t kLineBytes = 256;      // longest line (grblHAL's line buffer)

// Settings and startup lines shared by the connections of one process, with where they persist.
struct SettingsStore {
  Settings settings;
  Settings defaults;  // the machine configuration's values, before any write: what $RST=$ restores
  std::string path;   // the state folder's grbl.json; empty: not kept
  void save() const;  // temp file + rename
};

class Connection {
 public:
  Connection(runtime::Controller& controller, SettingsStore& store);

  // A sender connected: the welcome line (and the startup lines once the machine is idle).
  void connect(std::string& out);
  // Bytes from the sender; replies are appended to `out`.
  void receive(std::string_view bytes, std::string& out);
  // Called every few milliseconds: runs the next buffered line when the machine can take it,
  // completes $H, reports alarms as they arise.
  void poll(std::string& out);
  // Bytes received and not yet taken as lines (beyond kRxBufferBytes the transport stops reading).
  std::size_t buffered_bytes() const { return rx_.size(); }

  static constexpr std::string_view kWelcome = "Grbl 1.1h ['$' for help]";

 private:
  void realtime(unsigned char byte, std::string& out);
  void soft_reset(std::string& out);
  // Takes the next line from the receive buffer if it can be answered now; false: it waits.
  bool next_line(std::string& out);
  bool dollar(const std::string& line, std::string& out);  // false: must wait for Idle
  bool gcode(const std::string& line, std::string& out);   // false: must wait for the machine
  void jog(std::string_view body, std::string& out);
  void write_setting(std::string_view line, std::string& out);
  // Makes `next` the settings and puts their limits into the machine; false (reply written) when
  // the machine refuses them.
  bool adopt(const Settings& next, std::string& out);
  void restore(std::string_view what, std::string& out);
  void report_status(std::string& out);
  void offsets(std::string& out) const;
  void run_startup(std::string& out);
  void overrides(unsigned char byte);

  runtime::Controller& controller_;
  SettingsStore& store_;
  std::string rx_;       // bytes not yet taken as lines (real-time bytes removed)
  bool busy_ = false;    // a $RST=# job has not ended yet
  bool homing_ = false;  // $H answered once homing ends
  // A G38.x line: answered ([PRB:…] and ok) once its move has ended, as Grbl answers a probe
  // cycle; the lines after it wait.
  bool probing_ = false;
  bool probe_tripped_ = false;
  std::string last_probe_ = "[PRB:0.000,0.000,0.000:0]";
  bool door_ = false;   // safety door opened (0x84) and not yet resumed
  bool sleep_ = false;  // $SLP until soft reset
  bool startup_due_ = false;
  bool discard_line_ = false;  // an overlong line is being skipped to its end
  runtime::AlarmCode last_alarm_ = runtime::AlarmCode::kNone;
  int spindle_override_pct_ = 100;
  int reports_ = 0;
  AxisVec last_wco_;
  double last_ov_[3] = {-1, -1, -1};
};

}  // namespace cncore::grbl
