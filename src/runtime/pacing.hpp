// Pacing of the cycle thread and its figures: absolute-time sleeps on the monotonic clock (the
// n-th cycle is due at t0 + n·τ, so errors never accumulate), the wake-up latency and the work
// of every cycle in fixed histograms (allocated once, before the loop), and the real-time set-up
// the process is allowed (SCHED_FIFO, mlockall).
#pragma once

#include <cstdint>
#include <ctime>
#include <string>
#include <vector>

namespace cncore::runtime {

std::int64_t monotonic_ns();
// Sleeps until the monotonic clock reads `due_ns` (at once if it has passed).
void sleep_until_ns(std::int64_t due_ns);

// Tries SCHED_FIFO at `priority` for the calling thread and mlockall for the process. Returns
// what could not be done, in one line for the operator (empty: both done).
std::string enter_realtime(int priority);

// Counts of values in µs: 1 µs bins up to `max_us`, one overflow bin; the largest value seen.
class Histogram {
 public:
  explicit Histogram(std::uint32_t max_us = 20000) : bins_(max_us + 2, 0) {}
  void add_ns(std::int64_t ns);
  std::uint64_t count() const { return count_; }
  double max_us() const { return static_cast<double>(max_ns_) / 1000.0; }
  // The value (µs, bin upper edge) below which a fraction q of the values lie.
  double quantile_us(double q) const;
  void clear();

 private:
  std::vector<std::uint64_t> bins_;
  std::uint64_t count_ = 0;
  std::int64_t max_ns_ = 0;
};

}  // namespace cncore::runtime
