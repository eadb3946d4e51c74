// Internal to the runtime: the cutting simulation of `cncore serve` (a machine with [stock]).
// Its cost per cycle grows with the cells under the tool's footprint, so it does not run in the
// cycle thread: the cycle hands each cycle's tool position to a thread of its own through a
// bounded lock-free ring and reads back the spindle load it last computed (an atomic). The
// cycle never waits: when the ring is full it keeps the sample and merges the following cycles
// into it (the newest position, the tool events, the count of cycles), so the simulation later
// sweeps the straight segment from the last position it took to that one and no material
// removal is lost (on a curve, the chord of the merged cycles instead of their arc).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "config/machine_config.hpp"
#include "core/spsc_ring.hpp"
#include "motion/kernel.hpp"
#include "runtime/control.hpp"
#include "simulation/cutting/cutting_sim.hpp"

namespace cncore::runtime {

// One cycle's tool position for the simulation, or several merged cycles.
struct CutSample {
  std::uint64_t cycle = 0;    // the latest cycle it stands for
  std::uint32_t cycles = 1;   // cycles it stands for (> 1: merged while the ring was full)
  Vec3 position{};            // tool tip, machine coordinates (mm)
  double tool_selected = -1;  // a T word reached (its number), −1: none
  bool tool_change = false;   // M6 reached
  bool fresh_stock = false;   // a program starts: the stock is made new before this sample
};

class CuttingThread {
 public:
  // machine.cutting.stock.enabled; ring_cycles: a power of two. start = false: the thread starts
  // at start() (tests fill the ring first).
  explicit CuttingThread(const MachineConfig& machine, std::size_t ring_cycles = 4096,
                         bool start = true);
  ~CuttingThread();
  CuttingThread(const CuttingThread&) = delete;
  CuttingThread& operator=(const CuttingThread&) = delete;
  void start();

  // Cycle thread only: hands over cycle n's sample (status: the cycle's status so far) and
  // writes the load the simulation last computed into status.load_pct and s.load_pct, with the
  // figures status.cutting_coalesced and cutting_lag_cycles. A program job (not MDI) that starts
  // makes the stock new. Wait-free, no allocation.
  void on_cycle(std::uint64_t n, motion::Sample& s, Status& status) noexcept;

  // Any thread.
  void request_fresh_stock() { fresh_requested_.store(true, std::memory_order_release); }
  std::shared_ptr<const HeightMapGrid> heightmap() const;
  double load_pct() const { return load_pct_.load(std::memory_order_relaxed); }
  std::uint64_t version() const { return version_.load(std::memory_order_acquire); }
  // Cycles the simulation has taken so far (waits in tests).
  std::uint64_t cycles_done() const { return cycles_done_.load(std::memory_order_acquire); }

  // Publishes a new map when it changed, at most this often.
  static constexpr std::chrono::milliseconds kPublishEvery{500};

 private:
  void run();
  void take(const CutSample& c);
  void step(const Vec3& p, double tool_selected, bool tool_change);
  void make_fresh();
  void publish();

  const MachineConfig& machine_;
  SpscRing<CutSample> ring_;
  // Cycle thread's.
  CutSample pending_;
  bool has_pending_ = false;
  std::uint64_t coalesced_ = 0;
  std::uint64_t last_job_ = 0;
  // Simulation thread's.
  std::optional<cut::CuttingSimulator> sim_;
  Vec3 last_{};
  bool have_last_ = false;
  bool changed_ = true;
  std::chrono::steady_clock::time_point published_at_{};
  // Shared.
  std::atomic<double> load_pct_{0};
  std::atomic<std::uint64_t> taken_cycle_{0};
  std::atomic<std::uint64_t> cycles_done_{0};
  std::atomic<bool> fresh_requested_{false};
  std::atomic<std::uint64_t> version_{0};
  mutable std::mutex map_mutex_;  // guards map_ (the simulation thread is not real-time)
  std::shared_ptr<const HeightMapGrid> map_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace cncore::runtime
