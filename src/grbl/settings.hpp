// Grbl's `$` settings mapped onto cncore's machine configuration. Grbl stores step and pin
// settings that mean nothing to a controller without step generation ($0–$6, $100–$102): they are
// reported and accepted without effect. The rest read and write MachineConfig fields: $110–$112
// max rates, $120–$122 accelerations, $130–$132 travel, $24/$25/$27 homing, $11 the contour
// tolerance (docs/senders.md).
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>

#include "config/machine_config.hpp"

namespace cncore::grbl {

class Settings {
 public:
  // The values the configuration implies (and Grbl's defaults for those without a meaning here).
  static Settings from_machine(const MachineConfig& machine);

  // "$0=10\r\n$1=25\r\n…" in Grbl's order.
  std::string listing() const;
  std::optional<double> value(int number) const;
  // Sets $number; returns the Grbl error code when refused (3: no such setting or a value this
  // controller cannot honour, 4: negative or zero where a positive value is needed).
  std::optional<int> write(int number, double value);
  // Puts the settings that have a meaning here into `machine`.
  void apply(MachineConfig& machine) const;

  // The values and startup lines as JSON (the state folder's grbl.json) and back; a bad file
  // or value is ignored (the configuration's value stays).
  std::string to_json() const;
  void merge_json(const std::string& text);

  std::uint32_t status_mask() const { return static_cast<std::uint32_t>(values_.at(10)); }

  // $N0, $N1: lines run after the welcome (connect, soft reset) when the machine is idle.
  std::array<std::string, 2> startup;

 private:
  std::map<int, double> values_;
};

}  // namespace cncore::grbl
