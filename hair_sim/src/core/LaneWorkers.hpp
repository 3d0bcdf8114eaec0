#pragma once
/// Internal to the core: the helper threads of Simulator::setThreads (and HairMeshBuilder::setThreads, which
/// hands them blocks of strips). A substep of the Lanes path hands one the sweep of the second group of
/// strips (Simulator::stepLanes: the two groups share no spring pair and no block of chains, so they are
/// swept at once), with the runs of blocks of chains (lanes::stepBlock, which reads only the block's own
/// chains at the start of the substep and writes only their new state) shared between the two sweeps. Which
/// thread computes a block does not change its result, and the sweep order does not depend on the threads, so
/// the hair is the same bit for bit with any number of threads.
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

  /// The runs of blocks of two groups swept at once (Simulator::stepLanes): each group's own sweep claims its
  /// runs from the front as it reads its strips; the other sweep claims some from the back as it goes (the
  /// lend, Balance below) and, once done with its own group, the rest. Which thread computes a run does not
  /// change its result. startRuns resets the claims for a substep with runs[g] runs in group g (before
  /// start()).
  void startRuns(std::size_t runs0, std::size_t runs1);
  /// Claims the next unclaimed run of group g from its front (or back); false when none is left.
  bool claimRun(int g, bool from_back, std::size_t& run);
  /// Marks run `run` of group g computed (by the thread that claimed it).
  void markRunDone(int g, std::size_t run);
  /// Returns once run `run` of group g is computed (another thread claimed it).
  void waitRunDone(int g, std::size_t run);
  /// The balance of the two sweeps, learned from substep to substep (it decides only which thread computes
  /// which run, never a result): `lend` runs of group 1 are computed by group 0's sweep as it goes (spread
  /// over its strips), or for lend < 0, -lend runs of group 0 by group 1's sweep. After each substep
  /// settle() moves it by half the runs that would have evened the two sweeps' ends.
  struct Balance {
    int lend = 0;
    double run_seconds = 0.0;  ///< a run's time, as last measured
  };
  Balance balance;
  /// The balance's update from the two sweeps' ends (seconds; each sweep's own strips and the runs it lent)
  /// and the time of the runs computed for the other group (`lent` of them).
  void settle(double end0, double end1, double lent_seconds, int lent, int runs0, int runs1);

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
  struct RunGroup {
    std::size_t front = 0, back = 0;            // the unclaimed runs [front, back), guarded by mutex_
    std::unique_ptr<std::atomic<long>[]> done;  ///< per run: the run generation in which it was computed
    std::size_t done_size = 0;
  };
  RunGroup run_groups_[2];
  long run_generation_ = 0;  ///< startRuns calls (written before start(), read after its release)
};

}  // namespace hair_sim
