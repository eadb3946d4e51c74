// Subroutines in files of their own (LinuxCNC's SUBROUTINE_PATH): `o<name> call` of a
// subroutine the program does not define runs name.ngc from the program's folder or the
// subroutine path; the moves, the arguments and the return value are those of the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "test_machine.hpp"

namespace cncore::interp::test {
namespace {

namespace fs = std::filesystem;

class SubFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) / (std::string("sub_files_") + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "lib");
  }
  void TearDown() override { fs::remove_all(dir_); }

  void write(const fs::path& path, const std::string& text) const {
    std::ofstream(dir_ / path) << text;
  }

  // The blocks of dir_/main.ngc, or the first error.
  std::vector<Block> run(const std::vector<std::string>& path = {}) const {
    Options o;
    o.subroutine_path = path;
    Interpreter in((dir_ / "main.ngc").string(), test_machine(), o);
    std::vector<Block> out;
    Block b;
    while (in.next(b)) out.push_back(b);
    return out;
  }

  std::string error(const std::vector<std::string>& path = {}) const {
    try {
      run(path);
    } catch (const InputError& e) {
      return e.formatted();
    }
    return "no error";
  }

  static std::vector<double> xs(const std::vector<Block>& blocks) {
    std::vector<double> out;
    for (const Block& b : blocks) {
      if (is_motion(b)) out.push_back(b.end[0]);
    }
    return out;
  }

  fs::path dir_;
};

TEST_F(SubFiles, AFileInTheProgramsFolderRunsWithItsArgumentsAndReturnsAValue) {
  write("square.ngc",
        "(the file's subroutine: moves to #1, then #1+#2)\n"
        "o<square> sub\nG1 X#1 F500\nX[#1+#2]\no<square> return [#1*2]\no<square> endsub\n"
        "G0 X999 (never run)\nM2\n");
  write("main.ngc",
        "G21 G90\no<square> call [10] [5]\nG0 X#<_value>\no<square> call [1] [2]\nM30\n");
  const std::vector<Block> blocks = run();
  EXPECT_EQ(xs(blocks), (std::vector<double>{10, 15, 20, 1, 3}));
  // The moves made in the file carry the line of the call in the program: what the run's report
  // and the operator's page show.
  std::vector<std::uint32_t> lines;
  for (const Block& b : blocks) {
    if (is_motion(b)) lines.push_back(b.line);
  }
  EXPECT_EQ(lines, (std::vector<std::uint32_t>{2, 2, 3, 4, 4}));
}

TEST_F(SubFiles, TheSubroutinePathIsSearchedAfterTheProgramsFolderAndFilesCallFiles) {
  write("lib/outer.ngc", "o<outer> sub\nG1 X1 F500\no<inner> call [7]\nG1 X2\no<outer> endsub\n");
  write("lib/inner.ngc", "o<inner> sub\nG1 X#1\no<inner> endsub\n");
  write("main.ngc", "G21 G90\no<outer> call\nG0 X0\nM30\n");
  EXPECT_EQ(error(), (dir_ / "main.ngc").string() +
                         ":2:1: error: subroutine o<outer> is not defined in this file, and no "
                         "outer.ngc is in the program's folder or on the subroutine path");
  const std::string lib = (dir_ / "lib").string();
  EXPECT_EQ(xs(run({lib})), (std::vector<double>{1, 7, 2, 0}));
  // The program's own folder comes first.
  write("inner.ngc", "o<inner> sub\nG1 X[#1+100]\no<inner> endsub\n");
  EXPECT_EQ(xs(run({lib})), (std::vector<double>{1, 107, 2, 0}));
}

TEST_F(SubFiles, AFileHoldsItsOneSubroutineAndErrorsNameTheFileAndLine) {
  // Defined after the file's endsub: not reachable from the file.
  write("seq.ngc", "o<seq> sub\no200 call\no<seq> endsub\no200 sub\nG1 X1 F9\no200 endsub\n");
  write("main.ngc", "o<seq> call\nM30\n");
  const std::string seq = (dir_ / "seq.ngc").string();
  EXPECT_EQ(error(), seq + ":2:1: error: subroutine o200 is not defined in this file");
  // A subroutine defined inside the file's subroutine.
  write("seq.ngc", "o<seq> sub\no100 sub\no100 endsub\no<seq> endsub\n");
  EXPECT_EQ(error(), seq +
                         ":2:1: error: o100 sub in the file of o<seq>: a subroutine's file "
                         "defines that subroutine only");
  // A file without the subroutine's line.
  write("seq.ngc", "G1 X1 F9\n");
  EXPECT_EQ(error(),
            (dir_ / "main.ngc").string() + ":1:1: error: " + seq + " has no \"o<seq> sub\" line");
  // A file whose subroutine never ends.
  write("seq.ngc", "o<seq> sub\nG1 X1 F9\n");
  EXPECT_EQ(error(), seq + ":1:1: error: o<seq> sub has no matching endsub");
}

// Each file stays open until the program ends: their number is bounded.
TEST_F(SubFiles, AProgramOpensAtMost256Files) {
  std::string main = "G21 G90\n";
  for (int i = 0; i <= 256; ++i) {
    const std::string name = "f" + std::to_string(i);
    write(name + ".ngc",
          "o<" + name + "> sub\nG1 X" + std::to_string(i) + " F900\no<" + name + "> endsub\n");
    main += "o<" + name + "> call\n";
  }
  write("main.ngc", main);
  EXPECT_NE(error().find(":258:1: error: " + (dir_ / "f256.ngc").string() +
                         ": more than 256 subroutine files in one program"),
            std::string::npos)
      << error();
}

// Streamed lines cannot be read ahead or back, but a subroutine's file can: a controller's MDI
// line may call it.
TEST_F(SubFiles, StreamedLinesCallAFile) {
  write("lib/probe.ngc", "o<probe> sub\nG1 X#1 F500\nG0 X0\no<probe> endsub\n");
  std::vector<std::string> lines = {"G21 G90", "o<probe> call [4]", "G0 X9"};
  std::size_t next = 0;
  Options o;
  o.subroutine_path = {(dir_ / "lib").string()};
  Interpreter in(
      Interpreter::FromLines{},
      [&](std::string& line) {
        if (next >= lines.size()) return false;
        line = lines[next++];
        return true;
      },
      "mdi", test_machine(), o);
  std::vector<Block> out;
  Block b;
  while (in.next(b)) out.push_back(b);
  EXPECT_EQ(xs(out), (std::vector<double>{4, 0, 9}));
}

}  // namespace
}  // namespace cncore::interp::test
