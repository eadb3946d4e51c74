// libFuzzer target: the machine configuration loader on arbitrary TOML text. Bad input must end
// in InputError. A configuration that loads must also survive the round trip the contract
// promises: machine_config_to_toml prints it, and parsing that text gives back the same
// configuration (spec 05: `cncore machine` prints TOML "ready to copy and edit").
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "config/machine_config.hpp"
#include "core/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  cncore::MachineConfig config;
  try {
    config = cncore::parse_machine_config(text, "fuzz.toml");
  } catch (const cncore::InputError& e) {
    (void)e.formatted();
    return 0;
  }
  const std::string printed = cncore::machine_config_to_toml(config);
  try {
    const cncore::MachineConfig again = cncore::parse_machine_config(printed, "printed.toml");
    if (!(again == config)) {
      std::fprintf(stderr, "round trip changed the configuration; printed:\n%s\n", printed.c_str());
      std::abort();
    }
  } catch (const cncore::InputError& e) {
    std::fprintf(stderr, "printed configuration does not load: %s\nprinted:\n%s\n",
                 e.formatted().c_str(), printed.c_str());
    std::abort();
  }
  return 0;
}
