// Streamed lines (Controller::stream_line, what the Grbl endpoint feeds): measured on the
// set-points the controller served against `cncore run`'s kernel on the same program.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "served.hpp"
#include "simulation/stepper.hpp"

namespace cncore::runtime {
namespace {

using testing::Served;

// A circle of r 50 mm as `chords` G1 lines at F3000, from a rapid to its start.
std::vector<std::string> circle_lines(int chords) {
  std::vector<std::string> lines = {"G21 G90 G17", "G0 X50 Y0", "G1 F3000"};
  for (int i = 1; i <= chords; ++i) {
    const double a = 2 * M_PI * i / chords;
    std::ostringstream s;
    s.precision(4);
    s << std::fixed << "X" << 50 * std::cos(a) << " Y" << 50 * std::sin(a);
    lines.push_back(s.str());
  }
  return lines;
}

std::string write_program(const std::string& name, const std::vector<std::string>& lines) {
  const auto path = std::filesystem::path(CNCORE_TEST_TMP_DIR) / name;
  std::ofstream f(path);
  for (const std::string& l : lines) f << l << "\n";
  return path.string();
}

// Sends every line, waiting while the controller has no room (what a sender's buffer does).
void stream_all(Controller& c, const std::vector<std::string>& lines) {
  for (const std::string& l : lines) {
    for (;;) {
      const StreamReply r = c.stream_line(l);
      ASSERT_NE(r.outcome, StreamOutcome::kRefused) << l << ": " << r.error;
      if (r.outcome == StreamOutcome::kAccepted) break;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }
}

// Cycles from the first that moves to the last that moves.
double motion_time_s(const std::vector<motion::Sample>& s, double period_s) {
  std::size_t first = 0, last = 0;
  for (std::size_t i = 1; i < s.size(); ++i) {
    if (s[i].position != s[i - 1].position) {
      if (first == 0) first = i;
      last = i;
    }
  }
  return static_cast<double>(last - first + 1) * period_s;
}

std::vector<motion::Sample> run_samples(const std::string& program, const MachineConfig& m) {
  sim::ProgramStepper ref(program, m, motion::kernel_options_for(m));
  std::vector<motion::Sample> out;
  motion::Sample r;
  while (ref.next(r)) out.push_back(r);
  return out;
}

TEST(Stream, ACircleStreamedLineByLineRunsAsOneJobAtTheSpeedOfRun) {
  const MachineConfig m = default_machine_config();
  const std::vector<std::string> lines = circle_lines(1000);
  const std::string program = write_program("stream_circle1000.ngc", lines);
  Served sv(m);
  const std::uint64_t job_before = sv.c().status().job;
  stream_all(sv.c(), lines);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_EQ(sv.c().status().job, job_before + 1);  // one job for the whole stream
  const auto served = sv.samples();
  const auto ref = run_samples(program, m);
  const double t_served = motion_time_s(served, m.period_s);
  const double t_run = motion_time_s(ref, m.period_s);
  EXPECT_GT(t_run, 6.0);
  // Not starved (one job per line is 5x), with room for a loaded machine. Under AddressSanitizer
  // each line's check runs several times slower: only the one-job-per-line failure is caught.
#ifdef __SANITIZE_ADDRESS__
  constexpr double kBound = 3.0;
#else
  constexpr double kBound = 1.15;
#endif
  EXPECT_LE(t_served, kBound * t_run) << "served " << t_served << " s, run " << t_run << " s";
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(sv.c().status().commanded[i], ref.back().position[i], 1e-9);
  }
}

// A streamed line calls a subroutine file from the subroutine path: its moves are served,
// and the stream goes on after it.
TEST(Stream, StreamedLinesCallASubroutineFile) {
  const auto lib = std::filesystem::path(CNCORE_TEST_TMP_DIR) / "stream_subs";
  std::filesystem::create_directories(lib);
  std::ofstream(lib / "peck.ngc") << "o<peck> sub\nG1 Z#1 F600\nG0 Z5\no<peck> endsub\n";
  ControllerOptions o = Served::default_options();
  o.subroutine_path = {lib.string()};
  Served sv(default_machine_config(), o);
  stream_all(sv.c(), {"G21 G90 G0 X10 Z5", "o<peck> call [-3]", "G0 X20"});
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  const auto s = sv.samples();
  double z_min = 1e9;
  for (const motion::Sample& x : s) z_min = std::min(z_min, x.position[2]);
  EXPECT_NEAR(z_min, -3, 0.01) << "the file's G1 Z-3 was served (within the contour tolerance)";
  EXPECT_NEAR(sv.c().status().commanded[0], 20, 1e-9);
  EXPECT_NEAR(sv.c().status().commanded[2], 5, 1e-9);
  // Without the path the line is refused before anything moves.
  Served bare(default_machine_config());
  const StreamReply r = bare.c().stream_line("o<peck> call [-3]");
  EXPECT_EQ(r.outcome, StreamOutcome::kRefused);
  EXPECT_NE(r.error.find("no peck.ngc"), std::string::npos) << r.error;
}

TEST(Stream, ALineBeyondTheTravelIsRefusedBeforeMotionAndTheStreamGoesOn) {
  const MachineConfig m = default_machine_config();
  Served sv(m);
  ASSERT_EQ(sv.c().stream_line("G0 X10 Y10").outcome, StreamOutcome::kAccepted);
  const StreamReply beyond = sv.c().stream_line("G0 X5000");
  EXPECT_EQ(beyond.outcome, StreamOutcome::kRefused);
  EXPECT_NE(beyond.error.find("travel"), std::string::npos) << beyond.error;
  const StreamReply bad = sv.c().stream_line("G1 X20 F0");
  EXPECT_EQ(bad.outcome, StreamOutcome::kRefused);
  stream_all(sv.c(), {"G91 G0 X20", "G90"});  // the modal state of the lines before carries on
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_NEAR(sv.c().status().commanded[0], 30, 1e-9);
  EXPECT_NEAR(sv.c().status().commanded[1], 10, 1e-9);
  double max_x = -1e9;
  for (const motion::Sample& s : sv.samples()) max_x = std::max(max_x, s.position[0]);
  EXPECT_LE(max_x, 30 + 1e-9);
}

TEST(Stream, TheQueueBoundsWhatASenderHasInFlight) {
  const MachineConfig m = default_machine_config();
  ControllerOptions o = Served::default_options();
  o.stream_lines = 4;
  Served sv(m, o);
  // A long slow move first: the planner holds what it has read, the queue fills behind it.
  ASSERT_EQ(sv.c().stream_line("G1 X100 F600").outcome, StreamOutcome::kAccepted);
  int accepted = 0;
  StreamOutcome last = StreamOutcome::kAccepted;
  for (int i = 0; i < 5000 && last == StreamOutcome::kAccepted; ++i) {
    last = sv.c().stream_line("G4 P0.01").outcome;
    if (last == StreamOutcome::kAccepted) ++accepted;
  }
  EXPECT_EQ(last, StreamOutcome::kWait);
  EXPECT_EQ(sv.c().stream_room().free_lines, 0U);
  EXPECT_EQ(sv.c().stream_room().capacity, 4U);
  EXPECT_LT(accepted, 5000);
  // A reset drops the queued lines: the machine stops on its path, short of X100.
  ASSERT_TRUE(sv.c().reset().ok);
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_LT(sv.c().status().commanded[0], 100);
  EXPECT_EQ(sv.c().stream_room().free_lines, 4U);
  ASSERT_EQ(sv.c().stream_line("G0 X0").outcome, StreamOutcome::kAccepted);
  ASSERT_TRUE(sv.wait_for([](const Status& s) { return s.state == MachineState::kRun; }, 5));
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_NEAR(sv.c().status().commanded[0], 0, 1e-9);
}

TEST(Stream, M2EndsTheStreamAndTheNextLineStartsANewOneOnceIdle) {
  const MachineConfig m = default_machine_config();
  Served sv(m);
  const std::uint64_t job_before = sv.c().status().job;
  stream_all(sv.c(), {"G0 X20", "M2"});
  // Until the ended stream has run out, a further line waits.
  const StreamReply next = sv.c().stream_line("G0 X40");
  EXPECT_EQ(next.outcome, StreamOutcome::kWait);
  stream_all(sv.c(), {"G0 X40"});
  ASSERT_TRUE(sv.wait_for([](const Status& s) { return s.state == MachineState::kRun; }, 5));
  ASSERT_TRUE(sv.wait_state(MachineState::kIdle));
  EXPECT_EQ(sv.c().status().job, job_before + 2);
  EXPECT_NEAR(sv.c().status().commanded[0], 40, 1e-9);
}

TEST(Stream, CheckModeInterpretsStreamedLinesWithoutMotion) {
  Served sv(default_machine_config());
  ASSERT_TRUE(sv.c().set_check_mode(true).ok);
  EXPECT_EQ(sv.c().stream_line("G0 X100").outcome, StreamOutcome::kAccepted);
  EXPECT_EQ(sv.c().stream_line("G91 G0 X550").outcome, StreamOutcome::kRefused);  // 650: beyond
  sv.wait_cycles(50);
  EXPECT_EQ(sv.c().status().state, MachineState::kCheck);
  EXPECT_EQ(sv.c().status().commanded[0], 0);
}

}  // namespace
}  // namespace cncore::runtime
