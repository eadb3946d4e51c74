// Internal to the config library: reads the cutting-simulation sections of a machine
// configuration. Includes toml++, so only machine_config.cpp and cutting_config.cpp include it.
#pragma once

#include <toml++/toml.h>

#include <string>

#include "config/cutting_config.hpp"

namespace cncore {

// Where the keys checked across sections were written (for the error position).
struct CuttingSources {
  toml::source_region default_tool, material, stock;
};

// True when `key` names a cutting section ("stock", "tools", "cutting"); it is then read into
// `config`. Errors throw InputError(file, line, col) naming the key.
bool read_cutting_section(const std::string& file, const toml::key& key, const toml::node& node,
                          CuttingConfig& config, CuttingSources& where);
// Checks across sections (after the whole file is read): the stock's memory cap, the default
// tool in the table, a material name known when kc is not given. `file` names the source.
void validate_cutting_config(const std::string& file, const CuttingConfig& config,
                             const CuttingSources& where);

}  // namespace cncore
