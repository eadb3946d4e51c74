// Machine configuration: the built-in default, TOML parsing with every key validated, and the
// commented TOML printout. toml++ is included here only (it is heavy).
#include "config/machine_config.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "config/cutting_config_toml.hpp"
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
class Reader {
 public:
  explicit Reader(const std::string& file) : file_(file) {}

  [[noreturn]] void fail(const toml::source_region& where, const std::string& message) const {
    throw InputError(file_, static_cast<std::uint32_t>(where.begin.line),
                     static_cast<std::uint32_t>(where.begin.column), message);
  }

  double number(const toml::key& key, const toml::node& node, const std::string& name) const {
    if (const auto* f = node.as_floating_point()) {
      const double v = f->get();
      if (!std::isfinite(v)) fail(key.source(), fmt::format("{} must be a finite number", name));
      return v;
    }
    if (const auto* i = node.as_integer()) return static_cast<double>(i->get());
    fail(key.source(), fmt::format("{} must be a number", name));
  }

  bool boolean(const toml::key& key, const toml::node& node, const std::string& name) const {
    if (const auto* b = node.as_boolean()) return b->get();
    fail(key.source(), fmt::format("{} must be true or false", name));
  }

  std::int64_t integer(const toml::key& key, const toml::node& node,
                       const std::string& name) const {
    if (const auto* i = node.as_integer()) return i->get();
    fail(key.source(), fmt::format("{} must be an integer", name));
  }

  // lo < v ≤ hi (lo_open) or lo ≤ v ≤ hi.
  double number_in(const toml::key& key, const toml::node& node, const std::string& name, double lo,
                   bool lo_open, double hi, const char* unit) const {
    const double v = number(key, node, name);
    if ((lo_open ? v <= lo : v < lo) || v > hi) {
      fail(key.source(), fmt::format("{} = {} is out of range: it must be {} {} and <= {} {}", name,
                                     v, lo_open ? ">" : ">=", lo, hi, unit));
    }
    return v;
  }

  std::int64_t integer_in(const toml::key& key, const toml::node& node, const std::string& name,
                          std::int64_t lo, std::int64_t hi) const {
    const std::int64_t v = integer(key, node, name);
    if (v < lo || v > hi) {
      fail(key.source(),
           fmt::format("{} = {} is out of range: it must be between {} and {}", name, v, lo, hi));
    }
    return v;
  }

  const toml::table& table(const toml::key& key, const toml::node& node,
                           const std::string& name) const {
    const auto* t = node.as_table();
    if (t == nullptr) fail(key.source(), fmt::format("{} must be a table", name));
    return *t;
  }

  [[noreturn]] void unknown(const toml::key& key, const std::string& name,
                            const std::string& hint = {}) const {
    fail(key.source(), fmt::format("unknown key '{}'{}", name, hint));
  }

 private:
  const std::string& file_;
};

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
    } else if (k == "post_filter_s") {
      c.post_filter_s = r.number_in(key, node, name, 0, false, 1, "s");
    } else if (k == "lookahead_blocks") {
      c.lookahead_blocks = static_cast<std::uint32_t>(r.integer_in(key, node, name, 2, 1000000));
    } else if (k == "max_override_pct") {
      c.max_override_pct = r.number_in(key, node, name, 100, false, 1000, "%");
    } else if (k == "bound_resultant_accel") {
      c.bound_resultant_accel = r.boolean(key, node, name);
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
    } else if (k == "max_call_depth") {
      c.max_call_depth = static_cast<std::uint32_t>(r.integer_in(key, node, name, 1, 10000));
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
    } else {
      r.unknown(key, k,
                " (sections are [motion], [axes.<x|y|z|a|b|c>], [interpreter], [tables], "
                "[stock], [[tools]], [cutting])");
    }
  }
  validate_cutting_config(source_name, c.cutting, cutting_at);
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
       "Jmax, mm/s³; 0 = no jerk stage, else a second filter T2 = Amax / Jmax");
  line("contour_tolerance_mm = " + num(c.contour_tolerance_mm),
       "largest allowed deviation from the path (corner rounding), mm (> 0)");
  line("post_filter_s = " + num(c.post_filter_s),
       "per-axis post-interpolation moving average, s; 0 = off (<= 1)");
  line("lookahead_blocks = " + std::to_string(c.lookahead_blocks),
       "capacity of the execution-data (look-ahead) buffer, blocks (2 … 1000000)");
  line("max_override_pct = " + num(c.max_override_pct),
       "highest feed override accepted, % (100 … 1000)");
  line(fmt::format("bound_resultant_accel = {}", c.bound_resultant_accel),
       "arcs: true = tangential+normal resultant <= Amax; false = each <= Amax (seed)");

  o += "\n[interpreter]\n";
  line("max_loop_iterations = " + std::to_string(c.max_loop_iterations),
       "runaway-loop guard for while/do/repeat (1 … 1e12)");
  line("max_call_depth = " + std::to_string(c.max_call_depth),
       "O-word subroutine call nesting (1 … 10000)");

  o += "\n[tables]\n";
  line(fmt::format("cancel_mode = \"{}\"",
                   c.table_cancel_mode == TableCancelMode::kRebase ? "rebase" : "clear"),
       "SFTCAN: \"clear\" = later rows use their written L values; \"rebase\" = gaps stay shifted");
  line(fmt::format("slow_to_fit = {}", c.table_slow_to_fit),
       "a table over an axis limit: false = refused; true = reference slowed to fit");

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
  return o;
}

MachineConfig machine_config_or_default(const std::string& path) {
  return path.empty() ? default_machine_config() : load_machine_config(path);
}

}  // namespace cncore
