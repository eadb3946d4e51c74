// G-code interpreter (RS274/NGC as LinuxCNC documents it, with Fanuc habits): turns a part
// program into a stream of Blocks in machine coordinates and mm. It streams: it reads the
// program as it goes (seeking back only for loops and subroutine calls), so memory does not
// grow with program length. It knows nothing about time.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "config/tool_table.hpp"
#include "core/block.hpp"
#include "interpreter/modal_state.hpp"

namespace cncore::interp {

// #5070, as in LinuxCNC: 1 when the last G38 move tripped the probe, else 0.
inline constexpr int kParamProbeTripped = 5070;

struct Options {
  std::map<int, double> params;                // --param N=V: numbered parameters #N
  std::map<std::string, double> named_params;  // --var NAME=V: named parameters #<NAME>
  // The modal state to start in (a controller carries it from one MDI line or program to the
  // next); none: the defaults (G17 G21 G90 G54 G64 G80).
  std::optional<ModalState> modal;
  // --subroutine-path DIR: where `o<name> call` of a subroutine the program does not define
  // looks for name.ngc, after the program's own folder (LinuxCNC's SUBROUTINE_PATH).
  std::vector<std::string> subroutine_path;
  ToolTable tools;  // --tool-table FILE: replaces the machine's [[tools]] entries it lists
  // A tool missing from the table is an error (default: when the machine or `tools` lists any).
  std::optional<bool> tools_listed;
  // The operator's block delete switch: on, lines starting with "/" are skipped; off, they run.
  bool block_delete = true;
  // Operator messages, "(msg,…)" and "(debug,…)" comments (LinuxCNC's MESSAGE), as their lines
  // run; none: they are ignored.
  std::function<void(const std::string& text)> on_message;
  // Emit G0/G1 moves that go nowhere (LinuxCNC's canonical listing has them; the planner
  // needs none).
  bool zero_length_moves = false;
};

// What turns a block's machine coordinates into LinuxCNC's canonical (program) positions: the
// program units and the frame in force when the block was made,
//   program = R(−θ)·(machine − tool − work) − g92   (R turns X and Y).
struct CanonFrame {
  double unit_mm = 1;  // 25.4 in G20
  AxisVec tool_offset_mm;
  AxisVec work_offset_mm;   // the active system's (G54…G59.3)
  AxisVec g92_offset_mm;    // G92 / G52 while applied
  double rotation_deg = 0;  // the active system's XY rotation (G10 L2 R)
};

class Interpreter {
 public:
  // Opens the program file. Throws InputError if it cannot be read.
  Interpreter(const std::string& path, const MachineConfig& machine, const Options& options);
  // Interprets program text held in memory; `name` is the file name used in error messages.
  struct FromText {};
  Interpreter(FromText, std::string text, std::string name, const MachineConfig& machine,
              const Options& options);
  // Interprets lines as `pull` hands them over (false: no more), blocking in next() while pull
  // waits: a controller's streamed lines. Loops and subroutine calls are refused (no seeking).
  struct FromLines {};
  Interpreter(FromLines, std::function<bool(std::string& line)> pull, std::string name,
              const MachineConfig& machine, const Options& options);
  ~Interpreter();
  Interpreter(const Interpreter&) = delete;
  Interpreter& operator=(const Interpreter&) = delete;

  // Produces the next block. Returns false at the end of the program (M2, M30, or end of
  // file). Throws InputError (FILE:LINE:COL) on the first error in the program.
  bool next(Block& out);

  // After next() threw InputError: drop what the failing line produced and continue with the
  // following line, so that `cncore check` can report every error of a program. Returns false
  // when nothing can follow (the error was found at the end of the program). Later errors may
  // be consequences of the first (the failing line's modal changes may be half applied).
  // After a move beyond the travel, the interpreter continues from that move's end point (the
  // later blocks were written from there) and judges no travel again until a move ends inside
  // it: see beyond_travel().
  bool recover();
  // True while the interpreter continues from a position beyond the travel after recover().
  bool beyond_travel() const;

  // The numbered parameters first…last as they stand now (a controller keeps LinuxCNC's
  // persistent range 5161…5390 between programs: offsets, G28/G30 positions).
  std::map<int, double> numbered_parameters(int first, int last) const;
  // The modal state as it stands now (see Options::modal).
  ModalState modal_state() const;
  // The tool table as it stands now: the machine's and Options::tools entries with the program's
  // G10 L1/L10/L11 writes (a controller keeps it between programs and across restarts).
  const ToolTable& tool_table() const;

  // The frame of the block next() handed out last (for CanonPrinter).
  CanonFrame canon_frame() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// `cncore check --canon`: LinuxCNC's canonical-machine calls (STRAIGHT_TRAVERSE, STRAIGHT_FEED,
// ARC_FEED, SET_FEED_RATE, DWELL), one per line, for each block in turn.
class CanonPrinter {
 public:
  std::string print(const Block& block, const CanonFrame& frame);

 private:
  double last_feed_ = -1;
  double last_sync_ = 0;  // the pitch of the spindle synchronisation in force (0: none)
  double last_sync_deg_ = std::numeric_limits<double>::quiet_NaN();  // its start angle
};

// One line of `cncore check --blocks` for a block (stable text format used by golden tests,
// documented in docs/gcode.md). This overload prints the X, Y and Z axes.
std::string format_block(const Block& block);
// The same, printing the axes enabled on `machine` (in X Y Z A B C order).
std::string format_block(const Block& block, const MachineConfig& machine);

}  // namespace cncore::interp
