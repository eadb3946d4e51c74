#include "config/adaptive_section.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <string_view>

#include "config/toml_reader.hpp"
#include "core/error.hpp"

namespace cncore::config_detail {

namespace {

[[noreturn]] void fail(const std::string& file, const toml::source_region& where,
                       const std::string& message) {
  TomlReader(file).fail(where, message);
}

double number(const std::string& file, const toml::source_region& where, const toml::node& node,
              const std::string& name) {
  return TomlReader(file).number_at(where, node, name);
}

std::int64_t integer_in(const std::string& file, const toml::key& key, const toml::node& node,
                        const std::string& name, std::int64_t lo, std::int64_t hi) {
  return TomlReader(file).integer_in(key, node, name, lo, hi);
}

// depth = [[s_mm, depth_mm], ...]: each point checked where it is written.
feed::DepthProfile read_depth(const std::string& file, const toml::key& key,
                              const toml::node& node) {
  const auto* points = node.as_array();
  if (points == nullptr) {
    fail(file, key.source(),
         "adaptive.plant.depth must be an array of [s_mm, depth_mm] points, e.g. "
         "[[0, 0], [10, 1.0]]");
  }
  feed::DepthProfile d;
  std::size_t n = 0;
  for (const toml::node& p : *points) {
    ++n;
    const auto* pair = p.as_array();
    if (pair == nullptr || pair->size() != 2) {
      fail(file, p.source(),
           fmt::format("adaptive.plant.depth point {} must be [s_mm, depth_mm]", n));
    }
    const std::string what = fmt::format("adaptive.plant.depth point {}", n);
    d.s_mm.push_back(number(file, (*pair)[0].source(), (*pair)[0], what + " s_mm"));
    d.depth_mm.push_back(number(file, (*pair)[1].source(), (*pair)[1], what + " depth_mm"));
  }
  return d;
}

void read_plant(const std::string& file, const toml::table& t, feed::PlantSettings& p) {
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = "adaptive.plant." + k;
    if (k == "base_pct") {
      p.base_pct = number(file, key.source(), node, name);
    } else if (k == "k_pct_per_mm2_min") {
      p.k_pct_per_mm2_min = number(file, key.source(), node, name);
    } else if (k == "time_constant_s") {
      p.time_constant_s = number(file, key.source(), node, name);
    } else if (k == "noise_pct") {
      p.noise_pct = number(file, key.source(), node, name);
    } else if (k == "seed") {
      p.seed = static_cast<std::uint64_t>(
          integer_in(file, key, node, name, 0, std::numeric_limits<std::int64_t>::max()));
    } else if (k == "depth") {
      p.depth = read_depth(file, key, node);
    } else {
      fail(file, key.source(), fmt::format("unknown key '{}'", name));
    }
  }
}

// Where a key "adaptive.x" or "adaptive.plant.x" is written; the nearest enclosing table when
// the key is not written (its default clashes with a key that is).
toml::source_region where_is(const toml::table& root, std::string_view dotted) {
  const toml::node* adaptive = root.get("adaptive");
  toml::source_region region = adaptive != nullptr ? adaptive->source() : toml::source_region{};
  const toml::table* t = adaptive != nullptr ? adaptive->as_table() : nullptr;
  std::string_view rest = dotted.substr(std::string_view("adaptive.").size());
  while (t != nullptr) {
    const std::size_t dot = rest.find('.');
    const std::string_view part = rest.substr(0, dot);
    const toml::table* next = nullptr;
    for (const auto& [key, node] : *t) {
      if (key.str() != part) continue;
      region = key.source();
      if (dot != std::string_view::npos) next = node.as_table();
    }
    if (dot == std::string_view::npos || next == nullptr) break;
    t = next;
    rest = rest.substr(dot + 1);
  }
  return region;
}

std::string num(double v) {
  return fmt::format("{}", v);
}

std::string plant_toml(const feed::PlantSettings& p) {
  std::string o = "[adaptive.plant]\n";
  auto line = [&o](const std::string& key_value, std::string_view comment) {
    o += fmt::format("{:<34} # {}\n", key_value, comment);
  };
  line("base_pct = " + num(p.base_pct), "no-cut load (spindle idling), % (>= 0)");
  line("k_pct_per_mm2_min = " + num(p.k_pct_per_mm2_min),
       "load per feed × depth, % per (mm/min·mm) (>= 0)");
  line("time_constant_s = " + num(p.time_constant_s), "first-order lag of the load, s (>= 0)");
  line("noise_pct = " + num(p.noise_pct), "standard deviation of the measurement noise, %");
  line("seed = " + std::to_string(p.seed), "noise seed: the same seed gives the same run");
  o += "# depth: [path distance s_mm, depth of cut mm] points, s not decreasing; two points at\n"
       "# the same s make a jump; linear in between, held outside.\n";
  std::string depth = "depth = [";
  for (std::size_t i = 0; i < p.depth.s_mm.size() && i < p.depth.depth_mm.size(); ++i) {
    depth += fmt::format("{}[{}, {}]", i > 0 ? ", " : "", num(p.depth.s_mm[i]),
                         num(p.depth.depth_mm[i]));
  }
  o += depth + "]\n";
  return o;
}

}  // namespace

void read_adaptive_section(const std::string& file, const toml::key& section,
                           const toml::node& node, MachineConfig& c) {
  const auto* t = node.as_table();
  if (t == nullptr) fail(file, section.source(), "adaptive must be a table");
  feed::AdaptiveSettings& a = c.adaptive;
  for (const auto& [key, value] : *t) {
    const std::string k(key.str());
    const std::string name = "adaptive." + k;
    // Captured through references: clang 14 (the fuzz preset) cannot capture structured bindings.
    const toml::key& key_ref = key;
    const toml::node& value_ref = value;
    auto real = [&] { return number(file, key_ref.source(), value_ref, name); };
    if (k == "enabled") {
      const auto* b = value.as_boolean();
      if (b == nullptr) fail(file, key.source(), name + " must be true or false");
      a.enabled = b->get();
    } else if (k == "target_load_pct") {
      a.target_load_pct = real();
    } else if (k == "kp") {
      a.kp = real();
    } else if (k == "ki") {
      a.ki = real();
    } else if (k == "kd") {
      a.kd = real();
    } else if (k == "constant_pct") {
      a.constant_pct = real();
    } else if (k == "threshold_pct") {
      a.threshold_pct = real();
    } else if (k == "upper_pct") {
      a.upper_pct = real();
    } else if (k == "lower_pct") {
      a.lower_pct = real();
    } else if (k == "antiwindup") {
      const auto* s = value.as_string();
      const auto policy = s != nullptr ? feed::parse_antiwindup(s->get()) : std::nullopt;
      if (!policy) {
        fail(file, key.source(), name + R"( must be "none", "clamp" or "back_calculation")");
      }
      a.antiwindup = *policy;
    } else if (k == "control_cycles") {
      a.control_cycles = static_cast<std::uint32_t>(integer_in(file, key, value, name, 1, 1000000));
    } else if (k == "plant") {
      const auto* plant = value.as_table();
      if (plant == nullptr) fail(file, key.source(), "adaptive.plant must be a table");
      read_plant(file, *plant, c.adaptive_plant);
    } else {
      fail(file, key.source(), fmt::format("unknown key '{}'", name));
    }
  }
}

void check_adaptive_section(const std::string& file, const toml::table& root,
                            const MachineConfig& c) {
  if (const auto p = c.adaptive.find_problem(c.max_override_pct)) {
    fail(file, where_is(root, p->key), p->key + ": " + p->message);
  }
  const toml::node* adaptive = root.get("adaptive");
  const bool plant_written = adaptive != nullptr && adaptive->as_table() != nullptr &&
                             adaptive->as_table()->get("plant") != nullptr;
  if (!plant_written) return;
  if (const auto p = c.adaptive_plant.find_problem()) {
    fail(file, where_is(root, p->key), p->key + ": " + p->message);
  }
}

std::string adaptive_section_to_toml(const MachineConfig& c) {
  std::string o;
  auto line = [&o](const std::string& key_value, std::string_view comment) {
    o += fmt::format("{:<34} # {}\n", key_value, comment);
  };
  const feed::AdaptiveSettings& a = c.adaptive;
  o += "\n# Adaptive feed control on spindle load (spec 04, docs/adaptive-feed.md): a PID whose\n"
       "# error is target − load and whose output is the feed override,\n"
       "# o = kp·e + ki·∫e dt + kd·de/dt + constant_pct, limited to lower_pct … upper_pct.\n"
       "# It needs a load source: `cncore run --load FILE.csv` or [adaptive.plant] below.\n"
       "# In the program, M52 P1 switches it on and M52 P0 off.\n"
       "[adaptive]\n";
  line(fmt::format("enabled = {}", a.enabled),
       "on at program start (cncore run --adaptive on|off overrides it)");
  line("target_load_pct = " + num(a.target_load_pct), "target spindle load, % of rating (>= 0)");
  line("kp = " + num(a.kp), "proportional gain, % override per % load (>= 0)");
  line("ki = " + num(a.ki), "integral gain, % override per %load·s (> 0: back_calculation)");
  line("kd = " + num(a.kd), "derivative gain, % override·s per % load (>= 0)");
  line("constant_pct = " + num(a.constant_pct), "c: the output at zero error and integral, %");
  line("threshold_pct = " + num(a.threshold_pct),
       "lm: below it the tool is not cutting: operator's override, %");
  line("upper_pct = " + num(a.upper_pct), "ot: upper override limit, % (> lower, <= max_override)");
  line("lower_pct = " + num(a.lower_pct), "lower override limit, % (>= 0)");
  line(fmt::format("antiwindup = \"{}\"", feed::antiwindup_name(a.antiwindup)),
       R"("back_calculation" (seed), "clamp" (overwrite) or "none")");
  line("control_cycles = " + std::to_string(a.control_cycles),
       "control period in interpolation periods (1 … 1000000)");

  o += "\n# A plant model as load source: load = base + k·feed·depth(s) through a first-order\n"
       "# lag, plus noise; depth is a profile along the path distance s (mm from the start).\n";
  if (c.adaptive_plant.depth.s_mm.empty()) {
    // Not configured: shown as a commented example (an empty profile is not a valid plant).
    feed::PlantSettings example = c.adaptive_plant;
    example.depth.s_mm = {0, 10, 10, 60, 60, 100};
    example.depth.depth_mm = {0, 0, 1, 1, 2, 2};
    const std::string text = plant_toml(example);
    o += "# Not configured. Example:\n";
    std::size_t pos = 0;
    while (pos < text.size()) {
      const std::size_t nl = text.find('\n', pos);
      o += "# " + text.substr(pos, nl - pos) + "\n";
      pos = nl + 1;
    }
  } else {
    o += plant_toml(c.adaptive_plant);
  }
  return o;
}

}  // namespace cncore::config_detail
