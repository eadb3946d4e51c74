#include "runtime/pacing.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace cncore::runtime {

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

void sleep_until_ns(std::int64_t due_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(due_ns / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(due_ns % 1'000'000'000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

std::string enter_realtime(int priority) {
  std::string missing;
  sched_param sp{};
  sp.sched_priority = priority;
  if (const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp); rc != 0) {
    missing += "no SCHED_FIFO (" + std::string(std::strerror(rc)) +
               "; needs CAP_SYS_NICE, root or `ulimit -r`)";
  }
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    if (!missing.empty()) missing += ", ";
    missing += "no mlockall (" + std::string(std::strerror(errno)) +
               "; needs CAP_IPC_LOCK or `ulimit -l`)";
  }
  return missing;
}

void Histogram::add_ns(std::int64_t ns) {
  ns = std::max<std::int64_t>(ns, 0);
  const auto us = static_cast<std::size_t>(ns / 1000);
  ++bins_[std::min(us, bins_.size() - 1)];
  ++count_;
  max_ns_ = std::max(max_ns_, ns);
}

double Histogram::quantile_us(double q) const {
  if (count_ == 0) return 0;
  const auto want = static_cast<std::uint64_t>(q * static_cast<double>(count_ - 1)) + 1;
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < bins_.size(); ++i) {
    seen += bins_[i];
    if (seen >= want) return i + 1 == bins_.size() ? max_us() : static_cast<double>(i + 1);
  }
  return max_us();
}

void Histogram::clear() {
  std::fill(bins_.begin(), bins_.end(), 0);
  count_ = 0;
  max_ns_ = 0;
}

}  // namespace cncore::runtime
