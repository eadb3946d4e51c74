// The atomic output file: complete or absent, never half-written, never a temporary left over.
#include "io/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <thread>

#include "core/error.hpp"
#include "test_dir.hpp"

namespace cncore::io {
namespace {

using test::fresh_dir;
using test::list_dir;
using test::slurp;

TEST(AtomicOutputFile, CommitPutsTheWholeFileInPlace) {
  const auto dir = fresh_dir();
  const auto path = dir / "out.csv";
  {
    AtomicOutputFile f(path.string());
    // The temporary sits next to the final file, and the final name does not exist yet.
    EXPECT_EQ(std::filesystem::path(f.temp_path()).parent_path(), dir);
    EXPECT_EQ(f.temp_path().rfind(path.string() + ".tmp-", 0), 0u);
    EXPECT_FALSE(std::filesystem::exists(path));
    f.write("a,b\n");
    f.write("1,2\n");
    f.commit();
  }
  EXPECT_EQ(slurp(path), "a,b\n1,2\n");
  EXPECT_EQ(list_dir(dir), std::vector<std::string>{"out.csv"});
}

// A FIFO stands for any device or pipe (/dev/null, /dev/stdout): written directly, the node
// stays what it was (a rename over /dev/null as root made it a regular file).
TEST(AtomicOutputFile, PipeIsWrittenDirectlyAndStaysAPipe) {
  const auto dir = fresh_dir();
  const auto path = dir / "fifo";
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] {
    std::ifstream in(path);
    got.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  });
  {
    AtomicOutputFile f(path.string());
    EXPECT_TRUE(f.temp_path().empty());
    f.write("a,b\n");
    f.commit();
  }
  reader.join();
  EXPECT_EQ(got, "a,b\n");
  EXPECT_TRUE(std::filesystem::is_fifo(path));
  EXPECT_EQ(list_dir(dir), std::vector<std::string>{"fifo"});
}

TEST(AtomicOutputFile, NoCommitLeavesNothing) {
  const auto dir = fresh_dir();
  {
    AtomicOutputFile f((dir / "out.csv").string());
    f.write(std::string(1 << 20, 'x'));
  }
  EXPECT_TRUE(list_dir(dir).empty());
}

TEST(AtomicOutputFile, ExceptionDuringWritingLeavesNothingAndKeepsTheOldFile) {
  const auto dir = fresh_dir();
  const auto path = dir / "out.json";
  {
    std::ofstream old(path);
    old << "previous";
  }
  try {
    AtomicOutputFile f(path.string());
    f.write("partial");
    throw std::runtime_error("run failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(list_dir(dir), std::vector<std::string>{"out.json"});
  EXPECT_EQ(slurp(path), "previous");
}

TEST(AtomicOutputFile, CommitReplacesAnOldFile) {
  const auto dir = fresh_dir();
  const auto path = dir / "out.json";
  {
    std::ofstream old(path);
    old << "previous";
  }
  AtomicOutputFile f(path.string());
  f.write("new");
  f.commit();
  EXPECT_EQ(slurp(path), "new");
  EXPECT_EQ(list_dir(dir).size(), 1u);
}

TEST(AtomicOutputFile, MissingDirectoryIsAnInputErrorNamingTheFile) {
  const auto dir = fresh_dir();
  const std::string path = (dir / "no" / "such" / "out.csv").string();
  try {
    AtomicOutputFile f(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("cannot create"), std::string::npos);
  }
}

}  // namespace
}  // namespace cncore::io
