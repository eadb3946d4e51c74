// [probe] of the machine configuration (G38.2–G38.5): the solids the simulated probe touches.
// Reading with every key validated at its FILE:LINE:COL, and the commented printout. Private to
// cncore_config (it includes toml++).
#pragma once

#include <toml++/toml.h>

#include <string>

#include "config/machine_config.hpp"

namespace cncore::config_detail {

void read_probe_section(const std::string& file, const toml::table& t, ProbeConfig& p);
std::string probe_section_to_toml(const ProbeConfig& p);

}  // namespace cncore::config_detail
