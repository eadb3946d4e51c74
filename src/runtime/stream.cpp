#include "runtime/stream.hpp"

#include <cctype>

#include "core/error.hpp"
#include "interpreter/interpreter.hpp"
#include "runtime/persist.hpp"

namespace cncore::runtime {

namespace {

// M2 or M30 among the line's words (comments skipped; M20, M300 … are other codes).
bool has_program_end(const std::string& line) {
  int depth = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == ';') return false;
    if (c == '(') ++depth;
    if (c == ')' && depth > 0) --depth;
    if (depth > 0 || (c != 'M' && c != 'm')) continue;
    std::size_t j = i + 1;
    while (j < line.size() && (line[j] == ' ' || line[j] == '0')) ++j;
    std::string digits;
    while (j < line.size() && std::isdigit(static_cast<unsigned char>(line[j])) != 0) {
      digits += line[j++];
    }
    if (j < line.size() && line[j] == '.') continue;
    if (digits == "2" || digits == "30") return true;
  }
  return false;
}

}  // namespace

LineQueue::Push LineQueue::push(std::string line, bool last) {
  {
    const std::lock_guard lock(mutex_);
    if (closed_ || sealed_) return Push::kClosed;
    if (lines_.size() >= capacity_) return Push::kFull;
    lines_.push_back(std::move(line));
    sealed_ = last;
    last_activity_ = std::chrono::steady_clock::now();
  }
  arrived_.notify_all();
  return Push::kTaken;
}

bool LineQueue::pull(std::string& line, const std::atomic<bool>& cancel,
                     const std::function<bool()>& may_end) {
  std::unique_lock lock(mutex_);
  for (;;) {
    if (cancel.load(std::memory_order_acquire)) {
      closed_ = true;
      lines_.clear();
    }
    if (!lines_.empty()) {
      line = std::move(lines_.front());
      lines_.pop_front();
      last_activity_ = std::chrono::steady_clock::now();
      return true;
    }
    if (sealed_) closed_ = true;
    if (closed_) return false;
    // Only once the tool stands at the end of what it was given: a sender that pauses while the
    // machine has work ahead keeps its stream (and the look-ahead across the pause).
    if (std::chrono::steady_clock::now() - last_activity_ >= idle_end_ && may_end()) {
      closed_ = true;
      return false;
    }
    arrived_.wait_for(lock, std::chrono::milliseconds(1));
  }
}

void LineQueue::close() {
  {
    const std::lock_guard lock(mutex_);
    dropped_ = dropped_ || !closed_;
    closed_ = true;
    lines_.clear();
  }
  arrived_.notify_all();
}

bool LineQueue::dropped() const {
  const std::lock_guard lock(mutex_);
  return dropped_;
}

bool LineQueue::closed() const {
  const std::lock_guard lock(mutex_);
  return closed_ || sealed_;
}

std::size_t LineQueue::room() const {
  const std::lock_guard lock(mutex_);
  return closed_ || sealed_ ? 0 : capacity_ - lines_.size();
}

std::string StreamChecker::check(const std::string& line, const MachineConfig& machine,
                                 bool& ends_program) {
  ends_program = has_program_end(line);
  MachineConfig m = machine;
  m.start_position = position.v;
  interp::Options o;
  o.params = params;
  o.modal = modal;
  o.subroutine_path = subroutine_path;
  try {
    interp::Interpreter in(interp::Interpreter::FromText{}, line, "stream", m, o);
    Block b;
    AxisVec end = position;
    bool moved = false;
    while (in.next(b)) {
      end = b.end;
      moved = moved || is_motion(b);
    }
    modal = in.modal_state();
    params = in.numbered_parameters(kFirstPersistentParameter, kLastPersistentParameter);
    // It starts each checked line at 0.
    probe_tripped = in.numbered_parameters(interp::kParamProbeTripped, interp::kParamProbeTripped)
                        .at(interp::kParamProbeTripped) != 0;
    probed = moved && modal->motion == interp::Motion::kProbe;
    position = end;
  } catch (const InputError& e) {
    return e.formatted();
  }
  return {};
}

}  // namespace cncore::runtime
