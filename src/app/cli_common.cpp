#include "app/cli_common.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "config/tool_table.hpp"
#include "core/error.hpp"

namespace cncore::app {

std::string trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return std::string(s);
}

std::optional<double> to_number(std::string_view text) {
  const std::string s = trim(text);
  if (s.empty()) return std::nullopt;
  double v = 0;
  const char* first = s.data();
  if (*first == '+') ++first;
  const auto [end, ec] = std::from_chars(first, s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

double override_value(const std::string& option, std::string_view text, double max_pct) {
  const auto v = to_number(text);
  if (!v) throw UsageError(fmt::format("{}: '{}' is not a number", option, text));
  if (*v < 0 || *v > max_pct) {
    throw UsageError(fmt::format("{}: override {} % is outside 0 … {} % (machine max_override_pct)",
                                 option, *v, max_pct));
  }
  return *v;
}

std::pair<std::string, double> name_value(const std::string& option, const std::string& arg) {
  const std::size_t eq = arg.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw UsageError(fmt::format("{}: '{}' is not NAME=VALUE", option, arg));
  }
  const auto v = to_number(std::string_view(arg).substr(eq + 1));
  if (!v) throw UsageError(fmt::format("{}: '{}': the value must be a number", option, arg));
  return {trim(std::string_view(arg).substr(0, eq)), *v};
}

interp::Options interpreter_options(const std::vector<std::string>& vars,
                                    const std::vector<std::string>& params,
                                    const std::string& tool_table) {
  interp::Options o;
  if (!tool_table.empty()) o.tools = read_tool_table(tool_table);
  for (const std::string& a : vars) {
    auto [name, value] = name_value("--var", a);
    for (const char c : name) {
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) {
        throw UsageError(fmt::format("--var: '{}': a name has letters, digits and _ only", a));
      }
    }
    o.named_params[name] = value;
  }
  for (const std::string& a : params) {
    auto [name, value] = name_value("--param", a);
    int n = 0;
    const auto [end, ec] = std::from_chars(name.data(), name.data() + name.size(), n);
    if (ec != std::errc() || end != name.data() + name.size() || n < 1) {
      throw UsageError(
          fmt::format("--param: '{}': the parameter number must be an integer >= 1", a));
    }
    o.params[n] = value;
  }
  return o;
}

MachineConfig machine_from(const std::string& path) {
  if (!path.empty()) require_readable(path, "machine configuration");
  return machine_config_or_default(path);
}

void require_readable(const std::string& path, std::string_view what) {
  const std::string subject = what.empty() ? "cannot open" : fmt::format("cannot open {}", what);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, 0, 0, subject + ": it is a directory");
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr)
    throw InputError(path, 0, 0, fmt::format("{}: {}", subject, std::strerror(errno)));
  std::fclose(f);
}

}  // namespace cncore::app
