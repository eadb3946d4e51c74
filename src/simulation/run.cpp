#include "simulation/run.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <thread>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif
#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif

#include "core/error.hpp"
#include "core/spsc_ring.hpp"
#include "simulation/block_source.hpp"

namespace cncore::sim {

namespace {

// What the block source hands the motion cycle next: a kernel block, the end of the program,
// or an error.
enum class ItemKind : std::uint8_t {
  kBlock,
  kEnd,
  kInputError,  // stop at the end of the last good block, then rethrow
  kFatal,       // anything else: rethrow at once (as the single-thread path lets it through)
};

// 256 bytes, on 4 whole cache lines: the hand-over between cores moves whole lines.
struct alignas(64) Item {
  Block block;  // kBlock
  ItemKind kind = ItemKind::kEnd;
};

// The program's kernel blocks (simulation/block_source.hpp) as items for the motion cycle.
class BlockProducer {
 public:
  BlockProducer(const std::string& program_path, const MachineConfig& machine,
                const interp::Options& options, const motion::KernelOptions& kernel,
                const OperatorModes& modes)
      : source_(program_path, machine, options, kernel, modes) {}

  // Fills `item` (kBlock / kEnd / kInputError; the InputError in error()). Other exceptions
  // propagate.
  void next(Item& item) {
    switch (source_.next(item.block)) {
      case BlockSource::Status::kBlock:
        item.kind = ItemKind::kBlock;
        break;
      case BlockSource::Status::kEnd:
        item.kind = ItemKind::kEnd;
        break;
      case BlockSource::Status::kInputError:
        item.kind = ItemKind::kInputError;
        break;
    }
  }

  std::exception_ptr error() const { return source_.error(); }
  // Motion blocks interpreted so far (the cycle reads it once the producer has ended).
  std::uint64_t motion_blocks() const { return source_.motion_blocks(); }

 private:
  BlockSource source_;
};

// The single-thread source: produces each item when the cycle asks for it.
class InlineSource {
 public:
  explicit InlineSource(BlockProducer& producer) : producer_(producer) {}
  const Item& front() {
    producer_.next(item_);
    return item_;
  }
  void pop() {}
  void cycle_done() {}
  void finish(RunCounts& counts) const { counts.blocks = producer_.motion_blocks(); }
  std::exception_ptr error() const { return producer_.error(); }

 private:
  BlockProducer& producer_;
  Item item_;
};

// A full barrier between a store and a later load of another variable (the Dekker handshake
// below). ThreadSanitizer does not model fences (gcc refuses them under -fsanitize=thread):
// there an acq_rel read-modify-write of one shared variable orders the two sides instead
// (whichever RMW comes second acquires what the other side stored before its own).
inline void store_load_barrier([[maybe_unused]] std::atomic<std::uint32_t>& sync) {
#if defined(__SANITIZE_THREAD__)
  sync.fetch_add(0, std::memory_order_acq_rel);
#else
  std::atomic_thread_fence(std::memory_order_seq_cst);
#endif
}

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

// The threaded source: a producer thread runs the BlockProducer ahead of the cycle and hands
// the items through a lock-free SPSC ring; the cycle reads them in place.
//
// Waiting (outside the ring): the producer sleeps while the ring is full, until the cycle has
// drained it to half (few wake-ups); the cycle, finding it empty, spins briefly (a block that
// is being interpreted right now), then sleeps until the producer has queued a batch or ended.
// Sleeping is std::atomic::wait on a wake-up counter per side, guarded by a "waiting" flag; the
// waker bumps the counter before notify, so a wake-up between the check and the wait is not
// lost. The full fences of the Dekker handshake (store own flag, fence, load the other side's
// state: at least one side sees the other) are paid only on the way to sleep and with the last
// item, not per block: per block and per cycle each side only reads the other's flag. A
// wake-up missed by such a read is made up by the next one, by the sleeping path (each side,
// before it sleeps, also wakes the other: the ring it sleeps on is empty or full) or by the
// fenced last item, so neither side can sleep while the other waits on it.
class ThreadedSource {
 public:
  ThreadedSource(BlockProducer& producer, std::size_t ring_blocks, int cpu)
      : producer_(producer),
        ring_(ring_blocks),
        wake_batch_(std::min<std::size_t>(kWakeBatch, ring_blocks / 2)) {
    thread_ = std::thread([this] { run(); });
#if defined(__linux__)
    if (cpu >= 0) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(static_cast<unsigned>(cpu), &set);
      pthread_setaffinity_np(thread_.native_handle(), sizeof set, &set);
    }
#else
    (void)cpu;
#endif
  }
  ThreadedSource(const ThreadedSource&) = delete;
  ThreadedSource& operator=(const ThreadedSource&) = delete;
  // Stops the producer wherever it is (an observer may throw mid-run) and joins it.
  ~ThreadedSource() {
    stop_.store(true, std::memory_order_seq_cst);
    producer_wake_.fetch_add(1, std::memory_order_seq_cst);
    producer_wake_.notify_one();
    thread_.join();
  }

  const Item& front() {
    Item* item = ring_.front();
    if (item == nullptr) item = wait_front();
    // The next block, if already queued, comes over from the producer's core while the kernel
    // takes this one.
    ring_.prefetch_next();
    return *item;
  }
  void pop() {
    ring_.pop();
    popped_ = true;
  }
  // Once per cycle in which blocks were taken: wake the producer if it sleeps and the ring
  // has drained to half.
  void cycle_done() {
    if (!popped_) return;
    popped_ = false;
    wake_producer_if_drained();
  }
  std::exception_ptr error() const {
    return error_;
  }
  // After the end item: the producer has finished counting.
  void finish(RunCounts& counts) const {
    counts.blocks = producer_.motion_blocks();
    counts.producer_waits = waits_;
    counts.producer_wait_s = wait_s_;
  }

 private:
  void wake_producer_if_drained() {
    if (producer_waiting_.load(std::memory_order_relaxed) && ring_.size() <= ring_.capacity() / 2) {
      producer_waiting_.store(false, std::memory_order_relaxed);
      producer_wake_.fetch_add(1, std::memory_order_release);
      producer_wake_.notify_one();
    }
  }

  // Items the producer queues before it wakes a sleeping cycle (unless the program ended;
  // at most half the ring, which the producer always fills before it sleeps itself).
  static constexpr std::size_t kWakeBatch = 64;
  static constexpr int kSpins = 200;

  Item* wait_front() {
    // The cycle may take a whole ring's worth of blocks without finishing a cycle (a kernel
    // buffer larger than the ring): the producer may be asleep on a ring that is now empty.
    wake_producer_if_drained();
    // Timed only here, off the fast path (a clock read costs ~25 ns).
    ++waits_;
    struct AddTime {
      double& sum;
      std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
      ~AddTime() {
        sum += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      }
    } add_time{wait_s_};
    for (int i = 0; i < kSpins; ++i) {
      cpu_relax();
      if (Item* item = ring_.front()) return item;
    }
    while (true) {
      const std::uint32_t wake = consumer_wake_.load(std::memory_order_acquire);
      consumer_waiting_.store(true, std::memory_order_relaxed);
      store_load_barrier(sync_);
      if (Item* item = ring_.front()) {
        consumer_waiting_.store(false, std::memory_order_relaxed);
        return item;
      }
      wake_producer_if_drained();
      consumer_wake_.wait(wake, std::memory_order_acquire);
    }
  }

  void run() {
    Item item;
    bool last = false;
    while (!last && !stop_.load(std::memory_order_relaxed)) {
      try {
        producer_.next(item);
        if (item.kind == ItemKind::kInputError) error_ = producer_.error();
      } catch (...) {
        error_ = std::current_exception();
        item.kind = ItemKind::kFatal;
      }
      last = item.kind != ItemKind::kBlock;
      while (!ring_.try_push(item)) {
        if (!wait_for_space()) return;
      }
      if (last) store_load_barrier(sync_);
      if (consumer_waiting_.load(std::memory_order_relaxed) &&
          (last || ring_.size() >= wake_batch_)) {
        wake_consumer();
      }
    }
  }

  void wake_consumer() {
    consumer_waiting_.store(false, std::memory_order_relaxed);
    consumer_wake_.fetch_add(1, std::memory_order_release);
    consumer_wake_.notify_one();
  }

  // The ring is full: sleep until it has drained to half. false: the run is being stopped.
  bool wait_for_space() {
    while (true) {
      const std::uint32_t wake = producer_wake_.load(std::memory_order_acquire);
      producer_waiting_.store(true, std::memory_order_relaxed);
      store_load_barrier(sync_);
      if (stop_.load(std::memory_order_relaxed)) return false;
      if (ring_.size() <= ring_.capacity() / 2) {
        producer_waiting_.store(false, std::memory_order_relaxed);
        return true;
      }
      if (consumer_waiting_.load(std::memory_order_relaxed)) wake_consumer();
      producer_wake_.wait(wake, std::memory_order_acquire);
    }
  }

  BlockProducer& producer_;
  SpscRing<Item> ring_;
  const std::size_t wake_batch_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint32_t> sync_{0};  // store_load_barrier under ThreadSanitizer only
  // Producer side sleeps on producer_wake_, the cycle on consumer_wake_ (separate lines).
  alignas(64) std::atomic<bool> producer_waiting_{false};
  std::atomic<std::uint32_t> producer_wake_{0};
  alignas(64) std::atomic<bool> consumer_waiting_{false};
  std::atomic<std::uint32_t> consumer_wake_{0};
  alignas(64) bool popped_ = false;  // consumer's
  std::uint64_t waits_ = 0;          // consumer's
  double wait_s_ = 0;                // consumer's
  std::exception_ptr error_;         // written by the producer before it queues the error item
  std::thread thread_;               // last: started once everything above is constructed
};

// Samples handed to the observers at once (see run_cycles): 32 × 184 bytes, in L1.
constexpr std::size_t kSampleBatch = 32;

// The motion cycle: takes blocks from `source` whenever the kernel has room, steps the kernel,
// hands samples to the observers. The same code for both sources, so both paths make exactly
// the same kernel calls in the same order.
// Size: the motion cycle's driving loop: block intake, the stall watchdog, batching and error
// delivery share the loop's state and their order is the contract documented above.
template <typename Source>
RunCounts run_cycles(Source& source, const std::string& program_path, const MachineConfig& machine,
                     const RunOptions& options, const std::vector<SampleObserver*>& observers) {
  motion::Kernel kernel(machine, options.kernel);
  RunCounts counts;
  std::array<motion::Sample, kSampleBatch> batch;
  std::array<double, kSampleBatch> batch_override{};
  std::size_t next_step = 0;  // next override step to apply (steps sorted by time)
  std::vector<std::pair<double, double>> steps = options.override_steps;
  std::stable_sort(steps.begin(), steps.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });

  // Stall watchdog: a kernel that stops moving for good (a bug) would hang the run forever.
  // Standing still is legitimate during a dwell and while the override is 0, so the limit is
  // the longest dwell seen so far plus 60 s of simulated time.
  double override_now = options.kernel.override_pct;
  double override_set = override_now;  // what the kernel runs (the cycle controller's output)
  double longest_dwell_s = 0;
  std::uint64_t still_cycles = 0;
  AxisVec last_position;
  // Hands samples [0, n) of the batch to the observers, each observer all of them in one call.
  auto deliver = [&](std::size_t n) {
    if (n == 0) return;
    counts.cycles += n;
    for (SampleObserver* o : observers)
      o->on_samples(std::span<const motion::Sample>(batch.data(), n));
  };
  // The watchdog over the batch (override: the operator's override in force when each sample's
  // cycle ran); a stall is thrown after the samples before it are delivered.
  auto watch = [&](std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      const motion::Sample& s = batch[i];
      if (counts.cycles + i > 0 && s.position == last_position && batch_override[i] > 0) {
        if (++still_cycles * machine.period_s > longest_dwell_s + 60) {
          deliver(i);
          if (options.cycle_controller != nullptr && override_set <= 0) {
            // Not a kernel fault: the controller holds the feed at 0 and its load never falls
            // (a recorded load does not follow the feed).
            throw InputError(program_path, s.line, 1,
                             "adaptive feed control has held the feed override at 0 % for 60 s: "
                             "the measured load never fell below adaptive.threshold_pct (a "
                             "recorded load does not follow the feed); set adaptive.lower_pct "
                             "above 0, or an antiwindup policy other than \"none\"");
          }
          throw std::runtime_error("motion kernel stalled: no motion for " +
                                   std::to_string(still_cycles) + " cycles at line " +
                                   std::to_string(s.line) + ", t = " + std::to_string(s.t_s) +
                                   " s");
        }
      } else {
        still_cycles = 0;
      }
      last_position = s.position;
    }
  };
  // One interpolation period. The k-th sample (k = 0, 1, ...) has t = k·τ; an override step at
  // time T is set before the first cycle with t >= T, since set_override acts on the next cycle.
  // Samples of consecutive cycles are handed to the observers in batches (the kernel's
  // cycles in one tight loop, then the observers', overlap better on the CPU than one cycle of
  // each in turn). Each observer sees exactly the same samples and blocks in the same order: a
  // batch is delivered (to each observer in one on_samples call, one observer after the other)
  // before any on_block (a block is pushed between two cycles), at the end and before an error
  // goes on. A cycle controller needs each sample at once: no batching then.
  const std::size_t batch_max = options.cycle_controller != nullptr ? 1 : kSampleBatch;
  std::size_t batched = 0;
  auto flush = [&]() {
    watch(batched);
    deliver(batched);
    batched = 0;
  };
  std::uint64_t stepped = 0;  // cycles the kernel has run (counts.cycles: delivered)
  auto step = [&]() -> bool {
    const double t_next = static_cast<double>(stepped) * machine.period_s;
    while (next_step < steps.size() && t_next >= steps[next_step].first - 1e-9) {
      if (options.cycle_controller == nullptr) kernel.set_override(steps[next_step].second);
      override_now = steps[next_step].second;
      ++next_step;
    }
    motion::Sample& sample = batch[batched];
    if (!kernel.step(sample)) return false;
    ++stepped;
    batch_override[batched] = override_now;
    if (options.cycle_controller != nullptr) {
      override_set = options.cycle_controller->on_cycle(sample, override_now);
      kernel.set_override(override_set);
    }
    if (++batched == batch_max) flush();
    return true;
  };

  bool ended = false;  // the source has delivered the end of the program
  while (true) {
    // Take blocks only while the execution-data buffer has room, so memory stays bounded by the
    // buffer whatever the program length. When the source has nothing ready yet, front()
    // waits: the cycle must not run ahead of a block that is merely late.
    while (kernel.wants_block()) {
      if (ended) {
        kernel.end_of_program();
        break;
      }
      // Every sample so far reaches the observers before the next block or an error (front()
      // itself may throw).
      flush();
      const Item& item = source.front();
      if (item.kind == ItemKind::kBlock) {
        // The direction correction passes a dwell on unchanged, in the same call that read it
        // from the interpreter: the watchdog sees it before any further cycle, as before.
        if (item.block.kind == BlockKind::kDwell) {
          longest_dwell_s = std::max(longest_dwell_s, item.block.dwell_s);
        }
        for (SampleObserver* o : observers) o->on_block(item.block);
        kernel.push(item.block);
        source.pop();
        continue;
      }
      const ItemKind kind = item.kind;
      source.pop();
      if (kind == ItemKind::kFatal) std::rethrow_exception(source.error());
      kernel.end_of_program();
      if (kind == ItemKind::kInputError) {
        // Stop at the end of the last good block: the samples up to there are delivered, then
        // the error goes on to the caller (which discards its output files).
        while (step()) {
        }
        flush();
        std::rethrow_exception(source.error());
      }
      ended = true;
      break;
    }
    source.cycle_done();
    if (!step()) {
      flush();
      if (!ended) {
        // The kernel contract: step() returns false only after end_of_program().
        throw std::logic_error("motion kernel stopped before the end of the program");
      }
      break;
    }
  }
  source.finish(counts);
  for (SampleObserver* o : observers) o->on_finish();
  return counts;
}

}  // namespace

bool default_producer_thread() {
  static const bool value = [] {
    const char* v = std::getenv("CNCORE_PRODUCER_THREAD");
    return v != nullptr && std::string(v) == "1";
  }();
  return value;
}

RunCounts run_program(const std::string& program_path, const MachineConfig& machine,
                      const RunOptions& options, const std::vector<SampleObserver*>& observers) {
  // Constructed here, on the calling thread: a missing file throws before anything runs.
  BlockProducer producer(program_path, machine, options.interpreter, options.kernel,
                         options.operator_modes);
  if (!options.producer_thread) {
    InlineSource source(producer);
    return run_cycles(source, program_path, machine, options, observers);
  }
  ThreadedSource source(producer, options.ring_blocks, options.producer_cpu);
  return run_cycles(source, program_path, machine, options, observers);
}

}  // namespace cncore::sim
