// The tool table the interpreter applies tool length offsets from (G43, G43.2, G10 L1/L10/L11):
// per tool its offsets along the axes and its diameter, in mm. It comes from the machine
// configuration's [[tools]] (length_mm, diameter_mm) and from a LinuxCNC tool table file
// (`--tool-table FILE`: lines "T1 P1 Z12.5 D6 ;comment"), whose entries replace those.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>

#include "core/geometry.hpp"

namespace cncore {

struct ToolEntry {
  std::uint32_t number = 0;
  std::uint32_t pocket = 0;
  std::array<double, kMaxAxes> offset_mm{};  // X Y Z A B C (rotary: degrees); Z is the length
  double diameter_mm = 0;
  friend bool operator==(const ToolEntry&, const ToolEntry&) = default;
};

using ToolTable = std::map<std::uint32_t, ToolEntry>;

// Reads a LinuxCNC tool table (.tbl). Words per line, case-insensitive, in any order: T (tool,
// required), P (pocket), X Y Z A B C (offsets, mm / deg), U V W (must be 0: cncore has no such
// axes), D (diameter), I J Q (angles and orientation of lathe tools, ignored); ";" starts a
// comment; blank lines are skipped. Errors are InputError(FILE, LINE, COL).
ToolTable read_tool_table(const std::string& path);
ToolTable parse_tool_table(const std::string& text, const std::string& source_name);

}  // namespace cncore
