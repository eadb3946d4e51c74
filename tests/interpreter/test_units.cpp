// Unit tests of the pieces: numbers, expressions, the reader's seeking, format_block, and
// interpreter behaviours that the golden listings do not show (options, streaming memory).
#include <gtest/gtest.h>
#include <malloc.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

double x_of(const std::string& expr) {
  const MachineConfig m = test_machine();
  Interpreter in(Interpreter::FromText{}, "G0 X" + expr + "\n", "u.ngc", m, Options{});
  Block b;
  EXPECT_TRUE(in.next(b));
  return b.end[kX];
}

TEST(Numbers, LeadingAndTrailingDotsAndSigns) {
  EXPECT_DOUBLE_EQ(x_of(".5"), 0.5);
  EXPECT_DOUBLE_EQ(x_of("5."), 5.0);
  EXPECT_DOUBLE_EQ(x_of("-0.25"), -0.25);
  EXPECT_DOUBLE_EQ(x_of("+7"), 7.0);
  EXPECT_DOUBLE_EQ(x_of("0012.5"), 12.5);
  EXPECT_DOUBLE_EQ(x_of("123.456789"), 123.456789);
}

TEST(Expressions, TrigIsInDegrees) {
  EXPECT_NEAR(x_of("[SIN[90]]"), 1.0, 1e-12);
  EXPECT_NEAR(x_of("[ACOS[0.5]]"), 60.0, 1e-9);
  EXPECT_NEAR(x_of("[ATAN[-1]/[0]]"), -90.0, 1e-9);
}

TEST(Expressions, PowerAndModEdgeCases) {
  EXPECT_DOUBLE_EQ(x_of("[[-2] ** 3]"), -8.0);
  EXPECT_DOUBLE_EQ(x_of("[7.5 MOD 2]"), 1.5);
  EXPECT_DOUBLE_EQ(x_of("[-1 MOD 5]"), 4.0);
}

TEST(Options, ParamsAndVarsSeedTheProgram) {
  const MachineConfig m = test_machine();
  Options o;
  o.params[7] = 12.5;
  o.named_params["Depth"] = -3;
  Interpreter in(Interpreter::FromText{}, "G0 X#7 Z#<depth>\n", "o.ngc", m, o);
  Block b;
  ASSERT_TRUE(in.next(b));
  EXPECT_DOUBLE_EQ(b.end[kX], 12.5);
  EXPECT_DOUBLE_EQ(b.end[kZ], -3.0);
}

TEST(Parameters, PositionAndOffsetNumbersFollowLinuxCnc) {
  const MachineConfig m = test_machine();
  const char* program =
      "G10 L2 P2 X5\nG55 G0 X10 Y3\n"
      "G0 X[#5420 + #5220]\n"       // program X 10 + system 2 → 12
      "G0 Y[#5242 * 0 + #5241]\n";  // work offset X of G55 = 5 → program Y 5
  Interpreter in(Interpreter::FromText{}, program, "p.ngc", m, Options{});
  Block b;
  ASSERT_TRUE(in.next(b));
  EXPECT_DOUBLE_EQ(b.end[kX], 15.0);
  ASSERT_TRUE(in.next(b));
  EXPECT_DOUBLE_EQ(b.end[kX], 17.0);
  ASSERT_TRUE(in.next(b));
  EXPECT_DOUBLE_EQ(b.end[kY], 5.0);
}

TEST(FormatBlock, EnabledAxesOnlyAndNoNegativeZero) {
  MachineConfig m = test_machine();
  m.axes[kA].enabled = true;
  m.axes[kA].rotary = true;
  Block b;
  b.kind = BlockKind::kLine;
  b.line = 3;
  b.end[kX] = -0.00001;
  b.end[kA] = 90;
  b.feed_mm_min = 1000;
  EXPECT_EQ(format_block(b, m),
            "N3 LINE from 0.0000 0.0000 0.0000 0.0000 to 0.0000 0.0000 0.0000 90.0000 F1000.000");
  EXPECT_EQ(format_block(b), "N3 LINE from 0.0000 0.0000 0.0000 to 0.0000 0.0000 0.0000 F1000.000");
}

TEST(RotaryAxes, DegreesAreNeverConvertedByInchMode) {
  MachineConfig m = test_machine();
  m.axes[kA].enabled = true;
  m.axes[kA].rotary = true;
  m.axes[kA].min_mm = -360;
  m.axes[kA].max_mm = 360;
  Interpreter in(Interpreter::FromText{}, "G20 G1 X1 A90 F10\n", "r.ngc", m, Options{});
  Block b;
  ASSERT_TRUE(in.next(b));
  EXPECT_DOUBLE_EQ(b.end[kX], 25.4);
  EXPECT_DOUBLE_EQ(b.end[kA], 90.0);
}

TEST(Errors, MissingFileIsAnInputErrorNamingIt) {
  const MachineConfig m = test_machine();
  try {
    Interpreter in("/nonexistent/dir/p.ngc", m, Options{});
    FAIL() << "opened a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(e.formatted().find("/nonexistent/dir/p.ngc"), std::string::npos);
  }
}

TEST(Errors, LineEndingsCrLfAndNoFinalNewline) {
  const MachineConfig m = test_machine();
  Interpreter in(Interpreter::FromText{}, "G0 X1\r\nG0 X2", "crlf.ngc", m, Options{});
  Block b;
  ASSERT_TRUE(in.next(b));
  ASSERT_TRUE(in.next(b));
  EXPECT_DOUBLE_EQ(b.end[kX], 2.0);
  EXPECT_EQ(b.line, 2u);
  EXPECT_FALSE(in.next(b));
}

// The file reader crosses chunk boundaries and seeks back for loops: a long program with a
// loop at the end gives the same listing from a file as from memory.
TEST(Streaming, FileAndMemoryAgreeAcrossChunksAndSeeks) {
  std::string text = "G1 F1000\n";
  for (int i = 0; i < 20000; ++i) {
    text += "X" + std::to_string(i % 100) + ".5 Y" + std::to_string(i % 37) + " (padding text)\n";
  }
  text += "#1=0\no9 while [#1 LT 5]\n#1=[#1+1]\nG1 Z[-#1]\no9 endwhile\nM2\n";
  const std::string path =
      (std::filesystem::temp_directory_path() / "cncore_interp_stream_test.ngc").string();
  {
    std::ofstream out(path, std::ios::binary);
    out << text;
  }
  const MachineConfig m = test_machine();
  std::vector<std::string> from_file;
  {
    Interpreter in(path, m, Options{});
    Block b;
    while (in.next(b)) from_file.push_back(format_block(b, m));
  }
  std::filesystem::remove(path);
  const std::vector<std::string> from_memory = listing(text, m);
  EXPECT_EQ(from_file, from_memory);
  ASSERT_GE(from_file.size(), 6u);
  EXPECT_EQ(from_file[from_file.size() - 2].substr(0, 8), "N20005 L");
}

// Memory does not grow with program length: the heap in use after 300 000 lines equals the heap
// in use after 1 000 lines (glibc mallinfo2), with a subroutine defined at the top of the file
// and called from far below (seeks outside the reader's chunk) and a loop in between.
TEST(Streaming, HeapInUseDoesNotGrowWithProgramLength) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "cncore_interp_heap_test.ngc").string();
  {
    std::ofstream out(path, std::ios::binary);
    out << "o<peck> sub\nG1 Z-1\nG0 Z1\no<peck> endsub\nG21 G90 F1200\n";
    for (int i = 0; i < 300000; ++i) {
      out << "G1 X" << (i % 500) * 0.1 << " Y" << (i % 300) * 0.1 << " Z0.5 (cut)\n";
      if (i % 50000 == 49999)
        out << "o<peck> call\n#1=0\no2 while [#1 LT 3]\n#1=[#1+1]\no2 endwhile\n";
    }
    out << "M2\n";
  }
  const MachineConfig m = test_machine();
  std::size_t in_use_early = 0, in_use_late = 0, blocks = 0, calls = 0;
  {
    Interpreter in(path, m, Options{});
    Block b;
    while (in.next(b)) {
      ++blocks;
      if (b.line == 2) ++calls;
      if (blocks == 1000) in_use_early = mallinfo2().uordblks;
    }
    in_use_late = mallinfo2().uordblks;
  }
  std::filesystem::remove(path);
  EXPECT_EQ(calls, 6u);
  EXPECT_GT(blocks, 290000u);
  EXPECT_LT(in_use_late, in_use_early + 16 * 1024)
      << "heap grew from " << in_use_early << " to " << in_use_late << " bytes";
}

}  // namespace
}  // namespace cncore::interp::test

namespace cncore::interp::test {
namespace {

// `cncore check` reports every error: after an error the interpreter goes on with the next line.
TEST(Recovery, EveryErrorOfAProgramIsReportedWithItsLine) {
  const MachineConfig m = test_machine();
  const std::string program =
      "G21 G90 G1 F1000\n"  // 1
      "X10 E5\n"            // 2: unknown word
      "X20\n"               // 3: fine
      "G0 G1 X30\n"         // 4: two words of one modal group
      "X#<undefined>\n"     // 5: undefined parameter
      "X40\n";              // 6: fine
  Interpreter in(Interpreter::FromText{}, program, "r.ngc", m, Options{});
  std::vector<std::uint32_t> error_lines;
  std::vector<double> ends_x;
  for (;;) {
    try {
      Block b;
      if (!in.next(b)) break;
      if (b.kind == BlockKind::kLine) ends_x.push_back(b.end[kX]);
    } catch (const InputError& e) {
      error_lines.push_back(e.line());
      if (!in.recover()) break;
    }
  }
  EXPECT_EQ(error_lines, (std::vector<std::uint32_t>{2, 4, 5}));
  EXPECT_EQ(ends_x, (std::vector<double>{20, 40}));
}

TEST(Recovery, AnErrorAtTheEndOfTheProgramEndsIt) {
  const MachineConfig m = test_machine();
  Interpreter in(Interpreter::FromText{}, "o100 sub\nG0 X1\n", "e.ngc", m, Options{});
  int errors = 0;
  for (int guard = 0; guard < 10; ++guard) {
    try {
      Block b;
      if (!in.next(b)) break;
    } catch (const InputError&) {
      ++errors;
      if (!in.recover()) break;
    }
  }
  EXPECT_EQ(errors, 1);
}

// [interpreter] parameter_units: programs read and write the offset parameters in the
// machine's unit whatever G20/G21 is active; the offsets themselves are the same.
TEST(ParameterUnits, OffsetParametersAreInTheMachinesUnit) {
  for (const bool inch : {false, true}) {
    MachineConfig m = test_machine();
    m.parameters_inch = inch;
    std::vector<std::string> said;
    Options o;
    o.on_message = [&](const std::string& text) { said.push_back(text); };
    Interpreter in(Interpreter::FromText{},
                   "G20 G10 L2 P1 X1\n(debug,#5221)\nG21\n(debug,#5221)\n#5222=2\n"
                   "G21 G90 G0 X0 Y0\n",
                   "p.ngc", m, o);
    Block b, last;
    while (in.next(b)) last = b;
    const std::string one = inch ? "1.000000" : "25.400000";
    EXPECT_EQ(said, (std::vector<std::string>{one, one}));
    EXPECT_NEAR(last.end[kX], 25.4, 1e-9) << "G10 L2 X1 in G20 is 25.4 mm either way";
    EXPECT_NEAR(last.end[kY], inch ? 50.8 : 2, 1e-9) << "#5222=2 in the parameters' unit";
  }
}

std::vector<std::string> messages_of(const std::string& text) {
  std::vector<std::string> said;
  Options o;
  o.on_message = [&](const std::string& t) { said.push_back(t); };
  Interpreter in(Interpreter::FromText{}, text, "p.ngc", test_machine(), o);
  Block b;
  while (in.next(b)) {
  }
  return said;
}

// LinuxCNC's predefined named parameters read the modal state: G codes as ten times their
// number, flags as 1 or 0, F and S in program units.
TEST(Parameters, NamedModalStateFollowsLinuxCnc) {
  const auto said = messages_of(
      "G20 G91 G18 G55 G99 G95 F0.01 S500 M3 T2\nG1 Z-0.1\n"
      "(debug,#<_line> #<_motion_mode> #<_plane> #<_coord_system> #<_imperial> #<_metric>)\n"
      "(debug,#<_incremental> #<_retract_r_plane> #<_units_per_rev> #<_feed> #<_rpm>)\n"
      "(debug,#<_spindle_on> #<_spindle_cw> #<_selected_tool> #<_current_tool> #<_ccomp>)\n"
      "G21 G90 G17 G59.2 G80 G94 F100 M5\n"
      "(debug,#<_motion_mode> #<_plane> #<_coord_system> #<_metric> #<_absolute> #<_feed>)\n"
      "o1 sub\n(debug,#<_call_level>)\no1 endsub\no1 call\n(debug,#<_call_level>)\n");
  EXPECT_EQ(said, (std::vector<std::string>{
                      "3.000000 10.000000 180.000000 550.000000 1.000000 0.000000",
                      "1.000000 1.000000 1.000000 0.010000 500.000000",
                      "1.000000 1.000000 2.000000 0.000000 400.000000",
                      "800.000000 170.000000 592.000000 1.000000 1.000000 100.000000", "1.000000",
                      "0.000000"}));
}

// `return` may carry any O label inside a subroutine (LinuxCNC); a return without a value
// leaves 0 in #<_value>.
TEST(Parameters, ReturnValues) {
  const auto said = messages_of(
      "o1 sub\no2 if [#1 GT 0]\no2 return [#1 * 2]\no2 endif\no1 endsub\n"
      "o1 call [4]\n(debug,#<_value> #<_value_returned>)\n"
      "o1 call [-1]\n(debug,#<_value> #<_value_returned>)\n");
  EXPECT_EQ(said, (std::vector<std::string>{"8.000000 1.000000", "0.000000 0.000000"}));
}

}  // namespace
}  // namespace cncore::interp::test
