// The page's API without the HTTP around it: the status event it streams and the controls it
// posts, each turned into one call of runtime::Controller (docs/hmi.md lists them).
#pragma once

#include <string>
#include <string_view>

#include "runtime/control.hpp"

namespace cncore::hmi {

class ProgramView;

// One status event: positions (machine, work, actual), offsets, tool, feeds, overrides,
// spindle, load, state, line and alarm. `view` (may be null) gives the programmed feed at the
// line under the tool.
std::string status_event_json(const runtime::Status& s, const MachineConfig& machine,
                              const ProgramView* view, double time_s);

// The machine as the page draws it: axes with their travel, feeds, override range, the stock.
std::string machine_json(const MachineConfig& machine);

// The height map for the page: the binary grid of `cncore run --heightmap-grid` ("CNCZMAP1",
// u32 nx, ny, f64 x0, y0, cell in mm, then nx·ny float32 heights row by row, little-endian).
std::string heightmap_binary(const runtime::HeightMapGrid& grid);

struct Reply {
  int http_status = 200;  // 200 done, 400 a malformed request, 409 refused by the controller
  std::string body;       // {"ok":true} or {"ok":false,"error":"…"}
};

// A control posted to /api/<name> with a JSON body (names: start, hold, resume, reset, estop,
// unlock, home, jog, jog-cancel, mdi, override, switches, check, reset-stock). Unknown name:
// 404.
Reply control(runtime::Controller& c, std::string_view name, const std::string& body);

Reply reply_of(const runtime::Result& r);
Reply bad_request(const std::string& why);

}  // namespace cncore::hmi
