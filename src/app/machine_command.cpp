// `cncore machine`: the machine configuration as TOML, every default filled in.
#include <iostream>
#include <string>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "config/machine_config.hpp"

namespace cncore::app {

int command_machine(const std::string& machine_path) {
  std::cout << machine_config_to_toml(machine_from(machine_path));
  return 0;
}

}  // namespace cncore::app
