#include "hmi/api.hpp"

#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "hmi/program_view.hpp"

namespace cncore::hmi {

namespace {

using nlohmann::json;

json axes_json(const AxisVec& v, const MachineConfig& machine) {
  json j = json::object();
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!machine.axes[a].enabled) continue;
    j[std::string(1, static_cast<char>(std::tolower(kAxisLetters[a])))] = v[a];
  }
  return j;
}

double number_or(const json& j, const char* key, double fallback) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : fallback;
}

// {"mode":"inc"|"abs"|"cont","axes":{"x":10,"y":-5},"feed_mm_min":500}
Reply jog(runtime::Controller& c, const json& j) {
  runtime::JogRequest r;
  const std::string mode = j.value("mode", "inc");
  if (mode != "inc" && mode != "abs" && mode != "cont") {
    return bad_request("jog: mode must be inc, abs or cont");
  }
  r.incremental = mode != "abs";
  r.continuous = mode == "cont";
  r.feed_mm_min = number_or(j, "feed_mm_min", 0);
  const auto axes = j.find("axes");
  if (axes == j.end() || !axes->is_object()) return bad_request("jog: no axes");
  for (const auto& [key, value] : axes->items()) {
    std::size_t axis = kMaxAxes;
    for (std::size_t a = 0; a < kMaxAxes; ++a) {
      if (key.size() == 1 && std::toupper(static_cast<unsigned char>(key[0])) == kAxisLetters[a]) {
        axis = a;
      }
    }
    if (axis == kMaxAxes || !value.is_number()) {
      return bad_request("jog: '" + key + "' is not an axis with a number");
    }
    r.target[axis] = value.get<double>();
    r.axes |= 1U << axis;
  }
  return reply_of(c.jog(r));
}

Reply overrides(runtime::Controller& c, const json& j) {
  if (!j.contains("feed_pct") && !j.contains("rapid_pct")) {
    return bad_request("override: give feed_pct and/or rapid_pct");
  }
  if (j.contains("feed_pct")) {
    Reply r = reply_of(c.set_feed_override(number_or(j, "feed_pct", NAN)));
    if (r.http_status != 200) return r;
  }
  if (j.contains("rapid_pct")) {
    return reply_of(c.set_rapid_override(number_or(j, "rapid_pct", NAN)));
  }
  return reply_of({});
}

Reply switches(runtime::Controller& c, const json& j) {
  runtime::Switches s = c.status().switches;
  s.optional_stop = j.value("optional_stop", s.optional_stop);
  s.single_block = j.value("single_block", s.single_block);
  s.block_delete = j.value("block_delete", s.block_delete);
  return reply_of(c.set_switches(s));
}

}  // namespace

Reply reply_of(const runtime::Result& r) {
  if (r.ok) return {200, R"({"ok":true})"};
  return {409, json{{"ok", false}, {"error", r.error}}.dump()};
}

Reply bad_request(const std::string& why) {
  return {400, json{{"ok", false}, {"error", why}}.dump()};
}

std::string status_event_json(const runtime::Status& s, const MachineConfig& machine,
                              const ProgramView* view, double time_s) {
  json j;
  j["t"] = time_s;
  j["state"] = runtime::state_name(s.state);
  j["hold_complete"] = s.hold_complete;
  j["resetting"] = s.resetting;
  j["alarm"] = s.alarm == runtime::AlarmCode::kNone ? "" : runtime::alarm_text(s.alarm);
  j["alarm_line"] = s.alarm_line;
  j["homed"] = s.homed;
  j["program_loaded"] = s.program_loaded;
  j["check_mode"] = s.check_mode;
  j["cycle"] = s.cycle;
  j["job"] = s.job;
  j["line"] = s.line;
  j["machine"] = axes_json(s.commanded, machine);
  j["work"] = axes_json(s.commanded - s.work_offset, machine);
  j["actual"] = axes_json(s.actual, machine);
  j["work_offset"] = axes_json(s.work_offset, machine);
  j["feed_mm_min"] = s.feed_mm_min;
  j["programmed_feed_mm_min"] = view != nullptr && s.line != 0 ? view->feed_at_line(s.line) : 0.0;
  j["feed_override_pct"] = s.feed_override_pct;
  j["rapid_override_pct"] = s.rapid_override_pct;
  j["spindle_rpm"] = s.spindle_rpm;
  j["spindle_on"] = s.spindle_on;
  j["tool"] = s.tool;
  j["load_pct"] = s.load_pct;
  j["following_error_mm"] = s.following_error_mm;
  j["switches"] = {{"optional_stop", s.switches.optional_stop},
                   {"single_block", s.switches.single_block},
                   {"block_delete", s.switches.block_delete}};
  j["overruns"] = s.overruns;
  j["cutting_lag_cycles"] = s.cutting_lag_cycles;
  j["cutting_coalesced"] = s.cutting_coalesced;
  return j.dump();
}

std::string machine_json(const MachineConfig& machine) {
  json axes = json::array();
  for (std::size_t a = 0; a < kMaxAxes; ++a) {
    if (!machine.axes[a].enabled) continue;
    axes.push_back({{"name", std::string(1, kAxisLetters[a])},
                    {"min_mm", machine.axes[a].min_mm},
                    {"max_mm", machine.axes[a].max_mm}});
  }
  json stock = nullptr;
  if (machine.cutting.stock.enabled) {
    stock = {{"min_mm", machine.cutting.stock.min_mm}, {"size_mm", machine.cutting.stock.size_mm}};
  }
  json j{{"name", machine.name},
         {"stock", stock},
         {"axes", axes},
         {"max_feed_mm_min", machine.max_feed_mm_min},
         {"rapid_mm_min", machine.rapid_mm_min},
         {"max_override_pct", machine.max_override_pct},
         {"load_target_pct", machine.adaptive.target_load_pct},
         {"jog_feed_mm_min", machine.servo.jog_feed_mm_min}};
  return j.dump();
}

std::string heightmap_binary(const runtime::HeightMapGrid& g) {
  // "CNCZMAP1", u32 nx, u32 ny, f64 x0, y0, cell, then the float32 heights (little-endian, as
  // the machines this runs on store them): 40 bytes of header keep the heights 4-byte aligned.
  std::string out("CNCZMAP1");
  auto put = [&out](const auto& v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);  // NOLINT: bytes of a number
  };
  put(static_cast<std::uint32_t>(g.nx));
  put(static_cast<std::uint32_t>(g.ny));
  put(g.x0_mm);
  put(g.y0_mm);
  put(g.cell_mm);
  out.append(reinterpret_cast<const char*>(g.heights_mm.data()),  // NOLINT: bytes of floats
             g.heights_mm.size() * sizeof(float));
  return out;
}

Reply control(runtime::Controller& c, std::string_view name, const std::string& body) {
  const json j = json::parse(body.empty() ? std::string("{}") : body, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return bad_request("the body is not a JSON object");
  if (name == "start" || name == "resume") return reply_of(c.cycle_start());
  if (name == "hold") return reply_of(c.feed_hold());
  if (name == "reset") return reply_of(c.reset());
  if (name == "estop") return reply_of(c.estop());
  if (name == "unlock") return reply_of(c.clear_alarm());
  if (name == "home") return reply_of(c.home());
  if (name == "jog") return jog(c, j);
  if (name == "jog-cancel") return reply_of(c.jog_cancel());
  if (name == "override") return overrides(c, j);
  if (name == "switches") return switches(c, j);
  if (name == "check") return reply_of(c.set_check_mode(j.value("on", false)));
  if (name == "reset-stock") return reply_of(c.reset_stock());
  if (name == "mdi") {
    const std::string line = j.value("line", "");
    if (line.empty()) return bad_request("mdi: no line");
    return reply_of(c.mdi(line));
  }
  return {404, json{{"ok", false}, {"error", "no control '" + std::string(name) + "'"}}.dump()};
}

}  // namespace cncore::hmi
