// [servo] of the machine configuration (`cncore serve`): reading with every key validated at its
// FILE:LINE:COL, and the commented printout. Private to cncore_config (it includes toml++).
#pragma once

#include <toml++/toml.h>

#include <string>

#include "config/machine_config.hpp"

namespace cncore::config_detail {

void read_servo_section(const std::string& file, const toml::table& t, ServoConfig& s);
std::string servo_section_to_toml(const ServoConfig& s);

}  // namespace cncore::config_detail
