// The machine used by the interpreter tests: the built-in 3-axis mill of spec 05 (travel
// X −300…300, Y −200…200, Z −200…100 mm), written out here so that the golden listings do not
// change if the built-in default ever does.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"

namespace cncore::interp::test {

inline MachineConfig test_machine() {
  MachineConfig m;
  m.name = "interpreter test mill";
  const double lo[3] = {-300, -200, -200};
  const double hi[3] = {300, 200, 100};
  for (std::size_t a = 0; a < 3; ++a) {
    m.axes[a].enabled = true;
    m.axes[a].min_mm = lo[a];
    m.axes[a].max_mm = hi[a];
    m.axes[a].max_speed_mm_min = 15000;
    m.axes[a].max_accel_mm_s2 = 2000;
  }
  m.max_loop_iterations = 100000;
  m.max_call_depth = 64;
  return m;
}

// The motion blocks (rapid, line, arc) of a program given as text, named `name` in errors.
inline std::vector<Block> motion_blocks(const std::string& text, const std::string& name,
                                        const MachineConfig& m = test_machine()) {
  Interpreter in(Interpreter::FromText{}, text, name, m, Options{});
  std::vector<Block> out;
  Block b;
  while (in.next(b)) {
    if (is_motion(b)) out.push_back(b);
  }
  return out;
}

// The formatted error (FILE:LINE:COL: error: …) of a program given as text; empty if it runs.
inline std::string error_of_text(const std::string& text, const std::string& name) {
  try {
    motion_blocks(text, name);
  } catch (const InputError& e) {
    return e.formatted();
  }
  return {};
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The format_block listing of a whole program (text in memory).
inline std::vector<std::string> listing(const std::string& text, const MachineConfig& m,
                                        const std::string& name = "test.ngc") {
  Interpreter in(Interpreter::FromText{}, text, name, m, Options{});
  std::vector<std::string> out;
  Block b;
  while (in.next(b)) out.push_back(format_block(b, m));
  return out;
}

}  // namespace cncore::interp::test
