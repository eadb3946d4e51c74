// `cncore estimate`: `cncore run` on every program of a batch, each in its own worker process
// (this same binary, started with posix_spawn), N at a time. A process per program keeps memory
// bounded per program and lets one failed or crashed program be reported while the rest run;
// running `cncore run` itself gives the same cycle times as running the programs one by one.
#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "app/cli_common.hpp"
#include "app/commands.hpp"
#include "app/estimate_output.hpp"
#include "io/atomic_file.hpp"

extern char** environ;  // NOLINT(readability-redundant-declaration): POSIX, for posix_spawn

namespace cncore::app {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

bool is_program_file(const fs::path& p) {
  const std::string ext = p.extension().string();
  return ext == ".ngc" || ext == ".nc" || ext == ".gcode" || ext == ".tap" || ext == ".NGC" ||
         ext == ".NC";
}

// FILES…: files as given; a directory stands for the programs under it (sorted by path).
std::vector<std::string> expand_programs(const std::vector<std::string>& args) {
  std::vector<std::string> programs;
  for (const std::string& a : args) {
    std::error_code ec;
    if (!fs::is_directory(a, ec)) {
      programs.push_back(a);
      continue;
    }
    std::vector<std::string> found;
    for (const auto& e : fs::recursive_directory_iterator(a, ec)) {
      if (e.is_regular_file(ec) && is_program_file(e.path())) found.push_back(e.path().string());
    }
    std::sort(found.begin(), found.end());
    programs.insert(programs.end(), found.begin(), found.end());
  }
  return programs;
}

std::string self_executable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the cncore executable (/proc/self/exe)");
  return p.string();
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A directory for the workers' summaries and error outputs, removed with the object.
class TempDir {
 public:
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string tmpl =
        std::string(base != nullptr && *base != 0 ? base : "/tmp") + "/cncore-estimate-XXXXXX";
    if (mkdtemp(tmpl.data()) == nullptr) {
      throw std::runtime_error(fmt::format("cannot create {}: {}", tmpl, std::strerror(errno)));
    }
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

struct Worker {
  std::size_t index = 0;
  Clock::time_point start;
};

class Batch {
 public:
  Batch(const EstimateArgs& a, std::vector<std::string> programs, fs::path dir)
      : args_(a), dir_(std::move(dir)), exe_(self_executable()), results_(programs.size()) {
    for (std::size_t i = 0; i < programs.size(); ++i) results_[i].program = std::move(programs[i]);
  }

  std::vector<estimate::ProgramResult> run(unsigned jobs) {
    std::size_t next = 0;
    while (next < results_.size() || !running_.empty()) {
      while (next < results_.size() && running_.size() < jobs) start(next++);
      reap_one();
      show_progress();
    }
    clear_progress();
    return std::move(results_);
  }

 private:
  fs::path summary_path(std::size_t i) const { return dir_ / fmt::format("{}.json", i); }
  fs::path error_path(std::size_t i) const { return dir_ / fmt::format("{}.err", i); }

  void start(std::size_t i) {
    std::vector<std::string> argv_s{exe_, "run", results_[i].program, "--summary",
                                    summary_path(i).string()};
    if (!args_.machine.empty()) {
      argv_s.emplace_back("--machine");
      argv_s.push_back(args_.machine);
    }
    std::vector<char*> argv;
    argv.reserve(argv_s.size() + 1);
    for (std::string& s : argv_s) argv.push_back(s.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    const std::string err = error_path(i).string();
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0600);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, exe_.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) {
      throw std::runtime_error(fmt::format("cannot start {}: {}", exe_, std::strerror(rc)));
    }
    running_[pid] = Worker{i, Clock::now()};
  }

  void reap_one() {
    int status = 0;
    pid_t pid = -1;
    do {
      pid = waitpid(-1, &status, 0);
    } while (pid < 0 && errno == EINTR);
    const auto it = running_.find(pid);
    if (pid < 0 || it == running_.end()) return;
    const Worker w = it->second;
    running_.erase(it);
    estimate::ProgramResult& r = results_[w.index];
    r.wall_s = std::chrono::duration<double>(Clock::now() - w.start).count();
    ++done_;
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0 &&
        estimate::read_summary_json(slurp(summary_path(w.index)), r)) {
      r.ok = true;
      return;
    }
    std::string text = slurp(error_path(w.index));
    text = text.substr(0, text.find('\n'));
    if (WIFSIGNALED(status)) {
      text = fmt::format("{}: error: the run died of signal {} ({}){}", r.program, WTERMSIG(status),
                         strsignal(WTERMSIG(status)), text.empty() ? "" : ": " + text);
    } else if (text.empty()) {
      text = fmt::format("{}: error: the run failed with exit code {}", r.program,
                         WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    }
    r.error = text;
    ++failed_;
  }

  // One line over the whole set on stderr, only on a terminal.
  void show_progress() {
    if (!tty_) return;
    const double elapsed_s = std::chrono::duration<double>(Clock::now() - start_).count();
    const std::size_t n = results_.size();
    constexpr std::size_t kBar = 30;
    const std::size_t filled = n > 0 ? done_ * kBar / n : kBar;
    std::cerr << fmt::format("\r[{}{}] {}/{} programs, {} failed, {:.1f} s",
                             std::string(filled, '#'), std::string(kBar - filled, '.'), done_, n,
                             failed_, elapsed_s)
              << std::flush;
  }
  void clear_progress() const {
    if (tty_) std::cerr << "\r\033[K" << std::flush;
  }

  const EstimateArgs& args_;
  fs::path dir_;
  std::string exe_;
  std::vector<estimate::ProgramResult> results_;
  std::map<pid_t, Worker> running_;
  std::size_t done_ = 0, failed_ = 0;
  bool tty_ = isatty(STDERR_FILENO) != 0;
  Clock::time_point start_ = Clock::now();
};

}  // namespace

int command_estimate(const EstimateArgs& a) {
  if (a.csv.empty()) throw UsageError("--csv FILE.csv is required");
  const std::vector<std::string> programs = expand_programs(a.files);
  if (programs.empty()) throw UsageError("no programs to estimate");
  if (!a.machine.empty()) (void)machine_from(a.machine);  // a bad machine fails before any run
  unsigned jobs = a.jobs;
  if (jobs == 0) jobs = std::max(1U, std::thread::hardware_concurrency());
  // Outputs are created (as temporaries) first, so a bad path fails before the runs.
  io::AtomicOutputFile csv(a.csv);
  std::optional<io::AtomicOutputFile> html;
  if (!a.report.empty()) html.emplace(a.report);

  const Clock::time_point start = Clock::now();
  std::vector<estimate::ProgramResult> results;
  {
    const TempDir dir;
    results = Batch(a, programs, dir.path()).run(jobs);
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();

  csv.write(estimate::results_csv(results));
  const std::string machine_name = a.machine.empty() ? "the built-in machine" : a.machine;
  if (html) html->write(estimate::results_html(results, machine_name, wall_s, jobs));
  csv.commit();
  if (html) html->commit();

  double total_s = 0;
  std::size_t failed = 0;
  for (const estimate::ProgramResult& r : results) {
    if (r.ok) {
      total_s += r.cycle_time_s;
    } else {
      ++failed;
      std::cerr << r.error << "\n";
    }
  }
  std::cout << fmt::format(
      "programs      {} ({} ok, {} failed)\n"
      "cycle time    {:.3f} s in total ({:.2f} h)\n"
      "wall time     {:.2f} s with {} worker processes\n"
      "csv           {}\n",
      results.size(), results.size() - failed, failed, total_s, total_s / 3600, wall_s, jobs,
      a.csv);
  if (html) std::cout << "report        " << a.report << "\n";
  return failed > 0 ? 1 : 0;
}

}  // namespace cncore::app
