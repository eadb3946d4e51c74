#include "runtime/planning.hpp"

#include <chrono>
#include <exception>

#include "core/error.hpp"

namespace cncore::runtime {

PlanningThread::PlanningThread(EndHandler on_end)
    : on_end_(std::move(on_end)), thread_([this] { run(); }) {}

PlanningThread::~PlanningThread() {
  stop_.store(true);
  wake_.notify_all();
  thread_.join();
}

void PlanningThread::add(std::unique_ptr<Job> job, std::unique_ptr<JobSource> source) {
  {
    const std::lock_guard lock(mutex_);
    incoming_.push_back(Work{std::move(job), std::move(source)});
  }
  wake_.notify_all();
}

void PlanningThread::set_housekeeping(std::function<void()> task, int period_ms) {
  const std::lock_guard lock(mutex_);
  housekeeping_ = std::move(task);
  housekeeping_ms_ = period_ms;
}

void PlanningThread::finish_source(Work& w, const std::string& error, bool completed) {
  if (w.source && on_end_) on_end_(w.source->source().interpreter(), error, completed);
  w.source.reset();
}

bool PlanningThread::produce(Work& w) {
  Job& j = *w.job;
  if (!w.source) return false;
  if (j.cancel.load(std::memory_order_acquire)) {
    finish_source(w, {}, false);
    return true;
  }
  bool did = false;
  Block b;
  // Up to a batch per pass, so a retired job or a new one is seen soon.
  for (int k = 0; k < 512 && j.ring.size() < j.ring.capacity(); ++k) {
    sim::BlockSource::Status st = sim::BlockSource::Status::kEnd;
    std::string fatal;
    try {
      st = w.source->next(b);
    } catch (const std::exception& e) {
      fatal = e.what();
    }
    did = true;
    if (!fatal.empty()) {
      j.fatal.store(true, std::memory_order_release);
      j.failed.store(true, std::memory_order_release);
      finish_source(w, "planner failed: " + fatal, false);
      return true;
    }
    if (st == sim::BlockSource::Status::kBlock) {
      j.ring.try_push(b);  // room checked above; only this thread pushes
      continue;
    }
    std::string error;
    if (st == sim::BlockSource::Status::kInputError) {
      try {
        std::rethrow_exception(w.source->source().error());
      } catch (const InputError& e) {
        error = e.formatted();
        j.error_line = e.line();
      } catch (const std::exception& e) {
        error = e.what();
      }
      j.failed.store(true, std::memory_order_release);
    } else {
      j.produced_all.store(true, std::memory_order_release);
    }
    // A stream's source also ends when it is cancelled: that is no completed program.
    finish_source(w, error, error.empty() && !j.cancel.load(std::memory_order_acquire));
    break;
  }
  return did;
}

void PlanningThread::run() {
  auto last_housekeeping = std::chrono::steady_clock::now();
  while (!stop_.load()) {
    std::function<void()> housekeeping;
    int period_ms = 1000;
    {
      const std::lock_guard lock(mutex_);
      while (!incoming_.empty()) {
        work_.push_back(std::move(incoming_.front()));
        incoming_.pop_front();
      }
      housekeeping = housekeeping_;
      period_ms = housekeeping_ms_;
    }
    bool did = false;
    for (Work& w : work_) did = produce(w) || did;
    // Free what the cycle has let go of and the source no longer needs.
    std::erase_if(work_, [](const Work& w) {
      return !w.source && w.job->retired.load(std::memory_order_acquire);
    });
    const auto now = std::chrono::steady_clock::now();
    if (housekeeping && now - last_housekeeping >= std::chrono::milliseconds(period_ms)) {
      last_housekeeping = now;
      housekeeping();
    }
    if (!did) {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, std::chrono::milliseconds(1),
                     [this] { return stop_.load() || !incoming_.empty(); });
    }
  }
}

}  // namespace cncore::runtime
