// [adaptive] and [adaptive.plant] of the machine configuration (spec 04): reading with every
// key validated at its FILE:LINE:COL, and the commented printout. Private to cncore_config
// (it includes toml++).
#pragma once

#include <toml++/toml.h>

#include <string>

#include "config/machine_config.hpp"

namespace cncore::config_detail {

// Reads the [adaptive] table (with its optional [adaptive.plant] sub-table) into c.adaptive and
// c.adaptive_plant. Cross-key checks that involve other sections (upper_pct against
// motion.max_override_pct) are done by check_adaptive_section() once the whole file is read.
void read_adaptive_section(const std::string& file, const toml::key& key, const toml::node& node,
                           MachineConfig& c);
void check_adaptive_section(const std::string& file, const toml::table& root,
                            const MachineConfig& c);

// The commented TOML of both tables (empty depth profile: [adaptive.plant] as a commented
// example, so the printout reads back equal).
std::string adaptive_section_to_toml(const MachineConfig& c);

}  // namespace cncore::config_detail
