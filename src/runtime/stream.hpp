// Internal to the runtime: streamed G-code lines (a sender's, through the Grbl endpoint). The
// control side checks each line as it arrives (StreamChecker: the line interpreted from the
// state the lines before it left, so an error is the line's own, before anything moves) and
// puts it into a bounded LineQueue; the planning thread's interpreter pulls the lines from the
// queue into one job, so the look-ahead sees the stream as one program. Not real-time.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "config/machine_config.hpp"
#include "core/geometry.hpp"
#include "interpreter/modal_state.hpp"

namespace cncore::runtime {

// Lines from the control side to the planning thread's interpreter. Its capacity bounds the
// memory a stream holds and is the back-pressure a sender feels (no room: the line waits).
class LineQueue {
 public:
  LineQueue(std::size_t capacity, std::chrono::milliseconds idle_end)
      : capacity_(capacity), idle_end_(idle_end) {}

  enum class Push : std::uint8_t { kTaken, kFull, kClosed };
  // `last`: the line ends the program (M2, M30): the queue takes nothing after it.
  Push push(std::string line, bool last);
  // The planning thread: the next line, waiting for it. False when the stream has ended: closed,
  // cancelled, or no line for `idle_end` while `may_end()` (the tool has run out of planned
  // blocks and stands). A false return closes the queue.
  bool pull(std::string& line, const std::atomic<bool>& cancel,
            const std::function<bool()>& may_end);
  // Ends the stream and drops its lines (reset, alarm).
  void close();
  bool closed() const;
  // close() ended it (not its program end, not an idle end): the stream was abandoned.
  bool dropped() const;
  std::size_t room() const;
  std::size_t capacity() const { return capacity_; }

 private:
  const std::size_t capacity_;
  const std::chrono::milliseconds idle_end_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<std::string> lines_;
  bool closed_ = false;   // nothing more is taken
  bool dropped_ = false;  // closed by close()
  bool sealed_ = false;   // the program's end was taken: closed once drained
  std::chrono::steady_clock::time_point last_activity_ = std::chrono::steady_clock::now();
};

// The state the streamed lines checked so far leave: what the next line is interpreted from.
struct StreamChecker {
  std::optional<interp::ModalState> modal;
  std::map<int, double> params;
  AxisVec position;  // machine coordinates where the last checked line ends
  // The last checked line probed (G38.2 … G38.5) and the probe tripped (#5070 after it).
  bool probed = false;
  bool probe_tripped = false;
  std::vector<std::string> subroutine_path;  // interp::Options::subroutine_path

  // Interprets `line` from this state; empty and the state advanced when it is good, else the
  // error (FILE:LINE:COL: error: …) and the state as it was. `ends_program`: the line has M2
  // or M30.
  std::string check(const std::string& line, const MachineConfig& machine, bool& ends_program);
};

}  // namespace cncore::runtime
