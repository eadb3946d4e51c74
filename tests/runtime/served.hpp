// Test harness: a Controller with every cycle's sample collected on a thread of its own, and
// waits on its status.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "runtime/control.hpp"

namespace cncore::runtime::testing {

class Served {
 public:
  explicit Served(const MachineConfig& machine, ControllerOptions o = default_options())
      : machine_(machine) {
    c_ = std::make_unique<Controller>(machine_, o);
    controller_ = c_.get();
    collector_ = std::thread([this] { collect(); });
  }
  ~Served() {
    // Stop what moves while the collector still drains (the cycle waits for it), then the rest.
    (void)c_->reset();
    wait_for([](const Status& st) {
      return st.state != MachineState::kRun && st.state != MachineState::kHold &&
             st.state != MachineState::kJog && st.state != MachineState::kHoming;
    });
    stop_.store(true);
    collector_.join();
    c_.reset();
  }
  Served(const Served&) = delete;
  Served& operator=(const Served&) = delete;

  static ControllerOptions default_options() {
    ControllerOptions o;
    o.realtime = false;
    o.paced = true;
    o.lossless_samples = true;
    return o;
  }

  Controller& c() { return *c_; }
  const MachineConfig& machine() const { return machine_; }

  bool wait_for(const std::function<bool(const Status&)>& done, double timeout_s = 60) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < end) {
      if (done(c_->status())) return true;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    return false;
  }
  bool wait_state(MachineState s, double timeout_s = 60) {
    return wait_for([s](const Status& st) { return st.state == s && !st.resetting; }, timeout_s);
  }
  // Waits until `cycles` more cycles have run.
  void wait_cycles(std::uint64_t cycles) {
    const std::uint64_t until = c_->status().cycle + cycles;
    wait_for([until](const Status& st) { return st.cycle >= until; });
  }

  // Every cycle's sample so far, indexed by cycle number.
  std::vector<motion::Sample> samples() {
    const std::lock_guard lock(mutex_);
    return samples_;
  }
  std::vector<AppliedCommand> applied() {
    const std::lock_guard lock(mutex_);
    return applied_;
  }

 private:
  void collect() {
    std::vector<motion::Sample> batch(4096);
    std::vector<AppliedCommand> cmds(64);
    while (!stop_.load()) {
      const std::size_t n = controller_->read_samples(batch);
      const std::size_t k = controller_->read_applied(cmds);
      {
        const std::lock_guard lock(mutex_);
        samples_.insert(samples_.end(), batch.begin(), batch.begin() + static_cast<long>(n));
        applied_.insert(applied_.end(), cmds.begin(), cmds.begin() + static_cast<long>(k));
      }
      if (n == 0) std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
  }

  MachineConfig machine_;
  std::unique_ptr<Controller> c_;
  Controller* controller_ = nullptr;  // the collector's (c_ is reset only after it stopped)
  std::mutex mutex_;
  std::vector<motion::Sample> samples_;
  std::vector<AppliedCommand> applied_;
  std::atomic<bool> stop_{false};
  std::thread collector_;
};

}  // namespace cncore::runtime::testing
