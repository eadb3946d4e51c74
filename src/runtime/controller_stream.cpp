// Streamed lines (Controller::stream_line): each line checked on arrival, then queued into one
// running job whose interpreter pulls the queue on the planning thread (runtime/stream.hpp).
#include "runtime/controller_impl.hpp"

namespace cncore::runtime {

// A new stream from its first line: the checker starts from what the last job left, the
// job's interpreter pulls the queue from the planning thread, and the kernel fills as lines
// come (no prefill: the line after this one may not have been sent yet).
StreamReply Controller::Impl::start_stream(const std::string& line, const Status& st) {
  StreamChecker next;
  {
    const std::lock_guard lock(data);
    next.modal = modal;
    next.params = params;
  }
  next.subroutine_path = options.subroutine_path;
  next.position = st.commanded;
  bool ends = false;
  if (std::string e = next.check(line, machine, ends); !e.empty()) {
    return {StreamOutcome::kRefused, std::move(e)};
  }
  auto queue = std::make_shared<LineQueue>(options.stream_lines,
                                           std::chrono::milliseconds(options.stream_idle_end_ms));
  (void)queue->push(line, ends);
  checker = std::move(next);
  // The queue closes when the interpreter pulling it goes (the stream's end, an error, a reset).
  struct Closer {
    explicit Closer(std::shared_ptr<LineQueue> q) : queue(std::move(q)) {}
    std::shared_ptr<LineQueue> queue;
    Closer(const Closer&) = delete;
    Closer& operator=(const Closer&) = delete;
    ~Closer() { queue->close(); }
  };
  auto closer = std::make_shared<Closer>(queue);
  auto job_link = std::make_shared<std::atomic<Job*>>(nullptr);
  auto pull = [closer, job_link](std::string& out) {
    Job* j = job_link->load(std::memory_order_acquire);
    // The stream may end only where the tool has run out of blocks and stands (not held).
    const bool more = closer->queue->pull(out, j->cancel, [j] {
      return j->ring.size() == 0 && j->standing.load(std::memory_order_relaxed);
    });
    // A dropped stream (reset, E-stop) is an abandoned program, not a completed one: its modal
    // state is not carried to the next (the reset's own cancel may come a moment later).
    if (!more && closer->queue->dropped()) j->cancel.store(true, std::memory_order_release);
    return more;
  };
  const MachineConfig m = machine_at(st);
  auto in = std::make_unique<interp::Interpreter>(interp::Interpreter::FromLines{}, std::move(pull),
                                                  "stream", m, interpreter_options());
  {
    const std::lock_guard lock(data);
    stream = queue;
  }
  const Result r =
      start_job(Command::kMdi, std::move(in), "stream", st, false,
                [&job_link](Job& j) { job_link->store(&j, std::memory_order_release); });
  if (!r.ok) {
    queue->close();
    return {StreamOutcome::kRefused, r.error};
  }
  return {};
}

StreamReply Controller::stream_line(const std::string& line) {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  const Status st = d.status.load();
  bool ends = false;
  if (st.state == MachineState::kCheck) {
    if (!d.checker_in_check) {
      d.checker = StreamChecker{};
      const std::lock_guard data_lock(d.data);
      d.checker.modal = d.modal;
      d.checker.params = d.params;
      d.checker.position = st.commanded;
      d.checker.subroutine_path = d.options.subroutine_path;
    }
    d.checker_in_check = true;
    std::string e = d.checker.check(line, d.machine, ends);
    return e.empty() ? StreamReply{} : StreamReply{StreamOutcome::kRefused, std::move(e)};
  }
  d.checker_in_check = false;
  std::shared_ptr<LineQueue> queue;
  {
    const std::lock_guard data_lock(d.data);
    queue = d.stream;
  }
  if (queue && !queue->closed()) {
    if (queue->room() == 0) return {StreamOutcome::kWait, {}};
    StreamChecker next = d.checker;  // kept only once the line is queued
    if (std::string e = next.check(line, d.machine, ends); !e.empty()) {
      return {StreamOutcome::kRefused, std::move(e)};
    }
    if (queue->push(line, ends) == LineQueue::Push::kTaken) {
      d.checker = std::move(next);
      return {};
    }
    // The stream ended meanwhile: this line starts the next one.
  }
  if (is_moving(st.state) || st.resetting) return {StreamOutcome::kWait, {}};
  if (Result r = d.allowed(Command::kMdi); !r.ok) return {StreamOutcome::kRefused, r.error};
  try {
    return d.start_stream(line, st);
  } catch (const InputError& e) {
    return {StreamOutcome::kRefused, e.formatted()};
  }
}

StreamRoom Controller::stream_room() const {
  Impl& d = *impl_;
  std::shared_ptr<LineQueue> queue;
  {
    const std::lock_guard data_lock(d.data);
    queue = d.stream;
  }
  const std::size_t capacity = d.options.stream_lines;
  return {queue && !queue->closed() ? queue->room() : capacity, capacity};
}

interp::ModalState Controller::parser_state() const {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  bool streaming = d.checker_in_check;
  {
    const std::lock_guard data_lock(d.data);
    streaming = streaming || (d.stream && !d.stream->closed());
    if (!streaming) return d.modal.value_or(interp::ModalState{});
  }
  return d.checker.modal.value_or(interp::ModalState{});
}

std::optional<bool> Controller::last_line_probe() const {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  if (!d.checker.probed) return std::nullopt;
  return d.checker.probe_tripped;
}

void Controller::forget_modes() {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  d.checker_in_check = false;
  const std::lock_guard data_lock(d.data);
  d.modal.reset();
}

}  // namespace cncore::runtime
