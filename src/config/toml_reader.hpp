// Internal to the config library: typed reads of TOML values where every error names the key
// and points at it (FILE:LINE:COL). Includes toml++, so only the config .cpp files include it.
#pragma once

#include <fmt/format.h>
#include <toml++/toml.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.hpp"

namespace cncore::config_detail {

class TomlReader {
 public:
  explicit TomlReader(const std::string& file) : file_(file) {}

  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const toml::source_region& where, const std::string& message) const {
    throw InputError(file_, static_cast<std::uint32_t>(where.begin.line),
                     static_cast<std::uint32_t>(where.begin.column), message);
  }

  // A finite number (integer or float); the error points at `where`.
  double number_at(const toml::source_region& where, const toml::node& node,
                   const std::string& name) const {
    if (const auto* f = node.as_floating_point()) {
      if (!std::isfinite(f->get())) fail(where, fmt::format("{} must be a finite number", name));
      return f->get();
    }
    if (const auto* i = node.as_integer()) return static_cast<double>(i->get());
    fail(where, fmt::format("{} must be a number", name));
  }
  double number(const toml::key& key, const toml::node& node, const std::string& name) const {
    return number_at(key.source(), node, name);
  }

  double positive(const toml::key& key, const toml::node& node, const std::string& name,
                  const char* unit) const {
    const double v = number(key, node, name);
    if (v <= 0) fail(key.source(), fmt::format("{} = {} must be > 0 {}", name, v, unit));
    return v;
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

  bool boolean(const toml::key& key, const toml::node& node, const std::string& name) const {
    if (const auto* b = node.as_boolean()) return b->get();
    fail(key.source(), fmt::format("{} must be true or false", name));
  }

  std::int64_t integer(const toml::key& key, const toml::node& node,
                       const std::string& name) const {
    if (const auto* i = node.as_integer()) return i->get();
    fail(key.source(), fmt::format("{} must be an integer", name));
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

  std::uint32_t count(const toml::key& key, const toml::node& node, const std::string& name,
                      std::int64_t lo, std::int64_t hi) const {
    return static_cast<std::uint32_t>(integer_in(key, node, name, lo, hi));
  }

  std::string text(const toml::key& key, const toml::node& node, const std::string& name) const {
    const auto* s = node.as_string();
    if (s == nullptr) fail(key.source(), fmt::format("{} must be a string", name));
    return s->get();
  }

  const toml::table& table(const toml::key& key, const toml::node& node,
                           const std::string& name) const {
    const auto* t = node.as_table();
    if (t == nullptr) fail(key.source(), fmt::format("{} must be a table", name));
    return *t;
  }

  // [x, y, z] of finite numbers.
  std::array<double, 3> triple(const toml::key& key, const toml::node& node,
                               const std::string& name) const {
    const auto* a = node.as_array();
    if (a == nullptr || a->size() != 3) {
      fail(key.source(), fmt::format("{} must be an array of 3 numbers [x, y, z]", name));
    }
    std::array<double, 3> v{};
    for (std::size_t i = 0; i < 3; ++i) v[i] = number(key, *a->get(i), name);
    return v;
  }

  // "unknown key 'NAME'" followed by `hint` (e.g. " (keys here: a, b)").
  [[noreturn]] void unknown(const toml::key& key, const std::string& name,
                            const std::string& hint = {}) const {
    fail(key.source(), fmt::format("unknown key '{}'{}", name, hint));
  }

 private:
  const std::string& file_;
};

}  // namespace cncore::config_detail
