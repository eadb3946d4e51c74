// The interpreted blocks of a part program, through the interpreter's public API only
// (library cncore_test_support_interp): what the checker compares a trajectory with.
#pragma once

#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "core/block.hpp"
#include "interpreter/interpreter.hpp"

namespace cncore::testing {

// Every block of the program (motion, dwell, aux), in order. Throws InputError on a bad program.
std::vector<Block> read_blocks(const std::string& program_path, const MachineConfig& machine,
                               const interp::Options& options = {});

}  // namespace cncore::testing
