// Shared pieces of the `cncore` commands (src/app only): the usage error (exit code 2), parsing
// of command-line values, the machine configuration.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "config/machine_config.hpp"
#include "interpreter/interpreter.hpp"
#include "simulation/run.hpp"

namespace cncore::app {

// A command-line value that is wrong (exit code 2).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string trim(std::string_view s);

// The whole text must be a finite number.
std::optional<double> to_number(std::string_view text);

// A feed override in % from the option `option`: a number in 0 … max_pct, else UsageError.
double override_value(const std::string& option, std::string_view text, double max_pct);

// "NAME=VALUE" with a numeric value, else UsageError naming the option.
std::pair<std::string, double> name_value(const std::string& option, const std::string& arg);

// --var NAME=V, --param N=V and --tool-table FILE (empty: none) of `run` and `check`.
interp::Options interpreter_options(const std::vector<std::string>& vars,
                                    const std::vector<std::string>& params,
                                    const std::string& tool_table = {});

// The configuration file, or the built-in machine for an empty path (InputError when bad).
MachineConfig machine_from(const std::string& path);

// InputError "cannot open [WHAT]: REASON" (strerror, or "it is a directory") for a file that
// cannot be read, before anything is written.
void require_readable(const std::string& path, std::string_view what = {});

}  // namespace cncore::app
