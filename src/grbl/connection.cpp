#include "grbl/connection.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cstdio>
#include <fstream>

#include "grbl/codes.hpp"
#include "grbl/status_report.hpp"

namespace cncore::grbl {

namespace {

using runtime::MachineState;

constexpr unsigned char kSoftReset = 0x18;
constexpr unsigned char kSafetyDoor = 0x84;
constexpr unsigned char kJogCancel = 0x85;

void line_out(std::string& out, std::string_view text) {
  out.append(text);
  out.append("\r\n");
}

void error_out(std::string& out, Error e) {
  out += fmt::format("error:{}\r\n", static_cast<int>(e));
}

// Grbl strips spaces and upper-cases what it parses; comments go to cncore's interpreter as is.
std::string compact_upper(std::string_view s) {
  std::string r;
  for (const char c : s) {
    if (c == ' ' || c == '\t') continue;
    r += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  return r;
}

std::optional<double> number(std::string_view s) {
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

bool moving(MachineState s) {
  return s == MachineState::kRun || s == MachineState::kHold || s == MachineState::kJog ||
         s == MachineState::kHoming;
}

}  // namespace

void SettingsStore::save() const {
  if (path.empty()) return;
  const std::string temp = path + ".tmp";
  {
    std::ofstream f(temp, std::ios::trunc);
    f << settings.to_json() << "\n";
    if (!f.flush()) return;
  }
  std::rename(temp.c_str(), path.c_str());
}

Connection::Connection(runtime::Controller& controller, SettingsStore& store)
    : controller_(controller), store_(store) {}

void Connection::connect(std::string& out) {
  out += "\r\n";
  line_out(out, kWelcome);
  last_alarm_ = controller_.status().alarm;
  if (last_alarm_ != runtime::AlarmCode::kNone) {
    line_out(out, "[MSG:'$H'|'$X' to unlock]");
  }
  startup_due_ = true;
}

void Connection::receive(std::string_view bytes, std::string& out) {
  for (const char ch : bytes) {
    const auto b = static_cast<unsigned char>(ch);
    if (b == '?' || b == '!' || b == '~' || b >= 0x80 || b == kSoftReset) {
      realtime(b, out);
      continue;
    }
    if (discard_line_) {
      if (b == '\n' || b == '\r') discard_line_ = false;
      continue;
    }
    rx_ += ch;
  }
  poll(out);
}

void Connection::realtime(unsigned char b, std::string& out) {
  const runtime::Status s = controller_.status();
  switch (b) {
    case '?':
      report_status(out);
      return;
    case '!':
      if (s.state == MachineState::kRun) (void)controller_.feed_hold();
      if (s.state == MachineState::kJog) (void)controller_.jog_cancel();
      return;
    case '~':
      door_ = false;
      if (s.state == MachineState::kHold) (void)controller_.cycle_start();
      return;
    case kSoftReset:
      soft_reset(out);
      return;
    case kSafetyDoor:
      door_ = true;
      if (s.state == MachineState::kRun) (void)controller_.feed_hold();
      if (s.state == MachineState::kJog) (void)controller_.jog_cancel();
      return;
    case kJogCancel:
      if (s.state == MachineState::kJog) (void)controller_.jog_cancel();
      return;
    default:
      overrides(b);
      return;
  }
}

void Connection::overrides(unsigned char b) {
  const runtime::Status s = controller_.status();
  const double max_feed = controller_.machine().max_override_pct;
  auto feed = [&](double pct) {
    (void)controller_.set_feed_override(std::clamp(pct, 10.0, std::min(200.0, max_feed)));
  };
  auto spindle = [&](int pct) { spindle_override_pct_ = std::clamp(pct, 10, 200); };
  switch (b) {
    case 0x90:
      feed(100);
      break;
    case 0x91:
      feed(s.feed_override_pct + 10);
      break;
    case 0x92:
      feed(s.feed_override_pct - 10);
      break;
    case 0x93:
      feed(s.feed_override_pct + 1);
      break;
    case 0x94:
      feed(s.feed_override_pct - 1);
      break;
    case 0x95:
      (void)controller_.set_rapid_override(100);
      break;
    case 0x96:
      (void)controller_.set_rapid_override(50);
      break;
    case 0x97:
      (void)controller_.set_rapid_override(25);
      break;
    case 0x99:
      spindle(100);
      break;
    case 0x9A:
      spindle(spindle_override_pct_ + 10);
      break;
    case 0x9B:
      spindle(spindle_override_pct_ - 10);
      break;
    case 0x9C:
      spindle(spindle_override_pct_ + 1);
      break;
    case 0x9D:
      spindle(spindle_override_pct_ - 1);
      break;
    default:
      break;  // other extended bytes (spindle stop, coolant toggles) are ignored
  }
}

void Connection::soft_reset(std::string& out) {
  const runtime::Status s = controller_.status();
  if (moving(s.state)) (void)controller_.reset();
  if (s.state == MachineState::kCheck) (void)controller_.set_check_mode(false);
  controller_.forget_modes();  // Grbl's parser starts afresh after a soft reset
  rx_.clear();
  discard_line_ = false;
  busy_ = homing_ = door_ = sleep_ = probing_ = false;
  connect(out);
}

void Connection::poll(std::string& out) {
  const runtime::Status s = controller_.status();
  if (s.alarm != last_alarm_) {
    last_alarm_ = s.alarm;
    if (s.alarm != runtime::AlarmCode::kNone) {
      out += fmt::format("ALARM:{}\r\n", alarm_number(s.alarm));
      line_out(out, fmt::format("[MSG:{}]", runtime::alarm_text(s.alarm)));
    }
  }
  if (homing_ && s.state != MachineState::kHoming) {
    homing_ = false;
    if (s.state == MachineState::kAlarm) {
      error_out(out, Error::kSystemGcLock);
    } else {
      line_out(out, "ok");
    }
  }
  if (probing_ && !moving(s.state) && !s.resetting) {
    probing_ = false;
    if (s.state == MachineState::kAlarm) {
      error_out(out, Error::kSystemGcLock);
    } else {
      last_probe_ = probe_report(s.commanded, probe_tripped_, controller_.machine());
      line_out(out, last_probe_);
      line_out(out, "ok");
    }
  }
  if (busy_ && !moving(s.state)) busy_ = false;
  if (startup_due_ && s.state == MachineState::kIdle && !s.resetting) run_startup(out);
  if (!busy_ && !homing_ && !probing_) {
    while (next_line(out)) {
    }
  }
}

void Connection::run_startup(std::string& out) {
  startup_due_ = false;
  for (const std::string& line : store_.settings.startup) {
    if (line.empty()) continue;
    const runtime::Result r = controller_.mdi(line);
    out += fmt::format(">{}:", line);
    if (r.ok) {
      line_out(out, "ok");
    } else {
      error_out(out, error_for(r.error));
    }
  }
}

bool Connection::next_line(std::string& out) {
  const std::size_t end = rx_.find_first_of("\r\n");
  if (end == std::string::npos) {
    if (rx_.size() >= kLineBytes) {  // no end in sight: drop it, answer once
      rx_.clear();
      discard_line_ = true;
      error_out(out, Error::kOverflow);
    }
    return false;
  }
  std::string line = rx_.substr(0, end);
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
  std::size_t start = 0;
  while (start < line.size() && std::isspace(static_cast<unsigned char>(line[start]))) ++start;
  line.erase(0, start);
  const std::size_t consumed = end + 1;
  if (line.empty()) {  // an empty line or the \n of a \r\n: nothing to answer
    rx_.erase(0, consumed);
    return true;
  }
  if (line.size() > kLineBytes) {
    rx_.erase(0, consumed);
    error_out(out, Error::kOverflow);
    return true;
  }
  const bool taken = line[0] == '$' ? dollar(line, out) : gcode(line, out);
  if (taken) rx_.erase(0, consumed);
  return taken && !busy_ && !homing_ && !probing_;
}

bool Connection::gcode(const std::string& line, std::string& out) {
  const runtime::Status s = controller_.status();
  if (s.resetting || door_ || startup_due_ || busy_) return false;
  if (sleep_ || s.state == MachineState::kAlarm) {
    error_out(out, Error::kSystemGcLock);
    return true;
  }
  // Grbl's `ok` means the line is parsed and in the planner: here, checked and queued into the
  // running stream (no room: the line waits in the receive buffer, which slows the sender).
  const runtime::StreamReply r = controller_.stream_line(line);
  if (r.outcome == runtime::StreamOutcome::kWait) return false;
  if (r.outcome == runtime::StreamOutcome::kRefused) {
    line_out(out, fmt::format("[MSG:{}]", r.error));
    error_out(out, error_for(r.error));
    return true;
  }
  if (const std::optional<bool> tripped = controller_.last_line_probe();
      tripped && s.state != MachineState::kCheck) {
    probing_ = true;
    probe_tripped_ = *tripped;
    return true;
  }
  line_out(out, "ok");
  return true;
}

bool Connection::dollar(const std::string& raw, std::string& out) {
  const std::string line = compact_upper(raw);
  const runtime::Status s = controller_.status();
  const bool idle_like = s.state == MachineState::kIdle || s.state == MachineState::kAlarm ||
                         s.state == MachineState::kCheck;
  if (line.starts_with("$J=")) {
    // Jogs queue behind a jog; G-code lines before them must have ended.
    if (busy_ || s.state == MachineState::kRun || s.state == MachineState::kHold) return false;
    jog(std::string_view(raw).substr(raw.find('=') + 1), out);
    return true;
  }
  if (line == "$") {
    line_out(out, "[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]");
    line_out(out, "ok");
    return true;
  }
  if (line == "$G") {
    line_out(out, gcode_modes(controller_.parser_state(), s));
    line_out(out, "ok");
    return true;
  }
  if (line == "$I" || line.starts_with("$I=")) {
    line_out(out, "[VER:1.1h.cncore:]");
    line_out(out, fmt::format("[OPT:V,{},{}]", controller_.stream_room().capacity, kRxBufferBytes));
    line_out(out, "ok");
    return true;
  }
  if (!idle_like || busy_) {
    if (moving(s.state) || busy_) return false;  // wait: Grbl runs these only when idle
  }
  if (line == "$$") {
    out += store_.settings.listing();
  } else if (line == "$#") {
    offsets(out);
  } else if (line == "$N") {
    for (std::size_t i = 0; i < 2; ++i)
      out += fmt::format("$N{}={}\r\n", i, store_.settings.startup[i]);
  } else if (line.starts_with("$N0=") || line.starts_with("$N1=")) {
    const std::size_t i = line[2] == '0' ? 0 : 1;
    store_.settings.startup[i] = std::string(raw.substr(raw.find('=') + 1));
    store_.save();
  } else if (line == "$C") {
    const bool on = s.state != MachineState::kCheck;
    const runtime::Result r = controller_.set_check_mode(on);
    if (!r.ok) {
      error_out(out, Error::kIdleError);
      return true;
    }
    line_out(out, on ? "[MSG:Enabled]" : "[MSG:Disabled]");
    if (!on) {  // Grbl leaves check mode through a soft reset
      line_out(out, "ok");
      soft_reset(out);
      return true;
    }
  } else if (line == "$X") {
    if (s.state == MachineState::kAlarm) {
      const runtime::Result r = controller_.clear_alarm();
      if (!r.ok) {
        line_out(out, fmt::format("[MSG:{}]", r.error));
        error_out(out, Error::kSystemGcLock);
        return true;
      }
      line_out(out, "[MSG:Caution: Unlocked]");
    }
  } else if (line == "$H") {
    const runtime::Result r = controller_.home();
    if (!r.ok) {
      line_out(out, fmt::format("[MSG:{}]", r.error));
      error_out(out, Error::kIdleError);
      return true;
    }
    homing_ = true;  // ok when homing ends
    return true;
  } else if (line == "$SLP") {
    sleep_ = true;
    line_out(out, "[MSG:Sleeping]");
  } else if (line.starts_with("$RST=")) {
    restore(std::string_view(line).substr(5), out);
    return true;
  } else if (line.size() > 1 && std::isdigit(static_cast<unsigned char>(line[1])) != 0) {
    write_setting(line, out);
    return true;
  } else {
    error_out(out, Error::kInvalidStatement);
    return true;
  }
  line_out(out, "ok");
  return true;
}

void Connection::write_setting(std::string_view line, std::string& out) {
  const std::size_t eq = line.find('=');
  if (eq == std::string_view::npos) {
    error_out(out, Error::kInvalidStatement);
    return;
  }
  int n = 0;
  const auto key = line.substr(1, eq - 1);
  if (std::from_chars(key.data(), key.data() + key.size(), n).ec != std::errc()) {
    error_out(out, Error::kInvalidStatement);
    return;
  }
  const auto v = number(line.substr(eq + 1));
  if (!v) {
    error_out(out, Error::kBadNumberFormat);
    return;
  }
  // As Grbl: settings change only while nothing moves, and then at once.
  if (busy_ || moving(controller_.status().state)) {
    error_out(out, Error::kIdleError);
    return;
  }
  Settings next = store_.settings;
  if (const auto e = next.write(n, *v)) {
    error_out(out, static_cast<Error>(*e));
    return;
  }
  if (adopt(next, out)) line_out(out, "ok");
}

bool Connection::adopt(const Settings& next, std::string& out) {
  const runtime::MachineLimits now = controller_.limits();
  MachineConfig m = controller_.machine();
  runtime::apply_limits(m, now);
  next.apply(m);
  if (const runtime::MachineLimits wanted = runtime::limits_of(m); wanted != now) {
    if (const runtime::Result r = controller_.set_limits(wanted); !r.ok) {
      line_out(out, "[MSG:" + r.error + "]");
      error_out(out,
                moving(controller_.status().state) ? Error::kIdleError : Error::kInvalidStatement);
      return false;
    }
  }
  store_.settings = next;
  store_.save();
  return true;
}

void Connection::restore(std::string_view what, std::string& out) {
  if (what != "$" && what != "#" && what != "*") {
    error_out(out, Error::kInvalidStatement);
    return;
  }
  if (busy_ || moving(controller_.status().state)) {
    error_out(out, Error::kIdleError);
    return;
  }
  if (what == "$" || what == "*") {
    Settings next = store_.defaults;
    if (what == "$") next.startup = store_.settings.startup;
    if (!adopt(next, out)) return;
  }
  if (what == "#" || what == "*") {
    // The work offsets G54…G59.3 and G92 through cncore's own interpreter.
    std::string clear = "G92.1\n";
    for (int p = 1; p <= 9; ++p) clear += fmt::format("G10 L2 P{} X0 Y0 Z0\n", p);
    const runtime::Result r = controller_.mdi(clear);
    if (!r.ok) {
      line_out(out, fmt::format("[MSG:{}]", r.error));
      error_out(out, Error::kIdleError);
      return;
    }
    busy_ = true;
  }
  line_out(out, "ok");
}

void Connection::jog(std::string_view body, std::string& out) {
  const std::string w = compact_upper(body);
  runtime::JogRequest r;
  bool absolute_work = true;  // G90 (Grbl's default for $J) in work coordinates
  bool machine_coords = false;
  double scale = 1;
  bool has_feed = false;
  std::size_t i = 0;
  while (i < w.size()) {
    const char letter = w[i++];
    std::size_t j = i;
    while (j < w.size() && (std::isdigit(static_cast<unsigned char>(w[j])) != 0 || w[j] == '.' ||
                            w[j] == '-' || w[j] == '+')) {
      ++j;
    }
    const auto v = number(w.substr(i, j - i));
    i = j;
    if (!v) {
      error_out(out, Error::kBadNumberFormat);
      return;
    }
    if (letter == 'G') {
      if (*v == 90)
        absolute_work = true;
      else if (*v == 91)
        absolute_work = false;
      else if (*v == 53)
        machine_coords = true;
      else if (*v == 20)
        scale = 25.4;
      else if (*v == 21)
        scale = 1;
      else {
        error_out(out, Error::kInvalidJogCommand);
        return;
      }
      continue;
    }
    if (letter == 'F') {
      r.feed_mm_min = *v;
      has_feed = true;
      continue;
    }
    std::size_t axis = kMaxAxes;
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (kAxisLetters[a] == letter) axis = a;
    }
    if (axis == kMaxAxes) {
      error_out(out, Error::kInvalidJogCommand);
      return;
    }
    r.target[axis] = *v;
    r.axes |= 1U << axis;
  }
  if (!has_feed || r.feed_mm_min <= 0) {
    error_out(out, Error::kUndefinedFeedRate);
    return;
  }
  r.feed_mm_min *= scale;
  const runtime::Status s = controller_.status();
  const runtime::MachineLimits limits = controller_.limits();
  r.incremental = !absolute_work && !machine_coords;
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (((r.axes >> a) & 1U) == 0) continue;
    r.target[a] *= scale;
    if (!r.incremental && !machine_coords) r.target[a] += s.work_offset[a];
    const double end = r.incremental ? s.commanded[a] + r.target[a] : r.target[a];
    const bool enabled = controller_.machine().axes[a].enabled;
    if (enabled && (end < limits.min_mm[a] - 1e-9 || end > limits.max_mm[a] + 1e-9)) {
      error_out(out, Error::kTravelExceeded);
      return;
    }
  }
  const runtime::Result res = controller_.jog(r);
  if (!res.ok) {
    line_out(out, fmt::format("[MSG:{}]", res.error));
    error_out(out, s.state == MachineState::kAlarm ? Error::kSystemGcLock : Error::kIdleError);
    return;
  }
  line_out(out, "ok");
}

void Connection::offsets(std::string& out) const {
  const runtime::Status s = controller_.status();
  // cncore reports the active offset (G54…G59.3 + G92) as one; it is shown as G54.
  out += fmt::format("[G54:{:.3f},{:.3f},{:.3f}]\r\n", s.work_offset[0], s.work_offset[1],
                     s.work_offset[2]);
  for (const char* g : {"G55", "G56", "G57", "G58", "G59", "G28", "G30", "G92"}) {
    out += fmt::format("[{}:0.000,0.000,0.000]\r\n", g);
  }
  line_out(out, "[TLO:0.000]");
  line_out(out, last_probe_);
}

void Connection::report_status(std::string& out) {
  const runtime::Status s = controller_.status();
  ReportInputs in;
  in.door = door_;
  in.sleep = sleep_;
  in.mask = store_.settings.status_mask();
  in.planner_blocks_free = static_cast<int>(controller_.stream_room().free_lines);
  in.rx_bytes_free =
      static_cast<int>(kRxBufferBytes - std::min<std::size_t>(rx_.size(), kRxBufferBytes));
  in.line = moving(s.state) ? s.line : 0;
  in.spindle_override_pct = spindle_override_pct_;
  const bool wco_changed = s.work_offset.v != last_wco_.v;
  const bool ov_changed = last_ov_[0] != s.feed_override_pct ||
                          last_ov_[1] != s.rapid_override_pct ||
                          last_ov_[2] != spindle_override_pct_;
  in.with_wco = wco_changed || reports_ % 10 == 0;
  in.with_overrides = ov_changed || reports_ % 10 == 1;
  last_wco_ = s.work_offset;
  last_ov_[0] = s.feed_override_pct;
  last_ov_[1] = s.rapid_override_pct;
  last_ov_[2] = spindle_override_pct_;
  ++reports_;
  line_out(out, status_report(s, controller_.machine(), in));
}

}  // namespace cncore::grbl
