// Internal to the runtime: the controller's state behind runtime::Controller, shared by
// controller.cpp (programs, MDI, commands) and controller_stream.cpp (streamed lines).
#pragma once

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
#include "runtime/adaptive_feed.hpp"
#include "runtime/control.hpp"
#include "runtime/cutting.hpp"
#include "runtime/cycle.hpp"
#include "runtime/pacing.hpp"
#include "runtime/persist.hpp"
#include "runtime/planning.hpp"
#include "runtime/stream.hpp"

namespace cncore::runtime {

// The active work offset from LinuxCNC's parameters: the system's (5221 + 20·(n − 1) + axis)
// plus G92 (5211 + axis) while it is applied (5210).
inline AxisVec work_offset_from(const std::map<int, double>& p) {
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

inline bool is_moving(MachineState s) {
  return s == MachineState::kRun || s == MachineState::kHold || s == MachineState::kJog ||
         s == MachineState::kHoming;
}

struct Controller::Impl {
  Impl(MachineConfig m, const ControllerOptions& o)
      : machine(std::move(m)),
        configured(machine),
        options(o),
        commands(256),
        applied(4096),
        state_dir(o.state_dir) {
    if (machine.servo.kp_per_s * machine.period_s > 1) {
      throw std::runtime_error("servo.kp_per_s · motion.period_s must be ≤ 1 for a stable loop");
    }
    AxisVec start;
    for (std::size_t i = 0; i < kMaxAxes; ++i) start[i] = machine.start_position[i];
    if (!state_dir.empty()) {
      const PersistentState ps = load_state(state_dir);
      params = ps.parameters;
      tools = ps.tools;
      if (ps.has_position) start = ps.position;
      last_saved = ps;
    }
    work_offset = work_offset_from(params);
    if (o.sample_ring > 0) samples = std::make_unique<SpscRing<motion::Sample>>(o.sample_ring);
    if (o.servo == ServoKind::kUdp) output = open_udp_output(o.servo_address);
    if (o.servo == ServoKind::kShm) output = open_shm_output(o.servo_address, 4096);
    if (machine.cutting.stock.enabled) {
      // Both keep a reference: to the configuration as started, which never changes (the
      // running `machine` does, under set_limits).
      cutting = std::make_unique<CuttingThread>(configured);
      // Adaptive feed on the simulated cut; settings that do not fit the machine only matter
      // when [adaptive] asks for it at the start (as in `cncore run`).
      try {
        adaptive = std::make_unique<AdaptiveFeed>(configured, *cutting);
      } catch (const InputError&) {
        if (machine.adaptive.enabled) throw;
      }
    }
    CycleLinks links{&commands,    samples.get(),      &applied,      &status,
                     output.get(), o.lossless_samples, cutting.get(), adaptive.get()};
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
    tools = in.tool_table();
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
      ps.tools = tools;
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
    o.block_delete = switches.block_delete;
    o.tools = tools;
    o.subroutine_path = options.subroutine_path;
    // Unknown tools are errors when the machine lists its tools (G10 writes do not change that).
    o.tools_listed = !machine.cutting.tools.empty();
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

  MachineConfig machine;           // as running: set_limits() changes it (under `control`)
  const MachineConfig configured;  // as started: what machine() shows to the other threads
  ControllerOptions options;
  SpscRing<CycleCommand> commands;
  std::unique_ptr<SpscRing<motion::Sample>> samples;
  SpscRing<AppliedCommand> applied;
  Seqlock<Status> status;
  std::unique_ptr<ServoOutput> output;
  std::unique_ptr<CuttingThread> cutting;  // a machine with [stock]; outlives the cycle thread
  std::unique_ptr<AdaptiveFeed> adaptive;  // on the cutting simulation's load
  std::unique_ptr<CycleLoop> loop;
  std::mutex control;  // serialises the control methods (the command ring's one producer)
  std::string program_path;
  Switches switches;
  std::uint64_t next_serial = 1;
  std::uint64_t command_seq = 0;  // under `control`
  std::mutex data;                // what the planning thread and the control methods share
  std::map<int, double> params;
  ToolTable tools;                          // carried like params (G10 L1/L10/L11 writes)
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

}  // namespace cncore::runtime
