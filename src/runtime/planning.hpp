// Internal to the runtime: the planning thread. It interprets the running program ahead of the
// tool and hands its blocks to the cycle through the job's lock-free ring, frees the jobs the
// cycle has retired, and keeps the persistent state file current. Not real-time: it allocates,
// reads files and sleeps.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "runtime/job.hpp"

namespace cncore::runtime {

class PlanningThread {
 public:
  // Called on this thread when a job's source has ended, with its interpreter (what it leaves
  // for the next program: parameters, modal state), the program error (empty when none) and
  // whether the program was read to its end (false: cancelled by a reset or an alarm).
  using EndHandler =
      std::function<void(const interp::Interpreter&, const std::string&, bool completed)>;
  explicit PlanningThread(EndHandler on_end);
  ~PlanningThread();
  PlanningThread(const PlanningThread&) = delete;
  PlanningThread& operator=(const PlanningThread&) = delete;

  // Takes over a job whose kernel has been filled and the source that goes on producing for it.
  void add(std::unique_ptr<Job> job, std::unique_ptr<JobSource> source);
  // A periodic task (state file), run on this thread about every `period_ms`.
  void set_housekeeping(std::function<void()> task, int period_ms);

 private:
  struct Work {
    std::unique_ptr<Job> job;
    std::unique_ptr<JobSource> source;  // null once the source has ended
  };
  void run();
  bool produce(Work& w);  // true when it did something
  void finish_source(Work& w, const std::string& error, bool completed);

  EndHandler on_end_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Work> incoming_;
  std::vector<Work> work_;
  std::function<void()> housekeeping_;
  int housekeeping_ms_ = 1000;
  std::atomic<bool> stop_{false};
  std::thread thread_;  // last: started once the members above exist
};

}  // namespace cncore::runtime
