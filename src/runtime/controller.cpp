#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

#include "core/error.hpp"
#include "interpreter/interpreter.hpp"
#include "runtime/control.hpp"
#include "runtime/cycle.hpp"
#include "runtime/pacing.hpp"
#include "runtime/persist.hpp"
#include "runtime/planning.hpp"
#include "runtime/stream.hpp"

namespace cncore::runtime {

namespace {

// The active work offset from LinuxCNC's parameters: the system's (5221 + 20·(n − 1) + axis)
// plus G92 (5211 + axis) while it is applied (5210).
AxisVec work_offset_from(const std::map<int, double>& p) {
  auto get = [&p](int n) {
    const auto it = p.find(n);
    return it == p.end() ? 0.0 : it->second;
  };
  const int system = std::clamp(static_cast<int>(std::lround(get(5220))), 1, 9);
  AxisVec off;
  for (int a = 0; a < static_cast<int>(kMaxAxes); ++a) {
    off[static_cast<std::size_t>(a)] =
        get(5221 + 20 * (system - 1) + a) + (get(5210) != 0 ? get(5211 + a) : 0.0);
  }
  return off;
}

bool is_moving(MachineState s) {
  return s == MachineState::kRun || s == MachineState::kHold || s == MachineState::kJog ||
         s == MachineState::kHoming;
}

}  // namespace

struct Controller::Impl {
  Impl(MachineConfig m, const ControllerOptions& o)
      : machine(std::move(m)), options(o), commands(256), applied(4096), state_dir(o.state_dir) {
    if (machine.servo.kp_per_s * machine.period_s > 1) {
      throw std::runtime_error("servo.kp_per_s · motion.period_s must be ≤ 1 for a stable loop");
    }
    AxisVec start;
    for (std::size_t i = 0; i < kMaxAxes; ++i) start[i] = machine.start_position[i];
    if (!state_dir.empty()) {
      const PersistentState ps = load_state(state_dir);
      params = ps.parameters;
      if (ps.has_position) start = ps.position;
      last_saved = ps;
    }
    work_offset = work_offset_from(params);
    if (o.sample_ring > 0) samples = std::make_unique<SpscRing<motion::Sample>>(o.sample_ring);
    if (o.servo == ServoKind::kUdp) output = open_udp_output(o.servo_address);
    if (o.servo == ServoKind::kShm) output = open_shm_output(o.servo_address, 4096);
    CycleLinks links{&commands, samples.get(), &applied, &status, output.get(), o.lossless_samples};
    loop = std::make_unique<CycleLoop>(machine, links, start, o.sim_position_error);
    loop->set_stopping(&stop_cycle);
    Status first;
    first.commanded = start;
    first.actual = start;
    status.store(first);
    planning = std::make_unique<PlanningThread>(
        [this](const interp::Interpreter& in, const std::string& error, bool completed) {
          on_end(in, error, completed);
        });
    if (!state_dir.empty()) planning->set_housekeeping([this] { save_if_changed(false); }, 200);
    cycle_thread = std::thread([this] { cycle_main(); });
  }

  ~Impl() {
    // A controlled stop: what moves decelerates on its path, then the threads end.
    {
      const std::lock_guard lock(control);
      CycleCommand c = cycle_command(Command::kReset);
      c.seq = ++command_seq;
      commands.try_push(c);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (is_moving(status.load().state) && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    stop_cycle.store(true);
    cycle_thread.join();
    planning.reset();
    if (!state_dir.empty()) save_if_changed(true);
  }

  void cycle_main() {
    if (options.realtime) {
      const std::string missing = enter_realtime(80);
      if (!missing.empty()) {
        message("the cycle thread runs without real-time guarantees: " + missing);
      }
    }
    const auto period_ns = static_cast<std::int64_t>(std::llround(machine.period_s * 1e9));
    const std::int64_t t0 = monotonic_ns();
    for (std::uint64_t n = 0; !stop_cycle.load(std::memory_order_relaxed); ++n) {
      if (options.paced) {
        const std::int64_t due = t0 + static_cast<std::int64_t>(n) * period_ns;
        sleep_until_ns(due);
        if (monotonic_ns() > due + period_ns) loop->add_overrun();
      } else if (!is_moving(loop->state()) && commands.size() == 0) {
        std::this_thread::sleep_for(std::chrono::microseconds(100));
      }
      const std::int64_t start = monotonic_ns();
      if (options.paced) {
        const std::int64_t due = t0 + static_cast<std::int64_t>(n) * period_ns;
        wake_hist.add_ns(start - due);
      }
      loop->run(n);
      const std::int64_t work_ns = monotonic_ns() - start;
      work_hist.add_ns(work_ns);
      ++figure_cycles;
      loop->set_work_us(static_cast<double>(work_ns) / 1000.0);
      if (const int req = figures_request.load(std::memory_order_acquire); req != 0) {
        publish_figures(req == 2);  // between cycles, outside the measured work
      }
    }
  }

  void publish_figures(bool reset) {
    CycleFigures f;
    f.cycles = figure_cycles;
    f.wake_p50_us = wake_hist.quantile_us(0.5);
    f.wake_p99_us = wake_hist.quantile_us(0.99);
    f.wake_p999_us = wake_hist.quantile_us(0.999);
    f.wake_max_us = wake_hist.max_us();
    f.work_p50_us = work_hist.quantile_us(0.5);
    f.work_p99_us = work_hist.quantile_us(0.99);
    f.work_p999_us = work_hist.quantile_us(0.999);
    f.work_max_us = work_hist.max_us();
    f.overruns = status.load().overruns - overruns_at_reset;
    figures.store(f);
    if (reset) {
      wake_hist.clear();
      work_hist.clear();
      figure_cycles = 0;
      overruns_at_reset += f.overruns;
    }
    figures_request.store(0, std::memory_order_release);
    figures_serial.fetch_add(1, std::memory_order_release);
  }

  void message(std::string text) {
    const std::lock_guard lock(data);
    messages.push_back(std::move(text));
  }

  // A job's program has been read to its end (completed) or given up (reset, alarm): what it
  // leaves for the next one. An abandoned program's modal state is not carried over (the
  // planner read it ahead of the tool); its parameters are, like LinuxCNC's after an abort.
  void on_end(const interp::Interpreter& in, const std::string& error, bool completed) {
    std::map<int, double> p =
        in.numbered_parameters(kFirstPersistentParameter, kLastPersistentParameter);
    const interp::ModalState m = in.modal_state();
    const std::lock_guard lock(data);
    params = std::move(p);
    modal = completed ? std::optional<interp::ModalState>(m) : std::nullopt;
    work_offset = work_offset_from(params);
    if (!error.empty()) messages.push_back(error);
  }

  void save_if_changed(bool always) {
    const Status st = status.load();
    if (!always && is_moving(st.state)) return;
    PersistentState ps;
    {
      const std::lock_guard lock(data);
      ps.parameters = params;
    }
    ps.position = st.commanded;
    ps.has_position = true;
    if (ps == last_saved) return;
    try {
      save_state(state_dir, ps);
      last_saved = ps;
    } catch (const std::exception& e) {
      if (!save_failed) message(std::string("cannot save the machine state: ") + e.what());
      save_failed = true;
    }
  }

  // Hands the command to the cycle and waits until the cycle has taken it (a cycle or two), so
  // the caller's next status() or command sees its effect.
  Result send(CycleCommand c) {
    c.seq = ++command_seq;
    if (!commands.try_push(c)) return Result::fail("the controller is busy: too many commands");
    return wait_taken(c.seq);
  }

  Result wait_taken(std::uint64_t seq) const {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (status.load().applied_commands < seq) {
      if (std::chrono::steady_clock::now() > deadline) {
        return Result::fail("the cycle thread did not take the command within 2 s");
      }
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
    return {};
  }

  Result allowed(Command c) const {
    const Transition t = transition(status.load().state, c);
    if (!t.allowed) return Result::fail(std::string(t.why_not));
    return {};
  }

  // A command without data: refused with the table's reason when `check` and it is illegal now.
  Result command(Command c, bool check) {
    const std::lock_guard lock(control);
    if (check) {
      if (Result r = allowed(c); !r.ok) return r;
    }
    return send(cycle_command(c));
  }

  MachineConfig machine_at(const Status& st) const {
    MachineConfig m = machine;
    m.start_position = st.commanded.v;
    return m;
  }

  interp::Options interpreter_options() {
    interp::Options o;
    const std::lock_guard lock(data);
    o.params = params;
    o.modal = modal;
    return o;
  }

  // Interprets the whole program without motion: the first error, or empty.
  std::string check_program(const std::function<std::unique_ptr<interp::Interpreter>()>& make) {
    try {
      auto in = make();
      Block b;
      while (in->next(b)) {
      }
    } catch (const InputError& e) {
      return e.formatted();
    }
    return {};
  }

  // prefill: fill the kernel before the first cycle (a program or MDI); a stream's kernel
  // fills from the planning thread as lines arrive. made: told of the job before it runs.
  Result start_job(Command command, std::unique_ptr<interp::Interpreter> interpreter,
                   const std::string& name, const Status& st, bool prefill = true,
                   const std::function<void(Job&)>& made = {});
  StreamReply start_stream(const std::string& line, const Status& st);
  void close_stream() {
    std::shared_ptr<LineQueue> q;
    {
      const std::lock_guard lock(data);
      q = stream;
    }
    if (q) q->close();
  }

  MachineConfig machine;
  ControllerOptions options;
  SpscRing<CycleCommand> commands;
  std::unique_ptr<SpscRing<motion::Sample>> samples;
  SpscRing<AppliedCommand> applied;
  Seqlock<Status> status;
  std::unique_ptr<ServoOutput> output;
  std::unique_ptr<CycleLoop> loop;
  std::mutex control;  // serialises the control methods (the command ring's one producer)
  std::string program_path;
  Switches switches;
  std::uint64_t next_serial = 1;
  std::uint64_t command_seq = 0;  // under `control`
  std::mutex data;                // what the planning thread and the control methods share
  std::map<int, double> params;
  std::optional<interp::ModalState> modal;  // carried from one job to the next
  AxisVec work_offset;
  std::deque<std::string> messages;
  std::string state_dir;
  PersistentState last_saved;  // planning thread (housekeeping), then the destructor
  bool save_failed = false;
  std::shared_ptr<LineQueue> stream;  // the stream running or last run (under `data`)
  StreamChecker checker;              // under `control`
  bool checker_in_check = false;      // `checker` follows lines checked in Check
  std::unique_ptr<PlanningThread> planning;
  // The cycle thread's own figures (its thread only, but for the published copy).
  Histogram wake_hist, work_hist;
  std::uint64_t figure_cycles = 0, overruns_at_reset = 0;
  std::atomic<int> figures_request{0};  // 1: publish, 2: publish and reset
  std::atomic<std::uint64_t> figures_serial{0};
  Seqlock<CycleFigures> figures;
  std::atomic<bool> stop_cycle{false};
  std::thread cycle_thread;
};

Result Controller::Impl::start_job(Command command,
                                   std::unique_ptr<interp::Interpreter> interpreter,
                                   const std::string& name, const Status& st, bool prefill,
                                   const std::function<void(Job&)>& made) {
  const MachineConfig m = machine_at(st);
  motion::KernelOptions ko = motion::kernel_options_for(m);
  ko.override_pct = st.feed_override_pct;
  // Single block: every block ends with an exact stop (no merging across it), and the job source
  // puts a program stop after it.
  sim::OperatorModes modes;
  modes.single_block = switches.single_block;
  auto source = std::make_unique<JobSource>(
      std::make_unique<sim::BlockSource>(std::move(interpreter), name, m, ko, modes),
      switches.single_block);
  auto job = std::make_unique<Job>(m, ko, options.block_ring);
  job->serial = next_serial++;
  // The kernel starts full, as `cncore run` fills it before its first cycle.
  Block b;
  bool ended = false;
  if (made) made(*job);
  while (prefill && job->kernel.wants_block()) {
    const auto s = source->next(b);
    if (s == sim::BlockSource::Status::kBlock) {
      job->kernel.push(b);
      continue;
    }
    if (s == sim::BlockSource::Status::kInputError) {
      try {
        std::rethrow_exception(source->source().error());
      } catch (const InputError& e) {
        return Result::fail(e.formatted());
      }
    }
    job->kernel.end_of_program();
    job->end_given = true;
    job->produced_all.store(true);
    ended = true;
    break;
  }
  CycleCommand c = cycle_command(command);
  c.job = job.get();
  c.seq = ++command_seq;
  if (!commands.try_push(c)) return Result::fail("the controller is busy: too many commands");
  if (ended) {
    on_end(source->source().interpreter(), {}, true);
    source.reset();
  }
  // From here the cycle may use the job: the planning thread owns it until the cycle retires it.
  planning->add(std::move(job), std::move(source));
  return wait_taken(c.seq);
}

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
  auto job_link = std::make_shared<std::atomic<const Job*>>(nullptr);
  auto pull = [closer, job_link](std::string& out) {
    const Job* j = job_link->load(std::memory_order_acquire);
    // The stream may end only where the tool has run out of blocks and stands (not held).
    return closer->queue->pull(out, j->cancel, [j] {
      return j->ring.size() == 0 && j->standing.load(std::memory_order_relaxed);
    });
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

Controller::Controller(const MachineConfig& machine, const ControllerOptions& options)
    : impl_(std::make_unique<Impl>(machine, options)) {}

Controller::~Controller() = default;

Status Controller::status() const {
  Status st = impl_->status.load();
  const std::lock_guard lock(impl_->data);
  st.work_offset = impl_->work_offset;
  st.program_loaded = !impl_->program_path.empty();
  st.check_mode = st.state == MachineState::kCheck;
  return st;
}

const MachineConfig& Controller::machine() const {
  return impl_->machine;
}

std::optional<std::string> Controller::take_message() {
  const std::lock_guard lock(impl_->data);
  if (impl_->messages.empty()) return std::nullopt;
  std::string m = std::move(impl_->messages.front());
  impl_->messages.pop_front();
  return m;
}

Result Controller::load_program(const std::string& path) {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  if (Result r = d.allowed(Command::kLoad); !r.ok) return r;
  const Status st = d.status.load();
  const MachineConfig m = d.machine_at(st);
  const interp::Options io = d.interpreter_options();
  const std::string error =
      d.check_program([&] { return std::make_unique<interp::Interpreter>(path, m, io); });
  if (!error.empty()) return Result::fail(error);
  const std::lock_guard data_lock(d.data);
  d.program_path = path;
  return {};
}

Result Controller::cycle_start() {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  const Status st = d.status.load();
  if (st.state == MachineState::kHold) return d.send(cycle_command(Command::kResume));
  if (Result r = d.allowed(Command::kStart); !r.ok) return r;
  std::string path;
  {
    const std::lock_guard data_lock(d.data);
    path = d.program_path;
  }
  if (path.empty()) return Result::fail("no program loaded");
  if (st.state == MachineState::kRun) return {};
  const MachineConfig m = d.machine_at(st);
  const interp::Options io = d.interpreter_options();
  if (st.state == MachineState::kCheck) {
    const std::string error =
        d.check_program([&] { return std::make_unique<interp::Interpreter>(path, m, io); });
    return error.empty() ? Result{} : Result::fail(error);
  }
  try {
    return d.start_job(Command::kStart, std::make_unique<interp::Interpreter>(path, m, io), path,
                       st);
  } catch (const InputError& e) {
    return Result::fail(e.formatted());
  }
}

Result Controller::mdi(const std::string& line) {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  if (Result r = d.allowed(Command::kMdi); !r.ok) return r;
  const Status st = d.status.load();
  const MachineConfig m = d.machine_at(st);
  const interp::Options io = d.interpreter_options();
  auto make = [&] {
    return std::make_unique<interp::Interpreter>(interp::Interpreter::FromText{}, line, "MDI", m,
                                                 io);
  };
  const std::string error = d.check_program(make);
  if (!error.empty() || st.state == MachineState::kCheck) {
    return error.empty() ? Result{} : Result::fail(error);
  }
  try {
    return d.start_job(Command::kMdi, make(), "MDI", st);
  } catch (const InputError& e) {
    return Result::fail(e.formatted());
  }
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

Result Controller::feed_hold() {
  return impl_->command(Command::kHold, true);
}

Result Controller::reset() {
  impl_->close_stream();
  return impl_->command(Command::kReset, false);
}

Result Controller::estop() {
  impl_->close_stream();
  return impl_->command(Command::kEStop, false);
}

Result Controller::clear_alarm() {
  return impl_->command(Command::kClearAlarm, true);
}

Result Controller::jog(const JogRequest& request) {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  if (Result r = d.allowed(Command::kJog); !r.ok) return r;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (((request.axes >> i) & 1U) == 0) continue;
    if (!d.machine.axes[i].enabled) {
      return Result::fail(std::string("jog: the machine has no ") + kAxisLetters[i] + " axis");
    }
    if (!std::isfinite(request.target[i])) return Result::fail("jog: the target is not finite");
  }
  if (request.axes == 0) return Result::fail("jog: no axis named");
  if (!(request.feed_mm_min >= 0) || !std::isfinite(request.feed_mm_min)) {
    return Result::fail("jog: the feed must be > 0");
  }
  CycleCommand c = cycle_command(Command::kJog);
  c.jog = request;
  return d.send(c);
}

Result Controller::jog_cancel() {
  return impl_->command(Command::kJogCancel, false);
}

Result Controller::home() {
  return impl_->command(Command::kHome, true);
}

Result Controller::set_feed_override(double pct) {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  if (!std::isfinite(pct) || pct < 0 || pct > d.machine.max_override_pct) {
    return Result::fail("feed override must be between 0 and " +
                        std::to_string(static_cast<int>(d.machine.max_override_pct)) + " %");
  }
  return d.send(cycle_command(Command::kFeedOverride, pct));
}

Result Controller::set_rapid_override(double pct) {
  const std::lock_guard lock(impl_->control);
  if (!std::isfinite(pct) || pct < 0 || pct > 100) {
    return Result::fail("rapid override must be between 0 and 100 %");
  }
  return impl_->send(cycle_command(Command::kRapidOverride, pct));
}

Result Controller::set_switches(const Switches& switches) {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  d.switches = switches;
  CycleCommand c = cycle_command(Command::kSwitches);
  c.switches = switches;
  return d.send(c);
}

Result Controller::set_check_mode(bool on) {
  return impl_->command(on ? Command::kCheckOn : Command::kCheckOff, true);
}

std::size_t Controller::read_samples(std::span<motion::Sample> out) {
  if (!impl_->samples) return 0;
  std::size_t n = 0;
  while (n < out.size() && impl_->samples->try_pop(out[n])) ++n;
  return n;
}

CycleFigures Controller::cycle_figures(bool reset) {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  const std::uint64_t before = d.figures_serial.load(std::memory_order_acquire);
  d.figures_request.store(reset ? 2 : 1, std::memory_order_release);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  while (d.figures_serial.load(std::memory_order_acquire) == before &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return d.figures.load();
}

std::size_t Controller::read_applied(std::span<AppliedCommand> out) {
  std::size_t n = 0;
  while (n < out.size() && impl_->applied.try_pop(out[n])) ++n;
  return n;
}

}  // namespace cncore::runtime
