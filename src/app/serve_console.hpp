// The text console of `cncore serve` (standard input): one command per line, one reply per
// command ("ok", "error: …", or a JSON status line), so a shell script or a test can drive the
// controller through its control interface. The commands are listed in docs/runtime.md.
#pragma once

#include <string>

#include "runtime/control.hpp"

namespace cncore::app {

// Runs one console line. Returns the reply; sets `quit` on "quit".
std::string console_command(runtime::Controller& c, const std::string& line, bool& quit);

// The status as one JSON line (the console's "status" reply).
std::string status_json(const runtime::Status& s, const MachineConfig& machine);

}  // namespace cncore::app
