#include "app/serve_console.hpp"

#include <fmt/format.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <vector>

#include "app/cli_common.hpp"

namespace cncore::app {

namespace {

std::string reply(const runtime::Result& r) {
  return r.ok ? "ok" : "error: " + r.error;
}

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> w;
  for (std::string s; in >> s;) w.push_back(s);
  return w;
}

// jog [inc|abs|cont] X10 Y-5 F500: axis words and an optional feed.
std::string jog_command(runtime::Controller& c, const std::vector<std::string>& w) {
  runtime::JogRequest r;
  std::size_t i = 1;
  if (i < w.size() && (w[i] == "inc" || w[i] == "abs" || w[i] == "cont")) {
    r.incremental = w[i] != "abs";
    r.continuous = w[i] == "cont";
    ++i;
  }
  for (; i < w.size(); ++i) {
    const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(w[i][0])));
    const auto v = to_number(std::string_view(w[i]).substr(1));
    if (!v) return fmt::format("error: jog: '{}' is not an axis word like X10 or F500", w[i]);
    if (letter == 'F') {
      r.feed_mm_min = *v;
      continue;
    }
    std::size_t axis = kMaxAxes;
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (kAxisLetters[a] == letter) axis = a;
    }
    if (axis == kMaxAxes) return fmt::format("error: jog: '{}' names no axis", w[i]);
    r.target[axis] = *v;
    r.axes |= 1U << axis;
  }
  return reply(c.jog(r));
}

std::string wait_command(runtime::Controller& c, const std::vector<std::string>& w) {
  if (w.size() < 2) return "error: wait STATE [SECONDS]";
  const double seconds = w.size() > 2 ? to_number(w[2]).value_or(60) : 60;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    const runtime::Status s = c.status();
    if (runtime::state_name(s.state) == w[1] && !s.resetting) return "ok";
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return fmt::format("error: wait: still {} after {} s", runtime::state_name(c.status().state),
                     seconds);
}

std::string switches_command(runtime::Controller& c, const std::vector<std::string>& w) {
  runtime::Switches s = c.status().switches;
  for (std::size_t i = 1; i < w.size(); ++i) {
    const auto eq = w[i].find('=');
    const std::string key = w[i].substr(0, eq);
    const std::string val = eq == std::string::npos ? "" : w[i].substr(eq + 1);
    if (val != "on" && val != "off") return "error: switches: write KEY=on or KEY=off";
    const bool on = val == "on";
    if (key == "optional_stop") {
      s.optional_stop = on;
    } else if (key == "single_block") {
      s.single_block = on;
    } else if (key == "block_delete") {
      s.block_delete = on;
    } else {
      return fmt::format(
          "error: switches: no switch '{}' (optional_stop, single_block, block_delete)", key);
    }
  }
  return reply(c.set_switches(s));
}

std::string percent_command(const std::vector<std::string>& w, auto&& set) {
  const auto v = w.size() == 2 ? to_number(w[1]) : std::nullopt;
  if (!v) return fmt::format("error: {} PERCENT", w[0]);
  return reply(set(*v));
}

}  // namespace

std::string status_json(const runtime::Status& s, const MachineConfig& machine) {
  nlohmann::json j;
  j["state"] = runtime::state_name(s.state);
  j["hold_complete"] = s.hold_complete;
  j["alarm"] = s.alarm == runtime::AlarmCode::kNone ? "" : runtime::alarm_text(s.alarm);
  j["alarm_line"] = s.alarm_line;
  j["homed"] = s.homed;
  j["cycle"] = s.cycle;
  j["line"] = s.line;
  j["feed_mm_min"] = s.feed_mm_min;
  j["feed_override_pct"] = s.feed_override_pct;
  j["rapid_override_pct"] = s.rapid_override_pct;
  j["following_error_mm"] = s.following_error_mm;
  j["overruns"] = s.overruns;
  j["starved_cycles"] = s.starved_cycles;
  j["cycle_work_max_us"] = s.cycle_work_max_us;
  j["load_pct"] = s.load_pct;
  j["cutting_lag_cycles"] = s.cutting_lag_cycles;
  j["cutting_coalesced"] = s.cutting_coalesced;
  nlohmann::json mpos = nlohmann::json::object();
  nlohmann::json wco = nlohmann::json::object();
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!machine.axes[a].enabled) continue;
    const std::string name(1, static_cast<char>(std::tolower(kAxisLetters[a])));
    mpos[name] = s.commanded[a];
    wco[name] = s.work_offset[a];
  }
  j["machine_position"] = mpos;
  j["work_offset"] = wco;
  return j.dump();
}

std::string console_command(runtime::Controller& c, const std::string& line, bool& quit) {
  const std::vector<std::string> w = words(line);
  if (w.empty() || w[0][0] == '#') return {};
  const std::string& cmd = w[0];
  if (cmd == "quit" || cmd == "exit") {
    quit = true;
    return "ok";
  }
  if (cmd == "status") return status_json(c.status(), c.machine());
  if (cmd == "load") {
    if (w.size() != 2) return "error: load FILE";
    return reply(c.load_program(w[1]));
  }
  if (cmd == "start" || cmd == "resume") return reply(c.cycle_start());
  if (cmd == "hold") return reply(c.feed_hold());
  if (cmd == "reset" && w.size() == 2 && w[1] == "stock") return reply(c.reset_stock());
  if (cmd == "reset") return reply(c.reset());
  if (cmd == "estop") return reply(c.estop());
  if (cmd == "unlock") return reply(c.clear_alarm());
  if (cmd == "home") return reply(c.home());
  if (cmd == "jog") return jog_command(c, w);
  if (cmd == "jog-cancel") return reply(c.jog_cancel());
  if (cmd == "mdi") {
    const auto at = line.find("mdi");
    return reply(c.mdi(trim(line.substr(at + 3))));
  }
  if (cmd == "feed") return percent_command(w, [&](double v) { return c.set_feed_override(v); });
  if (cmd == "rapid") return percent_command(w, [&](double v) { return c.set_rapid_override(v); });
  if (cmd == "switches") return switches_command(c, w);
  if (cmd == "check") {
    if (w.size() != 2 || (w[1] != "on" && w[1] != "off")) return "error: check on|off";
    return reply(c.set_check_mode(w[1] == "on"));
  }
  if (cmd == "wait") return wait_command(c, w);
  return fmt::format(
      "error: unknown command '{}' (load, start, hold, resume, reset, estop, unlock, home, jog, "
      "jog-cancel, mdi, feed, rapid, switches, check, status, wait, quit)",
      cmd);
}

}  // namespace cncore::app
