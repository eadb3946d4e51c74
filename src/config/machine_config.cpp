// Machine configuration: the built-in default, TOML parsing with every key validated, and the
// commented TOML printout. toml++ is included here only (it is heavy).
#include "config/machine_config.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "config/adaptive_section.hpp"
#include "config/cutting_config_toml.hpp"
#include "config/probe_section.hpp"
#include "config/servo_section.hpp"
#include "config/toml_reader.hpp"
#include "core/error.hpp"

namespace cncore {

namespace {

constexpr std::array<const char*, kMaxAxes> kAxisKeys = {"x", "y", "z", "a", "b", "c"};

bool is_rotary_slot(std::size_t i) {
  return i >= kA;
}

// Defaults of an axis that a configuration file enables without giving every key. Linear axes
// take the built-in mill's X/Y/Z values; rotary axes a plain indexing table.
AxisConfig default_axis(std::size_t i) {
  AxisConfig a;
  a.rotary = is_rotary_slot(i);
  switch (i) {
    case kX:
      a.min_mm = -300;
      a.max_mm = 300;
      break;
    case kY:
      a.min_mm = -200;
      a.max_mm = 200;
      break;
    case kZ:
      a.min_mm = -200;
      a.max_mm = 100;
      break;
    default:  // A, B, C in degrees: 100 turns either way, 30 rev/min, 3 600 deg/s²
      a.min_mm = -36000;
      a.max_mm = 36000;
      a.max_speed_mm_min = 10800;
      a.max_accel_mm_s2 = 3600;
      return a;
  }
  a.max_speed_mm_min = 15000;
  a.max_accel_mm_s2 = 2000;
  return a;
}

AxisConfig disabled_axis(std::size_t i) {
  AxisConfig a;
  a.rotary = is_rotary_slot(i);
  return a;
}

// Key names carry the unit: mm for linear axes, deg for rotary ones.
struct AxisKeyNames {
  std::string min, max, speed, accel, start;
};
AxisKeyNames axis_key_names(bool rotary) {
  const std::string u = rotary ? "deg" : "mm";
  return {"min_" + u, "max_" + u, "max_speed_" + u + "_min", "max_accel_" + u + "_s2",
          "start_" + u};
}

// Reads and validates one table after the other; every error points at the key.
using Reader = config_detail::TomlReader;

void read_motion(const Reader& r, const toml::table& t, MachineConfig& c) {
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = "motion." + k;
    if (k == "period_s") {
      c.period_s = r.number_in(key, node, name, 0, true, 0.1, "s");
    } else if (k == "max_feed_mm_min") {
      c.max_feed_mm_min = r.number_in(key, node, name, 0, true, 1e6, "mm/min");
    } else if (k == "rapid_mm_min") {
      c.rapid_mm_min = r.number_in(key, node, name, 0, true, 1e6, "mm/min");
    } else if (k == "max_accel_mm_s2") {
      c.max_accel_mm_s2 = r.number_in(key, node, name, 0, true, 1e6, "mm/s²");
    } else if (k == "max_jerk_mm_s3") {
      c.max_jerk_mm_s3 = r.number_in(key, node, name, 0, false, 1e9, "mm/s³");
    } else if (k == "contour_tolerance_mm") {
      c.contour_tolerance_mm = r.number_in(key, node, name, 0, true, 10, "mm");
    } else if (k == "merge_tolerance_mm") {
      c.merge_tolerance_mm = r.number_in(key, node, name, 0, false, 0.001, "mm");
    } else if (k == "smooth_tolerance_mm") {
      c.smooth_tolerance_mm = r.number_in(key, node, name, 0, false, 1, "mm");
    } else if (k == "smooth_corner_deg") {
      c.smooth_corner_deg = r.number_in(key, node, name, 0, false, 180, "deg");
    } else if (k == "post_filter_s") {
      c.post_filter_s = r.number_in(key, node, name, 0, false, 1, "s");
    } else if (k == "lookahead_blocks") {
      c.lookahead_blocks = static_cast<std::uint32_t>(r.integer_in(key, node, name, 2, 1000000));
    } else if (k == "max_override_pct") {
      c.max_override_pct = r.number_in(key, node, name, 100, false, 1000, "%");
    } else if (k == "bound_resultant_accel") {
      c.bound_resultant_accel = r.boolean(key, node, name);
    } else if (k == "accdec") {
      const auto* s = node.as_string();
      if (s != nullptr && s->get() == "acceleration") {
        c.accdec = AccDecKind::kAcceleration;
      } else if (s != nullptr && s->get() == "moving_average") {
        c.accdec = AccDecKind::kMovingAverage;
      } else if (s != nullptr && s->get() == "search") {
        c.accdec = AccDecKind::kSearch;
      } else {
        r.fail(key.source(),
               fmt::format("{} must be \"acceleration\", \"moving_average\" or \"search\"", name));
      }
    } else {
      r.unknown(key, name);
    }
  }
}

void read_interpreter(const Reader& r, const toml::table& t, MachineConfig& c) {
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = "interpreter." + k;
    if (k == "max_loop_iterations") {
      c.max_loop_iterations =
          static_cast<std::uint64_t>(r.integer_in(key, node, name, 1, 1000000000000));
    } else if (k == "max_total_iterations") {
      c.max_total_iterations =
          static_cast<std::uint64_t>(r.integer_in(key, node, name, 1, 1000000000000));
    } else if (k == "max_call_depth") {
      c.max_call_depth = static_cast<std::uint32_t>(r.integer_in(key, node, name, 1, 10000));
    } else if (k == "parameter_units") {
      const auto* s = node.as_string();
      if (s == nullptr || (s->get() != "mm" && s->get() != "inch")) {
        r.fail(key.source(), fmt::format("{} must be \"mm\" or \"inch\"", name));
      }
      c.parameters_inch = s->get() == "inch";
    } else {
      r.unknown(key, name);
    }
  }
}

void read_tables(const Reader& r, const toml::table& t, MachineConfig& c) {
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = "tables." + k;
    if (k == "cancel_mode") {
      const auto* s = node.as_string();
      if (s != nullptr && s->get() == "clear") {
        c.table_cancel_mode = TableCancelMode::kClear;
      } else if (s != nullptr && s->get() == "rebase") {
        c.table_cancel_mode = TableCancelMode::kRebase;
      } else {
        r.fail(key.source(), fmt::format("{} must be \"clear\" or \"rebase\"", name));
      }
    } else if (k == "slow_to_fit") {
      c.table_slow_to_fit = r.boolean(key, node, name);
    } else if (k == "parameters" || k == "variables" || k == "signals") {
      std::map<int, double>& values = k == "parameters"  ? c.table_parameters
                                      : k == "variables" ? c.table_variables
                                                         : c.table_signals;
      for (const auto& [number_key, value] : r.table(key, node, name)) {
        const std::string_view text = number_key.str();
        int number = -1;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), number);
        if (ec != std::errc() || end != text.data() + text.size() || number < 0) {
          r.fail(number_key.source(),
                 fmt::format("{}: key '{}' must be a number >= 0 (the n of {}<n>)", name, text,
                             k == "parameters"  ? "P"
                             : k == "variables" ? "#"
                                                : "R"));
        }
        values[number] = r.number(number_key, value, fmt::format("{}.{}", name, text));
      }
    } else {
      r.unknown(key, name);
    }
  }
}

void read_axis(const Reader& r, const toml::key& axis_key, const toml::table& t, std::size_t i,
               MachineConfig& c) {
  AxisConfig a = default_axis(i);
  a.enabled = true;
  double start = 0;
  const AxisKeyNames names = axis_key_names(a.rotary);
  const AxisKeyNames other = axis_key_names(!a.rotary);
  const char* unit = a.rotary ? "deg" : "mm";
  // Where min, max and start were given, to point at them in cross-key errors.
  const toml::source_region* min_at = nullptr;
  const toml::source_region* max_at = nullptr;
  const toml::source_region* start_at = nullptr;
  const std::string prefix = fmt::format("axes.{}.", kAxisKeys[i]);
  constexpr double kTravel = 1e6;  // mm or deg: anything beyond is a typo
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = prefix + k;
    if (k == names.min) {
      a.min_mm = r.number_in(key, node, name, -kTravel, false, kTravel, unit);
      min_at = &key.source();
    } else if (k == names.max) {
      a.max_mm = r.number_in(key, node, name, -kTravel, false, kTravel, unit);
      max_at = &key.source();
    } else if (k == names.speed) {
      a.max_speed_mm_min =
          r.number_in(key, node, name, 0, true, 1e6, a.rotary ? "deg/min" : "mm/min");
    } else if (k == names.accel) {
      a.max_accel_mm_s2 = r.number_in(key, node, name, 0, true, 1e6, a.rotary ? "deg/s²" : "mm/s²");
    } else if (k == names.start) {
      start = r.number_in(key, node, name, -kTravel, false, kTravel, unit);
      start_at = &key.source();
    } else if (k == other.min || k == other.max || k == other.speed || k == other.accel ||
               k == other.start) {
      r.unknown(key, name,
                fmt::format(" (axis {} is {}: its keys are in {})", kAxisLetters[i],
                            a.rotary ? "rotary" : "linear", unit));
    } else {
      r.unknown(key, name);
    }
  }
  if (a.min_mm >= a.max_mm) {
    const toml::source_region& where = max_at ? *max_at : (min_at ? *min_at : axis_key.source());
    r.fail(where, fmt::format("{}{} ({}) must be less than {}{} ({})", prefix, names.min, a.min_mm,
                              prefix, names.max, a.max_mm));
  }
  if (start < a.min_mm || start > a.max_mm) {
    const toml::source_region& where = start_at ? *start_at : axis_key.source();
    r.fail(where, fmt::format("{}{} = {} lies outside the travel {} … {} {}", prefix, names.start,
                              start, a.min_mm, a.max_mm, unit));
  }
  c.axes[i] = a;
  c.start_position[i] = start;
}

void read_axes(const Reader& r, const toml::key& axes_key, const toml::table& t, MachineConfig& c) {
  // A file that lists axes replaces the built-in axis set: only the axes listed are enabled.
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    c.axes[i] = disabled_axis(i);
    c.start_position[i] = 0;
  }
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    std::size_t slot = kMaxAxes;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      if (k == kAxisKeys[i]) slot = i;
    }
    if (slot == kMaxAxes) r.unknown(key, "axes." + k, " (axes are x, y, z, a, b, c)");
    read_axis(r, key, r.table(key, node, "axes." + k), slot, c);
  }
  if (c.axis_count() == 0) r.fail(axes_key.source(), "axes: at least one axis must be configured");
}

std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (const char ch : s) {
    const auto u = static_cast<unsigned char>(ch);
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (u < 0x20 || u == 0x7f) {
      out += fmt::format("\\u{:04X}", static_cast<unsigned>(u));
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

// Shortest text that reads back to the same double; TOML accepts fmt's forms (1e-05, 10000).
std::string num(double v) {
  return fmt::format("{}", v);
}

// [direction_correction] (spec 03). A law is a formula string or a table [[FI, C], …]; each is
// checked over the FI range where it applies (uphill [0, 1], downhill [−1, 0]): a coefficient that
// is not finite or not > 0 anywhere there is an error naming the key and showing that FI.
CorrectionLaw read_correction_law(const Reader& r, const toml::key& key, const toml::node& node,
                                  const std::string& name) {
  CorrectionLaw law;
  if (const auto* s = node.as_string()) {
    law.formula = s->get();
    try {
      const CorrectionEvaluator check(law);
    } catch (const CorrectionLawError& e) {
      // Point at the character of the formula (the string starts after its opening quote).
      toml::source_region where = node.source();
      if (e.position() >= 0 && where.begin.line == where.end.line) {
        where.begin.column += static_cast<toml::source_index>(1 + e.position());
      } else {
        where = key.source();
      }
      r.fail(where, fmt::format("{}: formula \"{}\": {}", name, law.formula, e.what()));
    }
    return law;
  }
  const auto* arr = node.as_array();
  if (arr == nullptr || arr->empty()) {
    r.fail(
        key.source(),
        fmt::format("{} must be a formula in FI, F, D (a string) or a table [[FI, C], ...]", name));
  }
  for (const toml::node& item : *arr) {
    const auto* pair = item.as_array();
    std::array<double, 2> p{};
    bool ok = pair != nullptr && pair->size() == 2;
    for (std::size_t i = 0; ok && i < 2; ++i) {
      const toml::node& v = *pair->get(i);
      if (const auto* f = v.as_floating_point()) {
        p[i] = f->get();
      } else if (const auto* n = v.as_integer()) {
        p[i] = static_cast<double>(n->get());
      } else {
        ok = false;
      }
      ok = ok && std::isfinite(p[i]);
    }
    if (!ok)
      r.fail(item.source(),
             fmt::format("{}: every table entry must be [FI, C] (two numbers)", name));
    if (p[0] < -1 || p[0] > 1) {
      r.fail(item.source(), fmt::format("{}: FI = {} is outside [-1, 1]", name, p[0]));
    }
    if (!law.table.empty() && p[0] <= law.table.back()[0]) {
      r.fail(item.source(), fmt::format("{}: FI = {} must be greater than the previous FI ({})",
                                        name, p[0], law.table.back()[0]));
    }
    if (!(p[1] > 0)) {
      r.fail(item.source(),
             fmt::format("{}: C = {} at FI = {}: the coefficient must be > 0", name, p[1], p[0]));
    }
    law.table.push_back(p);
  }
  return law;
}

void check_correction_law(const Reader& r, const toml::source_region& where,
                          const CorrectionLaw& law, const std::string& name, double fi_lo,
                          double fi_hi, const MachineConfig& c) {
  std::optional<BadCoefficient> bad;
  try {
    bad = find_bad_coefficient(law, fi_lo, fi_hi, c.max_feed_mm_min,
                               c.direction_correction.tool_diameter_mm);
  } catch (const CorrectionLawError& e) {
    r.fail(where,
           fmt::format("{}: formula \"{}\" cannot be evaluated: {}", name, law.formula, e.what()));
  }
  if (bad) {
    r.fail(where,
           fmt::format("{}: C = {} at FI = {} (F = {} mm/min, D = {} mm): the coefficient "
                       "must be finite and > 0 for every FI in [{}, {}]",
                       name, std::isnan(bad->c) ? std::string("NaN") : num(bad->c), bad->fi,
                       bad->feed_mm_min, c.direction_correction.tool_diameter_mm, fi_lo, fi_hi));
  }
}

// Where the laws were given, for the check after the whole file is read (it needs the feed
// limit and D, whatever the order of sections and keys).
struct CorrectionSources {
  std::optional<toml::source_region> section, uphill, downhill;
};

void read_direction_correction(const Reader& r, const toml::key& section, const toml::table& t,
                               MachineConfig& c, CorrectionSources& at) {
  DirectionCorrectionConfig& d = c.direction_correction;
  at.section = section.source();
  std::optional<toml::source_region>& uphill_at = at.uphill;
  std::optional<toml::source_region>& downhill_at = at.downhill;
  for (const auto& [key, node] : t) {
    const std::string k(key.str());
    const std::string name = "direction_correction." + k;
    if (k == "enabled") {
      d.enabled = r.boolean(key, node, name);
    } else if (k == "active_at_start") {
      d.active_at_start = r.boolean(key, node, name);
    } else if (k == "direction") {
      const auto* arr = node.as_array();
      if (arr == nullptr || arr->size() != 3) {
        r.fail(key.source(), fmt::format("{} must be a vector [x, y, z]", name));
      }
      std::array<double, 3> v{};
      for (std::size_t i = 0; i < 3; ++i) {
        const toml::node& e = *arr->get(i);
        if (const auto* f = e.as_floating_point()) {
          v[i] = f->get();
        } else if (const auto* n = e.as_integer()) {
          v[i] = static_cast<double>(n->get());
        } else {
          r.fail(key.source(), fmt::format("{} must be a vector of three numbers", name));
        }
        if (!std::isfinite(v[i])) r.fail(key.source(), fmt::format("{} must be finite", name));
      }
      const Vec3 u{v[0], v[1], v[2]};
      const double len = norm(u);
      if (!(len > 1e-9)) {
        r.fail(key.source(), fmt::format("{} = [{}, {}, {}] is the zero vector: it needs a "
                                         "direction",
                                         name, v[0], v[1], v[2]));
      }
      // Normalised; a vector already of unit length (to 1e-12) is kept as written, so the
      // printed configuration reads back identical.
      d.direction = std::abs(len - 1) > 1e-12 ? (1 / len) * u : u;
    } else if (k == "uphill") {
      d.uphill = read_correction_law(r, key, node, name);
      uphill_at = key.source();
    } else if (k == "downhill") {
      d.downhill = read_correction_law(r, key, node, name);
      downhill_at = key.source();
    } else if (k == "override_mode") {
      const auto* s = node.as_string();
      if (s != nullptr && s->get() == "multiply") {
        d.override_mode = CorrectionOverrideMode::kMultiply;
      } else if (s != nullptr && s->get() == "replace") {
        d.override_mode = CorrectionOverrideMode::kReplace;
      } else {
        r.fail(key.source(),
               fmt::format("{} must be \"multiply\" (C × override) or \"replace\" (C only)", name));
      }
    } else if (k == "tool_diameter_mm") {
      d.tool_diameter_mm = r.number_in(key, node, name, 0, true, 1000, "mm");
    } else if (k == "arc_step_deg") {
      d.arc_step_deg = r.number_in(key, node, name, 0.01, false, 90, "deg");
    } else {
      r.unknown(key, name);
    }
  }
}

void check_direction_correction(const Reader& r, const CorrectionSources& at,
                                const MachineConfig& c) {
  if (!at.section) return;  // the built-in laws are valid
  const DirectionCorrectionConfig& d = c.direction_correction;
  check_correction_law(r, at.uphill.value_or(*at.section), d.uphill, "direction_correction.uphill",
                       0, 1, c);
  check_correction_law(r, at.downhill.value_or(*at.section), d.downhill,
                       "direction_correction.downhill", -1, 0, c);
}

std::string correction_law_toml(const CorrectionLaw& law) {
  if (!law.is_table()) return toml_string(law.formula);
  std::string s = "[";
  for (std::size_t i = 0; i < law.table.size(); ++i) {
    s += fmt::format("{}[{}, {}]", i > 0 ? ", " : "", num(law.table[i][0]), num(law.table[i][1]));
  }
  return s + "]";
}

}  // namespace

MachineConfig default_machine_config() {
  MachineConfig c;
  for (std::size_t i = 0; i < kMaxAxes; ++i) c.axes[i] = disabled_axis(i);
  for (std::size_t i : {kX, kY, kZ}) {
    c.axes[i] = default_axis(i);
    c.axes[i].enabled = true;
  }
  return c;
}

MachineConfig parse_machine_config(std::string_view toml_text, const std::string& source_name) {
  toml::table root;
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    throw InputError(source_name, static_cast<std::uint32_t>(e.source().begin.line),
                     static_cast<std::uint32_t>(e.source().begin.column),
                     fmt::format("TOML syntax: {}", e.description()));
  }
  MachineConfig c = default_machine_config();
  const Reader r(source_name);
  CorrectionSources correction_at;
  CuttingSources cutting_at;
  for (const auto& [key, node] : root) {
    const std::string k(key.str());
    if (read_cutting_section(source_name, key, node, c.cutting, cutting_at)) continue;
    if (k == "name") {
      const auto* s = node.as_string();
      if (s == nullptr) r.fail(key.source(), "name must be a string");
      c.name = s->get();
    } else if (k == "motion") {
      read_motion(r, r.table(key, node, k), c);
    } else if (k == "interpreter") {
      read_interpreter(r, r.table(key, node, k), c);
    } else if (k == "tables") {
      read_tables(r, r.table(key, node, k), c);
    } else if (k == "axes") {
      read_axes(r, key, r.table(key, node, k), c);
    } else if (k == "direction_correction") {
      read_direction_correction(r, key, r.table(key, node, k), c, correction_at);
    } else if (k == "adaptive") {
      config_detail::read_adaptive_section(source_name, key, node, c);
    } else if (k == "servo") {
      config_detail::read_servo_section(source_name, r.table(key, node, k), c.servo);
    } else if (k == "probe") {
      config_detail::read_probe_section(source_name, r.table(key, node, k), c.probe);
    } else {
      r.unknown(
          key, k,
          " (sections are [motion], [axes.<x|y|z|a|b|c>], [interpreter], [tables], "
          "[direction_correction], [stock], [[tools]], [cutting], [adaptive], [servo], [probe])");
    }
  }
  validate_cutting_config(source_name, c.cutting, cutting_at);
  check_direction_correction(r, correction_at, c);
  // After every section: adaptive.upper_pct is checked against motion.max_override_pct.
  if (root.contains("adaptive")) config_detail::check_adaptive_section(source_name, root, c);
  return c;
}

MachineConfig load_machine_config(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, 0, 0, "cannot open machine configuration: it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, 0, "cannot open machine configuration");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, 0, 0, "cannot read machine configuration");
  return parse_machine_config(text.str(), path);
}

// Size: one line per configuration key, in the order of the file it writes (every section and
// its comments); splitting it by section would scatter that order.
std::string machine_config_to_toml(const MachineConfig& c) {
  std::string o;
  auto line = [&o](const std::string& key_value, std::string_view comment) {
    o += fmt::format("{:<34} # {}\n", key_value, comment);
  };
  o += "# cncore machine configuration (TOML).\n"
       "# Every key is optional: a key left out keeps the built-in default. Unknown keys and\n"
       "# values out of range are errors that name the key. Units are part of every key name.\n\n";
  line("name = " + toml_string(c.name), "free text shown in summaries");

  o += "\n[motion]\n";
  line("period_s = " + num(c.period_s), "interpolation period τ, s (0 < τ <= 0.1)");
  line("max_feed_mm_min = " + num(c.max_feed_mm_min),
       "Vmax: highest path feed; higher F words are clamped to it");
  line("rapid_mm_min = " + num(c.rapid_mm_min), "G0 path speed, mm/min (see below)");
  line("max_accel_mm_s2 = " + num(c.max_accel_mm_s2),
       "Amax: tangential and normal path acceleration, mm/s²");
  // Written from this configuration's own values, so an edited file documents itself.
  const double t_s = c.max_feed_mm_min / 60 / c.max_accel_mm_s2;
  const long t_cycles = static_cast<long>(std::ceil(t_s / c.period_s - 1e-9));
  const double g0_mm_min =
      std::min(c.rapid_mm_min, c.max_accel_mm_s2 * static_cast<double>(t_cycles) * c.period_s * 60);
  o += fmt::format(
      "# The moving-average acc/dec filter follows from the limits: its time constant is\n"
      "# T = Vmax / Amax (s), i.e. ceil(Vmax / (Amax·τ)) cycles, so a step 0 → Vmax becomes a\n"
      "# ramp of slope Amax. Here T = {:.1f} ms ({} cycles). G0 uses the same filter, so it runs\n"
      "# at min(rapid, Amax·T) = {:.0f} mm/min. Arcs of radius R pass at\n"
      "# Vb = min(Vmax, sqrt(R·Amax)); a corner turning by θ at Amax·τ / (2·sin(θ/2)).\n",
      t_s * 1000, t_cycles, g0_mm_min);
  line("max_jerk_mm_s3 = " + num(c.max_jerk_mm_s3),
       "Jmax, mm/s³; 0 = no jerk stage, else a second filter of T2 = 2·Amax/Jmax");
  line("contour_tolerance_mm = " + num(c.contour_tolerance_mm),
       "largest allowed deviation from the path (corner rounding), mm (> 0)");
  line("merge_tolerance_mm = " + num(c.merge_tolerance_mm),
       "collinear G0/G1 pieces within this of one line run as that line, mm; 0 = off (<= 0.001)");
  line("smooth_tolerance_mm = " + num(c.smooth_tolerance_mm),
       "G1 chords within this of one line/arc/helix run as that curve, mm; 0 = off (<= 1)");
  line("smooth_corner_deg = " + num(c.smooth_corner_deg),
       "smoothing keeps joints turning more than this between chords longer than the tolerance");
  line("post_filter_s = " + num(c.post_filter_s),
       "per-axis post-interpolation moving average, s; 0 = off (<= 1)");
  line("lookahead_blocks = " + std::to_string(c.lookahead_blocks),
       "capacity of the execution-data (look-ahead) buffer, blocks (2 … 1000000)");
  line("max_override_pct = " + num(c.max_override_pct),
       "highest feed override accepted, % (100 … 1000)");
  line(fmt::format("bound_resultant_accel = {}", c.bound_resultant_accel),
       "arcs: true = tangential+normal resultant <= Amax; false = each <= Amax (seed)");
  line(fmt::format("accdec = \"{}\"", c.accdec == AccDecKind::kAcceleration ? "acceleration"
                                      : c.accdec == AccDecKind::kSearch     ? "search"
                                                                            : "moving_average"),
       "look-ahead acc/dec: \"acceleration\" = constant acceleration, a speed change takes "
       "|dV|/Amax; \"moving_average\" = the seed's filter, every change takes T = Vmax/Amax; "
       "\"search\" = samples searched ahead (no jerk limit or post filter)");

  o += "\n[interpreter]\n";
  line("max_loop_iterations = " + std::to_string(c.max_loop_iterations),
       "runaway-loop guard for while/do/repeat (1 … 1e12)");
  line("max_total_iterations = " + std::to_string(c.max_total_iterations),
       "runaway guard for the whole program: loop passes + calls (1 … 1e12)");
  line("max_call_depth = " + std::to_string(c.max_call_depth),
       "O-word subroutine call nesting (1 … 10000)");
  line(fmt::format("parameter_units = \"{}\"", c.parameters_inch ? "inch" : "mm"),
       "unit of the offset parameters #5161…#5389 as programs read and write them");

  o += "\n[tables]\n";
  line(fmt::format("cancel_mode = \"{}\"",
                   c.table_cancel_mode == TableCancelMode::kRebase ? "rebase" : "clear"),
       "SFTCAN: \"clear\" = later rows use their written L values; \"rebase\" = gaps stay shifted");
  line(fmt::format("slow_to_fit = {}", c.table_slow_to_fit),
       "a table over an axis limit: false = refused; true = reference slowed to fit");
  const std::pair<const char*, const std::map<int, double>*> table_values[] = {
      {"parameters", &c.table_parameters},
      {"variables", &c.table_variables},
      {"signals", &c.table_signals}};
  for (const auto& [section, values] : table_values) {
    if (values->empty()) {
      o += fmt::format("# [tables.{}]  # for SFT={}<n>; e.g. {} = -200\n", section,
                       section[0] == 'p'   ? "P"
                       : section[0] == 'v' ? "#"
                                           : "R",
                       section[0] == 's' ? "1001" : "501");
      continue;
    }
    o += fmt::format("[tables.{}]\n", section);
    for (const auto& [n, v] : *values) o += fmt::format("{} = {}\n", n, num(v));
  }

  const DirectionCorrectionConfig& dc = c.direction_correction;
  o += "\n# Feed correction by direction of motion (spec 03, docs/direction-correction.md).\n"
       "# FI = (unit direction of the move) · direction, in [-1, 1]: +1 along it, -1 against it.\n"
       "# The feed of every G1/G2/G3 becomes F·C(FI) (arcs and helices per sub-arc, following the\n"
       "# tangent); G0 is not corrected. A law is a muParser formula in FI, F (programmed feed,\n"
       "# mm/min) and D (tool diameter, mm), or a table [[FI, C], ...] (linear between points, "
       "flat\n"
       "# outside). Checked at load: C must be finite and > 0 over its FI range. In a program,\n"
       "# M160 turns the correction on and M161 off (until the other or the program end).\n";
  o += "[direction_correction]\n";
  line(fmt::format("enabled = {}", dc.enabled),
       "the on/off parameter; false = every run exactly as uncorrected");
  line(fmt::format("active_at_start = {}", dc.active_at_start),
       "on from the program start (else only after M160)");
  line(fmt::format("direction = [{}, {}, {}]", num(dc.direction.x), num(dc.direction.y),
                   num(dc.direction.z)),
       "direction component (normalised; not zero), e.g. the tool axis");
  line("uphill = " + correction_law_toml(dc.uphill), "C for FI >= 0 (the seed: C >= 1)");
  line("downhill = " + correction_law_toml(dc.downhill), "C for FI < 0 (the seed: C < 1)");
  line(fmt::format("override_mode = \"{}\"",
                   dc.override_mode == CorrectionOverrideMode::kReplace ? "replace" : "multiply"),
       "\"multiply\" = C x operator override; \"replace\" = C only (switch ignored)");
  line("tool_diameter_mm = " + num(dc.tool_diameter_mm), "D in the formulas, mm (> 0)");
  line("arc_step_deg = " + num(dc.arc_step_deg),
       "arcs/helices: one C per sub-arc of at most this angle, deg (0.01 ... 90)");

  o +=
      "\n# One table per axis; a table present enables the axis. When a file lists any axis, only\n"
      "# the axes listed are enabled. Linear axes (x y z) in mm, rotary axes (a b c) in deg.\n"
      "# The path limits of a block follow from its direction: the slowest axis decides.\n";
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    const AxisConfig& a = c.axes[i];
    if (!a.enabled) continue;
    const AxisKeyNames n = axis_key_names(a.rotary);
    const char* u = a.rotary ? "deg" : "mm";
    o += fmt::format("\n[axes.{}]\n", kAxisKeys[i]);
    line(n.min + " = " + num(a.min_mm), fmt::format("travel limit, machine coordinates, {}", u));
    line(n.max + " = " + num(a.max_mm), fmt::format("travel limit (> {}), {}", n.min, u));
    line(n.speed + " = " + num(a.max_speed_mm_min), fmt::format("axis speed limit, {}/min", u));
    line(n.accel + " = " + num(a.max_accel_mm_s2),
         fmt::format("axis acceleration limit, {}/s²", u));
    line(n.start + " = " + num(c.start_position[i]),
         fmt::format("position at program start, {}", u));
  }
  o += cutting_config_to_toml(c.cutting);
  o += config_detail::adaptive_section_to_toml(c);
  o += config_detail::servo_section_to_toml(c.servo);
  o += config_detail::probe_section_to_toml(c.probe);
  return o;
}

MachineConfig machine_config_or_default(const std::string& path) {
  return path.empty() ? default_machine_config() : load_machine_config(path);
}

}  // namespace cncore
