#include "program_blocks.hpp"

namespace cncore::testing {

std::vector<Block> read_blocks(const std::string& program_path, const MachineConfig& machine,
                               const interp::Options& options) {
  interp::Interpreter in(program_path, machine, options);
  std::vector<Block> out;
  Block b;
  while (in.next(b)) out.push_back(b);
  return out;
}

}  // namespace cncore::testing
