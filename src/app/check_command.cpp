// `cncore check`: interpret a program only and report every error (or list the blocks).
#include <fmt/format.h>

#include <cstdio>
#include <iostream>
#include <string>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "core/error.hpp"
#include "interpreter/interpreter.hpp"

namespace cncore::app {

int command_check(const CheckArgs& a) {
  const MachineConfig machine = machine_from(a.machine);
  interp::Options options = interpreter_options(a.vars, a.params, a.tool_table);
  options.subroutine_path = a.subroutine_path;
  std::string out;
  if (a.canon) {
    // As LinuxCNC's listing: moves that go nowhere and the operator messages, in program order.
    options.zero_length_moves = true;
    options.on_message = [&out](const std::string& text) { out += "MESSAGE(\"" + text + "\")\n"; };
  }
  require_readable(a.program);
  interp::Interpreter interpreter(a.program, machine, options);
  Block b;
  interp::CanonPrinter canon;
  std::uint64_t blocks = 0, motion = 0;
  auto flush = [&out] {
    std::fwrite(out.data(), 1, out.size(), stdout);
    out.clear();
  };
  // Every error is reported: after one, the interpreter goes on with the next line. Errors
  // after the first may be its consequences; a repeated error or too many end the check. After
  // a move beyond the travel the later blocks are not judged against the travel until they
  // return inside it (one note says so).
  constexpr int kMaxErrors = 50;
  int errors = 0;
  std::string last_error;
  bool noted = false;  // the note on blocks continuing beyond the travel was printed
  for (;;) {
    try {
      if (!interpreter.next(b)) break;
    } catch (const InputError& e) {
      flush();  // the blocks before the error are listed, then the error goes to stderr
      std::fflush(stdout);
      const std::string text = e.formatted();
      if (text == last_error) break;
      std::cerr << text << "\n";
      last_error = text;
      if (++errors >= kMaxErrors) {
        std::cerr << a.program << ": too many errors, stopping the check\n";
        break;
      }
      if (!interpreter.recover()) break;
      if (interpreter.beyond_travel() && !noted) {
        noted = true;
        std::cerr << fmt::format(
            "{}:{}:{}: note: the blocks after this one continue from its end point, beyond the "
            "travel; their travel is not checked until a move ends inside it again\n",
            e.file(), e.line(), e.col());
      }
      continue;
    }
    ++blocks;
    if (is_motion(b)) {
      ++motion;
    }
    if (a.canon) {
      out += canon.print(b, interpreter.canon_frame());
    } else if (a.blocks) {
      out += interp::format_block(b, machine);
      out += '\n';
    }
    if (out.size() > (1 << 16)) flush();
  }
  if (errors > 0) {
    flush();
    std::fflush(stdout);
    return 1;
  }
  if (!a.blocks && !a.canon)
    out = fmt::format("{}: ok, {} blocks ({} motion)\n", a.program, blocks, motion);
  std::fwrite(out.data(), 1, out.size(), stdout);
  std::fflush(stdout);
  return 0;
}

}  // namespace cncore::app
