#pragma once
/// Internal to the core: the helper threads of Simulator::setThreads. Each substep hands them parts of the
/// spring pairs to scan (computeSpringForces, each part into its own outputs) and, on the Lanes path, its
/// blocks of chains (lanes::stepBlock, which reads only the block's own chains at the start of
/// the substep and writes only their new state); the calling thread commits the strips in order as their
/// blocks complete and computes blocks itself while it waits. Which thread computes a block does not change
/// its result, so the hair is the same bit for bit with any number of threads.
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace hair_sim {

class LaneWorkers {
 public:
  /// Starts `helpers` threads that wait for work.
  explicit LaneWorkers(int helpers);
  /// Stops and joins the threads (after the current substep's blocks).
  ~LaneWorkers();
  LaneWorkers(const LaneWorkers&) = delete;
  LaneWorkers& operator=(const LaneWorkers&) = delete;

  int helpers() const { return static_cast<int>(threads_.size()); }

  /// Starts a substep of `blocks` blocks: run(context, block) computes one, on any thread (a plain function
  /// and its context: nothing is allocated per substep). `context` must stay valid until finish().
  void start(std::size_t blocks, void (*run)(void* context, std::size_t block), void* context);
  /// Returns once block b is computed, computing unclaimed blocks on the calling thread meanwhile.
  void waitFor(std::size_t b);
  /// Returns once every block is computed and every helper is idle again.
  void finish();

 private:
  void loop();
  /// Claims and computes the next block; false when none is left.
  bool runOne();

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool quit_ = false;
  long generation_ = 0;                     ///< substeps started (guarded by mutex_ for the helpers' wake-up)
  std::atomic<long> active_generation_{0};  ///< the substep whose blocks are handed out
  void (*run_)(void*, std::size_t) = nullptr;
  void* context_ = nullptr;
  std::size_t blocks_ = 0;
  std::atomic<std::size_t> next_{0};
  std::unique_ptr<std::atomic<long>[]> done_;  ///< per block: the generation in which it was computed
  std::size_t done_size_ = 0;
  std::atomic<int> busy_{0};  ///< helpers inside the current substep
};

}  // namespace hair_sim
