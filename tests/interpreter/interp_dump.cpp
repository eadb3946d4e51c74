// interp_dump PROGRAM: prints the block listing (format_block) of PROGRAM on the interpreter
// test machine, or the error. Used to check golden listings written by hand.
#include <cstdio>

#include "test_machine.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: interp_dump PROGRAM\n");
    return 2;
  }
  using namespace cncore;
  const MachineConfig m = interp::test::test_machine();
  try {
    interp::Interpreter in(argv[1], m, interp::Options{});
    Block b;
    while (in.next(b)) std::printf("%s\n", interp::format_block(b, m).c_str());
  } catch (const InputError& e) {
    std::printf("ERROR %s\n", e.formatted().c_str());
    return 1;
  }
  return 0;
}
