#include "config/servo_section.hpp"

#include <fmt/format.h>

#include <limits>

#include "config/toml_reader.hpp"

namespace cncore::config_detail {

void read_servo_section(const std::string& file, const toml::table& t, ServoConfig& s) {
  const TomlReader r(file);
  constexpr double kInf = std::numeric_limits<double>::max();
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = "servo." + k;
    if (k == "kp_per_s") {
      s.kp_per_s = r.positive(key, node, name, "1/s");
    } else if (k == "feedforward") {
      s.feedforward = r.number_in(key, node, name, 0, false, 1, "");
    } else if (k == "following_error_limit_mm") {
      s.following_error_limit_mm = r.positive(key, node, name, "mm");
    } else if (k == "home_search_mm_min") {
      s.home_search_mm_min = r.positive(key, node, name, "mm/min");
    } else if (k == "home_latch_mm_min") {
      s.home_latch_mm_min = r.positive(key, node, name, "mm/min");
    } else if (k == "home_pulloff_mm") {
      s.home_pulloff_mm = r.number_in(key, node, name, 0, false, kInf, "mm");
    } else if (k == "jog_feed_mm_min") {
      s.jog_feed_mm_min = r.positive(key, node, name, "mm/min");
    } else {
      r.fail(key.source(),
             fmt::format("unknown key '{}' (keys are kp_per_s, feedforward, "
                         "following_error_limit_mm, home_search_mm_min, home_latch_mm_min, "
                         "home_pulloff_mm, jog_feed_mm_min)",
                         name));
    }
  }
}

std::string servo_section_to_toml(const ServoConfig& s) {
  std::string o = "\n[servo]  # cncore serve: the simulated axes, homing and jogging\n";
  auto line = [&o](const std::string& kv, const std::string& comment) {
    o += fmt::format("{:<36}# {}\n", kv, comment);
  };
  line(fmt::format("kp_per_s = {}", s.kp_per_s),
       "position-loop gain, 1/s (velocity = feedforward·commanded + kp·error)");
  line(fmt::format("feedforward = {}", s.feedforward), "velocity feed-forward, 0 … 1");
  line(fmt::format("following_error_limit_mm = {}", s.following_error_limit_mm),
       "a larger |commanded − actual| raises an alarm, mm");
  line(fmt::format("home_search_mm_min = {}", s.home_search_mm_min),
       "homing: speed towards the switch at each axis's travel maximum, mm/min");
  line(fmt::format("home_latch_mm_min = {}", s.home_latch_mm_min),
       "homing: speed off the switch, where the position is latched, mm/min");
  line(fmt::format("home_pulloff_mm = {}", s.home_pulloff_mm),
       "homing: distance moved off the switch after the latch, mm");
  line(fmt::format("jog_feed_mm_min = {}", s.jog_feed_mm_min),
       "jog feed when a jog names none, mm/min");
  return o;
}

}  // namespace cncore::config_detail
