// The machine state that outlives the process (`cncore serve --state-dir`): the interpreter's
// persistent parameters (LinuxCNC's 5161…5390: G28/G30 positions, G92, the work offsets
// G54…G59.3 and the active system), the tool table and the last machine position. One JSON file,
// replaced atomically (temporary + fsync + rename + fsync of the folder): a crash at any moment
// leaves the old file or the new one, never a broken one.
#pragma once

#include <map>
#include <string>

#include "config/tool_table.hpp"
#include "core/geometry.hpp"

namespace cncore::runtime {

struct PersistentState {
  std::map<int, double> parameters;
  ToolTable tools;  // the machine's [[tools]] with the G10 L1/L10/L11 writes
  AxisVec position;
  bool has_position = false;
  friend bool operator==(const PersistentState&, const PersistentState&) = default;
};

// The parameters kept: LinuxCNC's persistent range.
inline constexpr int kFirstPersistentParameter = 5161;
inline constexpr int kLastPersistentParameter = 5390;

// $XDG_STATE_HOME/cncore, else $HOME/.local/state/cncore.
std::string default_state_dir();
std::string state_file(const std::string& dir);
// The saved state, or an empty one when the folder has none. Throws InputError (FILE:LINE:COL)
// on a file that is not a state file.
PersistentState load_state(const std::string& dir);
// Creates the folder if needed. Throws std::runtime_error with the reason on failure.
void save_state(const std::string& dir, const PersistentState& state);

}  // namespace cncore::runtime
