#include "runtime/controller_impl.hpp"

namespace cncore::runtime {

Result Controller::Impl::start_job(Command command,
                                   std::unique_ptr<interp::Interpreter> interpreter,
                                   const std::string& name, const Status& st, bool prefill,
                                   const std::function<void(Job&)>& made) {
  const MachineConfig m = machine_at(st);
  motion::KernelOptions ko = motion::kernel_options_for(m);
  ko.override_pct = st.feed_override_pct;
  // Single block at the start: no block is merged across (each ends with an exact stop), and
  // feed_one puts a program stop after each.
  sim::OperatorModes modes;
  modes.single_block = switches.single_block;
  auto source = std::make_unique<JobSource>(
      std::make_unique<sim::BlockSource>(std::move(interpreter), name, m, ko, modes));
  auto job = std::make_unique<Job>(m, ko, options.block_ring);
  job->serial = next_serial++;
  // The kernel starts full, as `cncore run` fills it before its first cycle.
  bool ended = false;
  if (made) made(*job);
  while (prefill && job->kernel.wants_block()) {
    auto s = sim::BlockSource::Status::kBlock;
    const bool fed = feed_one(*job, switches.single_block, [&](Block& next) {
      s = source->next(next);
      return s == sim::BlockSource::Status::kBlock;
    });
    if (fed) continue;
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

Controller::Controller(const MachineConfig& machine, const ControllerOptions& options)
    : impl_(std::make_unique<Impl>(machine, options)) {}

Controller::~Controller() = default;

Status Controller::status() const {
  Status st = impl_->status.load();
  const std::lock_guard lock(impl_->data);
  st.work_offset = impl_->work_offset;
  st.program_loaded = !impl_->program_path.empty();
  st.check_mode = st.state == MachineState::kCheck;
  if (impl_->cutting) st.heightmap_version = impl_->cutting->version();
  return st;
}

const MachineConfig& Controller::machine() const {
  return impl_->configured;
}

MachineLimits Controller::limits() const {
  const std::lock_guard lock(impl_->control);
  return limits_of(impl_->machine);
}

Result Controller::set_limits(const MachineLimits& limits) {
  Impl& d = *impl_;
  const std::lock_guard lock(d.control);
  if (std::string e = limits_error(limits, d.machine); !e.empty()) return Result::fail(e);
  if (Result r = d.allowed(Command::kLimits); !r.ok) return r;
  if (d.status.load().resetting) return Result::fail("a reset is stopping the tool: wait for Idle");
  apply_limits(d.machine, limits);
  CycleCommand c = cycle_command(Command::kLimits);
  c.limits = limits;
  return d.send(c);
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
  // Checked again as a whole before motion: MDI lines, the tool or the block delete switch may
  // have changed what the program does since it was loaded.
  const std::string error =
      d.check_program([&] { return std::make_unique<interp::Interpreter>(path, m, io); });
  if (st.state == MachineState::kCheck || !error.empty()) {
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
