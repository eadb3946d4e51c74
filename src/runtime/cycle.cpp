#include "runtime/cycle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "runtime/adaptive_feed.hpp"
#include "runtime/cutting.hpp"

namespace cncore::runtime {

namespace {

// The point of the segment from `from` towards `to` (or beyond it, for a continuous jog) that
// stays within the travel of every enabled axis: a jog stops at the limit.
AxisVec clamp_to_travel(const MachineConfig& m, const AxisVec& from, const AxisVec& to) {
  double t_max = 1;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    const AxisConfig& a = m.axes[i];
    const double d = to[i] - from[i];
    if (!a.enabled || a.max_mm <= a.min_mm || d == 0) continue;
    const double room = d > 0 ? a.max_mm - from[i] : a.min_mm - from[i];
    t_max = std::min(t_max, std::max(room / d, 0.0));
  }
  AxisVec r = from;
  for (std::size_t i = 0; i < kMaxAxes; ++i) r[i] = from[i] + t_max * (to[i] - from[i]);
  return r;
}

}  // namespace

CycleLoop::CycleLoop(const MachineConfig& machine, const CycleLinks& links, const AxisVec& start,
                     const AxisVec& sim_position_error)
    : machine_(machine), links_(links), sim_(machine_, start, sim_position_error) {
  status_.commanded = start;
  status_.actual = start;
  // Homing order: Z first (the tool away from the part), then X, Y and the rotary axes.
  for (const Axis axis : {kZ, kX, kY, kA, kB, kC}) {
    if (machine_.axes[axis].enabled) home_order_[home_count_++] = static_cast<std::uint8_t>(axis);
  }
}

void CycleLoop::run(std::uint64_t n) {
  CycleCommand c;
  while (links_.commands->try_pop(c)) {
    apply(c, n);
    status_.applied_commands = c.seq;
  }
  motion::Sample s;
  s.position = status_.commanded;
  s.path_position = status_.commanded;
  speed_mm_s_ = 0;
  const MachineState st = status_.state;
  if (job_ != nullptr && (st == MachineState::kRun || st == MachineState::kHold)) {
    program_cycle(s);
  } else if (st == MachineState::kJog || st == MachineState::kHoming) {
    motion_cycle(s);
  }
  finish_outputs(n, s);
}

void CycleLoop::apply(const CycleCommand& c, std::uint64_t n) {
  const Transition t = transition(status_.state, c.command);
  if (!t.allowed) {
    // The control side refused it already unless the state changed in between: drop it.
    if (c.job != nullptr) {
      c.job->cancel.store(true, std::memory_order_release);
      c.job->retired.store(true, std::memory_order_release);
    }
    return;
  }
  if (links_.applied != nullptr) links_.applied->try_push(AppliedCommand{n, c.command, c.value});
  const bool moving_alone =
      status_.state == MachineState::kJog || status_.state == MachineState::kHoming;
  switch (c.command) {
    case Command::kStart:
    case Command::kMdi:
      if (c.job != nullptr && job_ == nullptr) {
        start_job(c.job, n, c.command == Command::kMdi);
      } else if (c.job != nullptr) {  // one job at a time: the planner frees this one
        c.job->cancel.store(true, std::memory_order_release);
        c.job->retired.store(true, std::memory_order_release);
      }
      break;
    case Command::kResume:
      if (job_ != nullptr) {
        job_->kernel.set_feed_hold(false);
        // Single block: one more block. The blocks the kernel took before the switch went on
        // have no program stop after them: the kernel stops at the next block end instead.
        job_->kernel.release_stop_at_block_end();
        if (status_.switches.single_block) job_->kernel.request_stop_at_block_end();
      }
      paused_by_program_ = false;
      status_.state = MachineState::kRun;
      status_.hold_complete = false;
      break;
    case Command::kHold:
    case Command::kReset:
    case Command::kJog:
    case Command::kJogCancel:
    case Command::kHome:
      apply_stop_or_move(c, moving_alone);
      break;
    case Command::kEStop:
      line_ = LineMotion{};  // set-points frozen from this cycle on
      jog_pending_ = false;
      raise_alarm(AlarmCode::kEStop, status_.line);
      break;
    case Command::kClearAlarm:
      if (status_.state == MachineState::kAlarm) {
        status_.state = MachineState::kIdle;
        status_.alarm = AlarmCode::kNone;
        status_.alarm_line = 0;
      }
      break;
    case Command::kFeedOverride:
      status_.feed_override_pct = c.value;
      if (job_ != nullptr) job_->kernel.set_override(c.value);
      break;
    case Command::kRapidOverride:
      status_.rapid_override_pct = c.value;
      rapid_set_ = true;
      if (job_ != nullptr) job_->kernel.set_rapid_override(c.value);
      break;
    case Command::kSwitches:
      if (job_ != nullptr && c.switches.single_block != status_.switches.single_block) {
        // On: the blocks the kernel holds already (up to the whole look-ahead buffer) came
        // without a program stop after them, so the kernel stops at the first block end it can
        // still stop at. Off: that stop is lifted (a cycle start still ends a pause there).
        if (c.switches.single_block) {
          job_->kernel.request_stop_at_block_end();
        } else {
          job_->kernel.release_stop_at_block_end();
        }
      }
      status_.switches = c.switches;
      break;
    case Command::kCheckOn:
      status_.state = MachineState::kCheck;
      break;
    case Command::kCheckOff:
      status_.state = MachineState::kIdle;
      break;
    case Command::kLimits:
      apply_limits(machine_, c.limits);  // doubles only: no allocation
      break;
    case Command::kLoad:
    case Command::kCount:
      break;
  }
}

// Hold, reset, jog and homing: what they do depends on what moves now.
void CycleLoop::apply_stop_or_move(const CycleCommand& c, bool moving_alone) {
  switch (c.command) {
    case Command::kHold:
      if (job_ != nullptr && status_.state == MachineState::kRun) {
        job_->kernel.set_feed_hold(true);
        status_.state = MachineState::kHold;
        status_.hold_complete = false;
      } else if (moving_alone) {
        line_.stop();
        jog_pending_ = false;
      }
      break;
    case Command::kReset:
      if (job_ != nullptr) {
        job_->kernel.set_feed_hold(true);
        status_.resetting = true;
      } else if (moving_alone) {
        line_.stop();
        jog_pending_ = false;
        status_.resetting = true;
      }
      break;
    case Command::kJog: {
      if (status_.state == MachineState::kJog) {
        pending_jog_ = c.jog;
        jog_pending_ = true;
        break;
      }
      pending_jog_ = c.jog;
      jog_pending_ = true;
      status_.state = MachineState::kJog;
      break;
    }
    case Command::kJogCancel:
      if (status_.state == MachineState::kJog) line_.stop();
      jog_pending_ = false;
      break;
    case Command::kHome:
      status_.alarm = AlarmCode::kNone;
      status_.homed = false;
      status_.state = MachineState::kHoming;
      home_index_ = 0;
      if (home_count_ == 0) {
        status_.state = MachineState::kIdle;
      } else {
        start_homing_axis();
      }
      break;
    default:
      break;
  }
}

void CycleLoop::start_job(Job* job, std::uint64_t n, bool mdi) {
  job_ = job;
  status_.job_mdi = mdi;
  status_.job_end = JobEnd::kRunning;
  status_.job_first_cycle = n;
  status_.job_last_cycle = n;
  ended_sent_ = false;
  paused_by_program_ = false;
  status_.state = MachineState::kRun;
  status_.hold_complete = false;
  status_.resetting = false;
  status_.job = job->serial;
  // Overrides changed since the control side made the kernel.
  job->kernel.set_override(status_.feed_override_pct);
  if (rapid_set_) job->kernel.set_rapid_override(status_.rapid_override_pct);
}

void CycleLoop::retire_job(JobEnd end) {
  if (job_ == nullptr) return;
  status_.job_end = end;
  job_->cancel.store(true, std::memory_order_release);
  job_->retired.store(true, std::memory_order_release);
  job_ = nullptr;
  ended_sent_ = false;
  paused_by_program_ = false;
}

void CycleLoop::feed_kernel() {
  Job& j = *job_;
  if (ended_sent_) return;
  const bool single_block = status_.switches.single_block;
  auto from_ring = [&j](Block& b) { return j.ring.try_pop(b); };
  for (int k = 0; k < kMaxPushesPerCycle && j.kernel.wants_block(); ++k) {
    if (feed_one(j, single_block, from_ring)) continue;
    // The planner publishes its end after its last block: look at the ring once more.
    if (j.produced_all.load(std::memory_order_acquire) ||
        j.failed.load(std::memory_order_acquire)) {
      if (feed_one(j, single_block, from_ring)) continue;
      j.kernel.end_of_program();
      ended_sent_ = true;
      break;
    }
    ++status_.starved_cycles;  // the kernel stops at the end of what it has: safe, but slower
    break;
  }
}

void CycleLoop::program_cycle(motion::Sample& s) {
  Job& j = *job_;
  feed_kernel();
  if (!j.kernel.step(s)) {
    const bool failed = j.failed.load(std::memory_order_acquire);
    const bool fatal = j.fatal.load(std::memory_order_acquire);
    const std::uint32_t line = j.error_line;
    retire_job(failed || fatal ? JobEnd::kAlarm : JobEnd::kCompleted);
    status_.resetting = false;
    status_.hold_complete = false;
    s.position = status_.commanded;
    s.path_position = status_.commanded;
    if (fatal) {
      raise_alarm(AlarmCode::kPlannerLost, line);
    } else if (failed) {
      raise_alarm(AlarmCode::kProgramError, line);
    } else {
      status_.state = MachineState::kIdle;
    }
    return;
  }
  status_.line = s.line;
  speed_mm_s_ = s.feed_mm_min / 60;
  note_aux(s);
  const bool single_block_pause = s.aux_value == 0 && s.aux_p == kSingleBlockPause;
  const bool pause =
      (s.aux_letter == 'M' &&
       ((s.aux_value == 0 && (!single_block_pause || status_.switches.single_block)) ||
        (s.aux_value == 1 && status_.switches.optional_stop))) ||
      (status_.switches.single_block && j.kernel.stopped_at_block_end());
  if (pause && status_.state == MachineState::kRun) {
    j.kernel.set_feed_hold(true);
    status_.state = MachineState::kHold;
    paused_by_program_ = true;
  }
  const bool still = s.feed_mm_min == 0 && s.position == status_.commanded;
  j.standing.store(still && status_.state == MachineState::kRun, std::memory_order_relaxed);
  status_.commanded = s.position;
  if (status_.state == MachineState::kHold) status_.hold_complete = still;
  if (status_.resetting && still) {
    retire_job(JobEnd::kReset);
    status_.resetting = false;
    status_.hold_complete = false;
    status_.spindle_on = false;  // a reset ends the program and stops the spindle
    status_.coolant_mist = status_.coolant_flood = false;
    status_.state = MachineState::kIdle;
  }
}

void CycleLoop::note_aux(const motion::Sample& s) {
  if (s.aux_letter == 'S') status_.spindle_rpm = s.aux_value;
  if (s.aux_letter == 'T') tool_prepared_ = static_cast<std::uint32_t>(s.aux_value);
  if (s.aux_letter != 'M') return;
  if (s.aux_value == 3 || s.aux_value == 4) {
    status_.spindle_on = true;
    status_.spindle_ccw = s.aux_value == 4;
  }
  if (s.aux_value == 5 || s.aux_value == 2 || s.aux_value == 30) status_.spindle_on = false;
  if (s.aux_value == 7) status_.coolant_mist = true;
  if (s.aux_value == 8) status_.coolant_flood = true;
  if (s.aux_value == 9 || s.aux_value == 2 || s.aux_value == 30) {
    status_.coolant_mist = status_.coolant_flood = false;
  }
  if (s.aux_value == 6) status_.tool = tool_prepared_;
}

void CycleLoop::motion_cycle(motion::Sample& s) {
  AxisVec p = status_.commanded;
  double v = 0;
  if (line_.step(p, v)) {
    status_.commanded = p;
    speed_mm_s_ = v;
  }
  if (status_.resetting) {
    if (!line_.active()) {
      status_.resetting = false;
      status_.state = MachineState::kIdle;
    }
  } else if (status_.state == MachineState::kHoming) {
    homing_step();
  } else if (!line_.active()) {
    if (jog_pending_) {
      jog_pending_ = false;
      const JogRequest& r = pending_jog_;
      AxisVec to = status_.commanded;
      for (std::size_t i = 0; i < kMaxAxes; ++i) {
        if (((r.axes >> i) & 1U) == 0) continue;
        // A continuous jog heads for the travel limit along its direction.
        to[i] = r.continuous    ? status_.commanded[i] + r.target[i] * 1e6
                : r.incremental ? status_.commanded[i] + r.target[i]
                                : r.target[i];
      }
      to = clamp_to_travel(machine_, status_.commanded, to);
      const double feed = r.feed_mm_min > 0 ? r.feed_mm_min : machine_.servo.jog_feed_mm_min;
      line_.start(machine_, status_.commanded, to, feed);
      if (!line_.active()) status_.state = MachineState::kIdle;
    } else {
      status_.state = MachineState::kIdle;
    }
  }
  s.position = status_.commanded;
  s.path_position = status_.commanded;
}

void CycleLoop::start_homing_axis() {
  const std::size_t axis = home_order_[home_index_];
  const AxisConfig& a = machine_.axes[axis];
  AxisVec to = status_.commanded;
  // Past the far end on purpose: the switch is at the travel maximum, wherever the axis is.
  to[axis] += 1.5 * (a.max_mm - a.min_mm) + 1;
  line_.start(machine_, status_.commanded, to, machine_.servo.home_search_mm_min);
  home_phase_ = HomePhase::kSearch;
}

void CycleLoop::homing_step() {
  const std::size_t axis = home_order_[home_index_];
  const AxisConfig& a = machine_.axes[axis];
  switch (home_phase_) {
    case HomePhase::kSearch:
      if (sim_.switch_pressed(axis)) {
        line_.stop();
        home_phase_ = HomePhase::kStopping;
      } else if (!line_.active()) {
        raise_alarm(AlarmCode::kHomingFailed, 0);
      }
      break;
    case HomePhase::kStopping:
      if (!line_.active()) {
        AxisVec to = status_.commanded;
        to[axis] -= a.max_mm - a.min_mm;
        line_.start(machine_, status_.commanded, to, machine_.servo.home_latch_mm_min);
        home_phase_ = HomePhase::kLatch;
      }
      break;
    case HomePhase::kLatch:
      if (!sim_.switch_pressed(axis)) {
        // The switch released here: this point is the travel maximum.
        const double delta = a.max_mm - status_.commanded[axis];
        status_.commanded[axis] += delta;
        sim_.rebase(axis, delta);
        AxisVec to = status_.commanded;
        to[axis] = a.max_mm - machine_.servo.home_pulloff_mm;
        line_.start(machine_, status_.commanded, to, machine_.servo.home_latch_mm_min);
        home_phase_ = HomePhase::kPulloff;
      } else if (!line_.active()) {
        raise_alarm(AlarmCode::kHomingFailed, 0);
      }
      break;
    case HomePhase::kPulloff:
      if (!line_.active()) {
        if (++home_index_ == home_count_) {
          status_.homed = true;
          status_.state = MachineState::kIdle;
        } else {
          start_homing_axis();
        }
      }
      break;
  }
}

void CycleLoop::raise_alarm(AlarmCode alarm, std::uint32_t line) {
  retire_job(JobEnd::kAlarm);
  line_ = LineMotion{};
  jog_pending_ = false;
  status_.resetting = false;
  status_.hold_complete = false;
  status_.state = MachineState::kAlarm;
  status_.alarm = alarm;
  status_.alarm_line = line;
  status_.spindle_on = false;  // an alarm stops the spindle with the axes
  status_.coolant_mist = status_.coolant_flood = false;
}

void CycleLoop::finish_outputs(std::uint64_t n, motion::Sample& s) {
  if (links_.cutting != nullptr) links_.cutting->on_cycle(n, s, status_);
  if (links_.adaptive != nullptr && job_ != nullptr) {
    job_->kernel.set_override(links_.adaptive->on_cycle(s, status_));
  }
  const double fe = sim_.step(status_.commanded);
  status_.following_error_mm = fe;
  status_.actual = sim_.actual();
  if (fe > machine_.servo.following_error_limit_mm && status_.state != MachineState::kAlarm) {
    raise_alarm(AlarmCode::kFollowingError, status_.line);
  }
  status_.cycle = n;
  if (job_ != nullptr) status_.job_last_cycle = n;
  status_.feed_mm_min = speed_mm_s_ * 60;
  status_.blocks_queued = job_ != nullptr ? static_cast<std::uint32_t>(job_->ring.size()) : 0;
  if (job_ == nullptr) status_.line = 0;
  if (links_.output != nullptr) {
    ServoRecord r;
    r.seq = n;
    r.t_ns =
        static_cast<std::uint64_t>(std::llround(static_cast<double>(n) * machine_.period_s * 1e9));
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      if (machine_.axes[i].enabled) r.axes |= static_cast<std::uint8_t>(1U << i);
    }
    r.state = static_cast<std::uint8_t>(status_.state);
    r.alarm = static_cast<std::uint8_t>(status_.alarm);
    r.line = status_.line;
    r.setpoint = status_.commanded.v;
    links_.output->write(r);
  }
  if (links_.samples != nullptr) {
    s.t_s = static_cast<double>(n) * machine_.period_s;
    s.override_pct = status_.feed_override_pct;
    if (job_ == nullptr) {
      s.line = 0;
      s.feed_mm_min = speed_mm_s_ * 60;
    }
    while (!links_.samples->try_push(s)) {
      if (!links_.lossless_samples || (stopping_ != nullptr && stopping_->load())) {
        ++status_.samples_dropped;
        break;
      }
      std::this_thread::yield();  // tests only (ControllerOptions::lossless_samples)
    }
  }
  links_.status->store(status_);
}

}  // namespace cncore::runtime
