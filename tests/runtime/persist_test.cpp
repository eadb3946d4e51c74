// The persistent machine state: read back as written, and a kill -9 at any moment of a write
// leaves the old file or the new one, never a broken one.
#include "runtime/persist.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "core/error.hpp"

namespace cncore::runtime {
namespace {

std::string fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::filesystem::remove_all(dir);
  return dir.string();
}

PersistentState sample_state(double k) {
  PersistentState s;
  for (int n = 5221; n < 5230; ++n) s.parameters[n] = k * n;
  s.parameters[5220] = 2;
  s.position[0] = k;
  s.position[2] = -k;
  s.has_position = true;
  return s;
}

TEST(Persist, ReadsBackWhatItWrote) {
  const std::string dir = fresh_dir("persist-roundtrip");
  EXPECT_EQ(load_state(dir), PersistentState{});  // nothing saved yet
  const PersistentState s = sample_state(1.25);
  save_state(dir, s);
  EXPECT_EQ(load_state(dir), s);
}

TEST(Persist, ABrokenFileIsAnInputErrorNamingIt) {
  const std::string dir = fresh_dir("persist-broken");
  std::filesystem::create_directories(dir);
  std::ofstream(state_file(dir)) << "{\"format\": \"cncore-machine-state-1\", \"param";
  try {
    load_state(dir);
    FAIL() << "a broken state file was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(e.formatted().find("machine-state.json"), std::string::npos) << e.formatted();
  }
}

TEST(Persist, KillDuringWritesLeavesTheOldOrTheNewFile) {
  const std::string dir = fresh_dir("persist-kill");
  const PersistentState a = sample_state(1), b = sample_state(2);
  save_state(dir, a);
  std::mt19937 rng(7);
  for (int round = 0; round < 30; ++round) {
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      for (int i = 0;; ++i) save_state(dir, i % 2 == 0 ? b : a);
    }
    usleep(static_cast<useconds_t>(std::uniform_int_distribution<int>(200, 20000)(rng)));
    kill(child, SIGKILL);
    int status = 0;
    waitpid(child, &status, 0);
    const PersistentState got = load_state(dir);
    EXPECT_TRUE(got == a || got == b) << "round " << round;
  }
}

}  // namespace
}  // namespace cncore::runtime
