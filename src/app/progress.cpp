#include "app/progress.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>

#include "app/cli_common.hpp"

namespace cncore::app {
namespace {

constexpr double kFirstLineAfterS = 1.0;
constexpr double kUpdateEveryS = 0.5;

// Lines of the file: its '\n' count, plus one for a last line without one (0 when unreadable).
std::uint32_t count_lines(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return 0;
  std::array<char, 1 << 16> buf{};
  std::uint32_t lines = 0;
  char last = '\n';
  for (std::size_t n = 0; (n = std::fread(buf.data(), 1, buf.size(), f)) > 0;) {
    lines += static_cast<std::uint32_t>(std::count(buf.begin(), buf.begin() + n, '\n'));
    last = buf[n - 1];
  }
  std::fclose(f);
  return lines + (last == '\n' ? 0 : 1);
}

}  // namespace

ProgressMode progress_mode(const std::string& option) {
  if (option == "auto") {
    return ::isatty(STDERR_FILENO) == 1 ? ProgressMode::kLine : ProgressMode::kOff;
  }
  if (option == "on") return ProgressMode::kLine;
  if (option == "off") return ProgressMode::kOff;
  if (option == "json") return ProgressMode::kJson;
  throw UsageError(fmt::format("--progress: '{}' is not one of auto, on, off, json", option));
}

ProgressObserver::ProgressObserver(ProgressMode mode, const std::string& program_path)
    : mode_(mode),
      terminal_(::isatty(STDERR_FILENO) == 1),
      next_update_s_(mode == ProgressMode::kJson ? 0.0 : kFirstLineAfterS),
      start_(Clock::now()) {
  if (enabled() && !program_path.empty()) lines_total_ = count_lines(program_path);
}

void ProgressObserver::on_sample(const motion::Sample& s) {
  sim_s_ = s.t_s;
  line_ = std::max(line_, s.line);
  if (mode_ == ProgressMode::kOff || (++cycles_ & 4095) != 0) return;
  const double wall_s = std::chrono::duration<double>(Clock::now() - start_).count();
  if (wall_s < next_update_s_) return;
  next_update_s_ = wall_s + kUpdateEveryS;
  show(wall_s, false);
}

void ProgressObserver::on_finish() {
  if (mode_ == ProgressMode::kJson) {
    show(std::chrono::duration<double>(Clock::now() - start_).count(), true);
  }
  clear();
}

void ProgressObserver::show(double wall_s, bool done) {
  // Share of the program done (the furthest line the tool has run), and the time left if the rest
  // goes at the same pace: left = wall · (100 − pct) / pct.
  double pct = -1;
  if (lines_total_ > 0) {
    pct = done ? 100.0 : std::min(100.0, 100.0 * line_ / lines_total_);
  }
  const double speed = wall_s > 0 ? sim_s_ / wall_s : 0.0;
  const double left_s = pct > 0 ? wall_s * (100.0 - pct) / pct : -1;
  if (mode_ == ProgressMode::kJson) {
    std::string o = "{";
    if (pct >= 0) {
      o += fmt::format(R"("percent":{:.1f},"line":{},"lines":{},)", pct, line_, lines_total_);
    }
    o += fmt::format(R"("simulated_s":{:.3f},"wall_s":{:.3f},"speed_x":{:.2f})", sim_s_, wall_s,
                     speed);
    if (left_s >= 0) o += fmt::format(R"(,"left_s":{:.1f})", left_s);
    o += fmt::format(R"(,"done":{}}})", done);
    std::fprintf(stderr, "%s\n", o.c_str());
  } else {
    std::string o = "cncore: ";
    if (pct >= 0) o += fmt::format("{:3.0f} % (line {} of {}), ", pct, line_, lines_total_);
    o += fmt::format("simulated {:.1f} s, {:.1f}x real time", sim_s_, speed);
    if (left_s >= 0) o += fmt::format(", {:.0f} s left", left_s);
    if (terminal_) {
      std::fprintf(stderr, "\r%-78s", o.c_str());
      shown_ = true;
    } else {
      std::fprintf(stderr, "%s\n", o.c_str());
    }
  }
  std::fflush(stderr);
}

void ProgressObserver::clear() {
  if (!shown_) return;
  std::fprintf(stderr, "\r%78s\r", "");
  std::fflush(stderr);
  shown_ = false;
}

}  // namespace cncore::app
